#include "client/lib/ingest_session.h"

#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "client/lib/backoff.h"
#include "client/lib/status.h"

namespace fremen::client {

namespace {

// How long the reader waits for a writer to notice a broken stream before cancelling the call to
// unblock it (a write blocked in flow control on a dead link).
constexpr absl::Duration kWriterGrace = absl::Seconds(1);

}  // namespace

absl::StatusOr<std::unique_ptr<IngestSession>> IngestSession::Open(std::shared_ptr<Connection> connection,
                                                                   std::string map, IngestOptions options) {
  if (map.empty()) return absl::InvalidArgumentError("map is empty: name the map to ingest into");
  if (options.max_unacknowledged == 0) return absl::InvalidArgumentError("max_unacknowledged must be at least 1");
  // Fail now on an unknown map or a refused token, rather than at the first ack.
  v1::GetMapRequest request;
  request.set_map(map);
  v1::GetMapResponse response;
  absl::Status exists = connection->CallIdempotent(
      {}, map, [&](grpc::ClientContext& context) { return connection->maps().GetMap(&context, request, &response); });
  if (!exists.ok()) return exists;
  uint64_t writer = options.writer_id;
  while (writer == 0) writer = RandomSeed();
  uint64_t first = options.first_sequence;
  if (first == 0 && options.writer_id != 0) {
    // A writer that may have sent before (and may have lost its count): continue after the map's
    // last batch of it. A read, so retried like one.
    v1::LastSequenceRequest last_request;
    last_request.set_map(map);
    last_request.set_writer_id(writer);
    v1::LastSequenceResponse last;
    absl::Status asked = connection->CallIdempotent({}, map, [&](grpc::ClientContext& context) {
      return connection->ingest().LastSequence(&context, last_request, &last);
    });
    if (!asked.ok()) return asked;
    first = last.last_sequence() + 1;
  }
  if (first == 0) first = 1;
  std::unique_ptr<IngestSession> session(
      new IngestSession(std::move(connection), std::move(map), std::move(options), writer, first));
  session->thread_ = std::thread([s = session.get()] { s->Run(); });
  return session;
}

IngestSession::IngestSession(std::shared_ptr<Connection> connection, std::string map, IngestOptions options,
                             uint64_t writer_id, uint64_t first_sequence)
    : connection_(std::move(connection)),
      map_(std::move(map)),
      options_(std::move(options)),
      writer_id_(writer_id),
      first_sequence_(first_sequence),
      next_sequence_(first_sequence) {}

IngestSession::~IngestSession() {
  {
    base::MutexLock lock(&mutex_);
    stopping_ = true;
    if (stream_ != nullptr) stream_->context->TryCancel();
    changed_.SignalAll();
  }
  if (thread_.joinable()) thread_.join();
}

absl::StatusOr<uint64_t> IngestSession::Send(Scan scan) {
  auto request = std::make_shared<v1::IngestRequest>(std::move(scan.request));
  request->set_map(map_);
  request->set_writer_id(writer_id_);
  uint64_t sequence;
  {
    base::MutexLock lock(&mutex_);
    while (error_.ok() && !closing_ && !stopping_ && pending_.size() >= options_.max_unacknowledged) {
      changed_.Wait(&mutex_);
    }
    if (!error_.ok()) return error_;
    if (closing_ || stopping_) return absl::FailedPreconditionError("the ingest session is closed: open a new one");
    sequence = next_sequence_++;
    request->set_sequence(sequence);
    pending_.push_back({sequence, std::move(request)});
    ++totals_.sent;
    changed_.SignalAll();  // the first batch makes the session's thread open the stream
  }
  base::TimedMutexLock write_lock(&write_mutex_);
  WriteUnsentLocked();
  return sequence;
}

absl::Status IngestSession::Flush(absl::Duration timeout) {
  const absl::Time deadline = absl::Now() + timeout;  // InfiniteFuture for InfiniteDuration: no limit
  base::MutexLock lock(&mutex_);
  while (!pending_.empty() && error_.ok() && !stopping_) {
    if (changed_.WaitWithDeadline(&mutex_, deadline)) break;  // timed out
  }
  if (!error_.ok()) return error_;
  if (!pending_.empty()) {
    return absl::DeadlineExceededError(absl::StrCat(pending_.size(), " batches of map \"", map_,
                                                    "\" not acknowledged after ", absl::FormatDuration(timeout),
                                                    " (is fremend at ", connection_->address(), " up?)"));
  }
  return absl::OkStatus();
}

absl::Status IngestSession::Close(absl::Duration timeout) {
  absl::Status flushed = Flush(timeout);
  {
    base::MutexLock lock(&mutex_);
    closing_ = true;
    changed_.SignalAll();
  }
  {
    // Ends our side of the stream; the daemon then ends the call with OK and the thread leaves.
    base::TimedMutexLock write_lock(&write_mutex_);
    if (stream_ != nullptr && flushed.ok()) stream_->rw->WritesDone();
  }
  if (!flushed.ok()) {
    base::MutexLock lock(&mutex_);
    stopping_ = true;
    if (stream_ != nullptr) stream_->context->TryCancel();
    changed_.SignalAll();
  }
  if (thread_.joinable()) thread_.join();
  base::MutexLock lock(&mutex_);
  return flushed.ok() ? error_ : flushed;
}

std::vector<IngestAck> IngestSession::TakeAcks() {
  base::MutexLock lock(&mutex_);
  return std::exchange(acks_, {});
}

IngestTotals IngestSession::totals() const {
  base::MutexLock lock(&mutex_);
  return totals_;
}

size_t IngestSession::unacknowledged() const {
  base::MutexLock lock(&mutex_);
  return pending_.size();
}

std::shared_ptr<IngestSession::Stream> IngestSession::OpenStreamLocked() {
  auto stream = std::make_shared<Stream>();
  // No deadline: the stream lives as long as the session; keepalive notices a dead link.
  stream->context = connection_->NewContext(absl::InfiniteFuture(), map_);
  {
    base::MutexLock lock(&mutex_);
    if (stopping_) return nullptr;
    if (generation_ > 0) ++totals_.reconnects;
    ++generation_;
  }
  stream->rw = connection_->ingest().Ingest(stream->context.get());
  {
    base::MutexLock lock(&mutex_);
    stream_ = stream;
    // The destructor may have come between the two locks: it found no stream to cancel.
    if (stopping_) stream->context->TryCancel();
  }
  WriteUnsentLocked();
  return stream;
}

void IngestSession::WriteUnsentLocked() {
  if (stream_ == nullptr) return;
  for (;;) {
    std::shared_ptr<const v1::IngestRequest> next;
    {
      base::MutexLock lock(&mutex_);
      for (Pending& pending : pending_) {
        if (pending.sent_on < generation_) {
          pending.sent_on = generation_;
          next = pending.request;
          break;
        }
      }
    }
    // A failed write means a broken stream: the reader reconnects and resends from the oldest.
    if (next == nullptr || !stream_->rw->Write(*next)) return;
  }
}

absl::Status IngestSession::MatchLocked(const v1::IngestResponse& response, IngestAck& ack) const {
  if (pending_.empty() || response.sequence() != pending_.front().sequence) {
    return absl::InternalError(absl::StrCat("fremend acknowledged batch ", response.sequence(), " while batch ",
                                            pending_.empty() ? 0 : pending_.front().sequence,
                                            " was the oldest unacknowledged one"));
  }
  ack.sequence = response.sequence();
  ack.accepted = response.accepted();
  ack.rejected = response.rejected();
  ack.duplicate = response.duplicate();
  for (const v1::Rejection& r : response.rejections()) ack.rejections.push_back({r.index(), r.reason()});
  if (response.has_error() && response.error().code() != 0) {
    ack.error = absl::Status(static_cast<absl::StatusCode>(response.error().code()), response.error().message());
  }
  return absl::OkStatus();
}

void IngestSession::RecordLocked(IngestAck ack) {
  pending_.pop_front();
  ++totals_.acknowledged;
  totals_.duplicates += ack.duplicate ? 1 : 0;
  totals_.refused += ack.error.ok() ? 0 : 1;
  totals_.accepted += ack.accepted;
  totals_.rejected += ack.rejected;
  if (options_.collect_acks) acks_.push_back(std::move(ack));
  changed_.SignalAll();
}

void IngestSession::FailLocked(absl::Status error) {
  if (error_.ok()) error_ = std::move(error);
  changed_.SignalAll();
}

void IngestSession::Run() {
  Backoff backoff(connection_->options().retry, RandomSeed());
  std::optional<absl::Time> failing_since;  // when the streams started failing, none working since
  for (;;) {
    {
      // Open a stream only when there is something to send.
      base::MutexLock lock(&mutex_);
      while (!stopping_ && error_.ok() && !closing_ && pending_.empty()) changed_.Wait(&mutex_);
      if (stopping_ || !error_.ok() || (closing_ && pending_.empty())) return;
    }
    std::shared_ptr<Stream> stream;
    {
      base::TimedMutexLock write_lock(&write_mutex_);
      stream = OpenStreamLocked();
    }
    if (stream == nullptr) return;

    v1::IngestResponse response;
    while (stream->rw->Read(&response)) {
      IngestAck ack;
      absl::Status matched;
      {
        base::MutexLock lock(&mutex_);
        matched = MatchLocked(response, ack);
        if (!matched.ok()) FailLocked(matched);
      }
      if (!matched.ok()) {
        stream->context->TryCancel();
        break;
      }
      failing_since.reset();
      backoff.Reset();
      // Before the batch leaves pending_, so that a Flush that returned saw every callback.
      if (options_.on_ack) options_.on_ack(ack);
      base::MutexLock lock(&mutex_);
      RecordLocked(std::move(ack));
    }

    // The stream has ended. Writes on it fail now; wait for a writer to return, then read the status.
    if (!write_mutex_.TryLockFor(absl::ToChronoNanoseconds(kWriterGrace))) {
      stream->context->TryCancel();
      write_mutex_.Lock();
    }
    const absl::Status status = FromGrpcStatus(stream->rw->Finish(), connection_->address());
    base::MutexLock lock(&mutex_);
    stream_.reset();
    write_mutex_.Unlock();
    if (stopping_ || !error_.ok()) return;
    if (status.ok() && pending_.empty()) {
      if (closing_) return;
      continue;  // the daemon ended an idle stream; open another with the next batch
    }
    // UNAVAILABLE: the daemon is restarting or out of reach. OK with batches unanswered: it ended
    // the stream early. Either way, resend them on a new stream.
    // A stream reset by a proxy whose upstream died (nginx on a kill -9 of the daemon: RST_STREAM
    // INTERNAL_ERROR, which gRPC reports as INTERNAL) is a daemon out of reach too: the batches are
    // idempotent by (writer, sequence), so resending them cannot apply one twice.
    const bool reset = status.code() == absl::StatusCode::kInternal && absl::StrContains(status.message(), "RST_STREAM");
    if (!status.ok() && !IsRetryable(status.code()) && !reset) return FailLocked(status);
    const absl::Time now = absl::Now();
    if (!failing_since) failing_since = now;
    if (now - *failing_since >= options_.reconnect_timeout || !backoff.MayRetry()) {
      return FailLocked(
          absl::UnavailableError(absl::StrCat("gave up reconnecting to fremend at ", connection_->address(), " after ",
                                              absl::FormatDuration(now - *failing_since), " with ", pending_.size(),
                                              " batches not acknowledged; last error: ", status.message())));
    }
    const absl::Duration delay = backoff.Next();
    const absl::Time retry_at = absl::Now() + delay;
    while (!stopping_) {
      if (changed_.WaitWithDeadline(&mutex_, retry_at)) break;  // timed out
    }
    if (stopping_) return;
  }
}

}  // namespace fremen::client
