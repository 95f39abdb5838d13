#include "server/services/ingest_stream.h"

#include <grpcpp/alarm.h>

#include <chrono>
#include <functional>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/time/clock.h"
#include "server/convert/ingest_convert.h"
#include "server/rpc/map_lookup.h"
#include "server/rpc/map_name.h"
#include "server/rpc/status_convert.h"

namespace fremen::server {

namespace {

constexpr MethodSpec kIngest{"Ingest", Access::kWrite, /*blocking=*/false};

// Runs `f` on a gRPC thread after `delay`. The alarm frees itself once it has fired (gRPC keeps
// the callback alive until it returns).
void RunAfter(absl::Duration delay, std::function<void()> f) {
  auto* alarm = new grpc::Alarm;
  alarm->Set(std::chrono::system_clock::now() + absl::ToChronoNanoseconds(delay),
             [alarm, f = std::move(f)](bool /*fired*/) {
               delete alarm;
               f();
             });
}

// Submit's refusals that concern the batch alone; any other ends the stream.
bool IsBatchError(const absl::Status& status) {
  return status.code() == absl::StatusCode::kInvalidArgument || status.code() == absl::StatusCode::kOutOfRange;
}

}  // namespace

IngestStream::IngestStream(const ServiceDeps& deps, grpc::CallbackServerContext* context)
    : deps_(deps), context_(context), record_(kIngest.name, *context, deps.observer) {}

IngestStream* IngestStream::Start(const ServiceDeps& deps, grpc::CallbackServerContext* context) {
  std::shared_ptr<IngestStream> stream(new IngestStream(deps, context));
  stream->self_ = stream;
  base::MutexLock lock(&stream->mutex_);
  auto id = deps.calls->BeginStream(stream);
  if (!id.ok()) {
    stream->EndLocked(id.status());
  } else {
    stream->tracker_id_ = *id;
    if (absl::Status denied = deps.auth->Authorize(*context, kIngest.access, kIngest.name); !denied.ok()) {
      stream->EndLocked(denied);
    }
  }
  stream->PumpLocked();
  return stream.get();
}

void IngestStream::OnReadDone(bool ok) {
  {
    base::MutexLock lock(&mutex_);
    reading_ = false;
    // The client closed its side: answer what is in flight, then end with OK. Or the call failed
    // (cancelled, a message over the size limit): gRPC has ended it already.
    if (!ok && context_->IsCancelled()) cancelled_ = true;
    if (!ok) EndLocked(absl::OkStatus());
    // A batch read while winding down is dropped unanswered: the client resends it.
    if (!ok || EndingLocked()) return PumpLocked();
    // From here until the store has it, request_ is the stream's: no read may overwrite it.
    holding_ = true;
  }
  // An unparsable message ends the stream: the batches after it cannot be trusted to be what the
  // client sent either. Then the map is routed.
  const size_t bytes = message_.Length();  // before Parse consumes it
  absl::Status routed = Parse();
  if (routed.ok()) routed = Route();
  if (routed.ok() && deps_.observer != nullptr) deps_.observer->IngestReceived(map_name_, bytes);
  if (!routed.ok()) {
    base::MutexLock lock(&mutex_);
    holding_ = false;
    EndLocked(routed);
    return PumpLocked();
  }
  {
    base::MutexLock lock(&mutex_);
    held_slot_ = &slots_.emplace_back();
  }
  SubmitHeld();
  base::MutexLock lock(&mutex_);
  PumpLocked();
}

absl::Status IngestStream::Parse() {
  ++messages_;
  const grpc::Status parsed = grpc::SerializationTraits<v1::IngestRequest>::Deserialize(&message_, &request_);
  if (parsed.ok()) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrCat("message ", messages_, " of the stream: cannot parse ",
                                                 v1::IngestRequest::descriptor()->name(),
                                                 " (the batches before it are answered; it and the ones after "
                                                 "are not applied)"));
}

absl::Status IngestStream::Route() {
  if (map_ == nullptr) {
    auto map = LookUpMap(*deps_.store, *context_, request_.map());
    if (!map.ok()) return map.status();
    map_ = *std::move(map);
    map_name_ = map_->info().name;
    return absl::OkStatus();
  }
  auto name = ResolveMapName(*context_, request_.map(), "map");
  if (!name.ok()) return name.status();
  if (*name != map_name_) {
    return absl::InvalidArgumentError(absl::StrCat("map is \"", *name, "\" but this stream ingests into \"", map_name_,
                                                   "\"; open one stream per map"));
  }
  return absl::OkStatus();
}

void IngestStream::SubmitHeld() {
  Slot* const slot = held_slot_;
  auto batch = BatchFromRequest(map_->info(), request_);
  absl::Status status = batch.status();
  const uint64_t observations = batch.ok() ? batch->observation_count() : 0;
  if (batch.ok()) {
    status = map_->Submit(*std::move(batch), [self = shared_from_this(), slot](absl::StatusOr<storage::BatchAck> ack) {
      self->OnAck(*slot, std::move(ack));
    });
  }
  base::ReleasableMutexLock lock(&mutex_);
  if (status.ok()) {
    holding_ = false;
  } else if (storage::IsQueueFull(status) && !EndingLocked()) {
    waiting_room_ = true;
    waiting_since_ = absl::Now();
    lock.Release();
    WaitForRoom(observations);
  } else if (IsBatchError(status)) {
    ErrorToResponse(request_.sequence(), status, slot->response);
    slot->ready = true;
    holding_ = false;
  } else {
    // The store refuses writes (closing, or a failed log), or the stream is winding down: the batch
    // stays unanswered, for the client to resend elsewhere or later.
    slots_.pop_back();
    holding_ = false;
    EndLocked(status);
  }
}

void IngestStream::WaitForRoom(uint64_t observations) {
  // OnRoom applies Submit's own rule, so it calls back when this batch fits (at once if the queue
  // drained meanwhile). Another stream may still take the room first; then Submit refuses again
  // and this waits again — on the store's next group, never by polling.
  map_->OnRoom(observations, [self = shared_from_this()] {
    // Off the store's thread: converting and preparing a batch is the stream's work.
    RunAfter(absl::ZeroDuration(), [self] { self->RoomAvailable(); });
  });
}

void IngestStream::RoomAvailable() {
  {
    base::MutexLock lock(&mutex_);
    if (!waiting_room_) return;  // dropped by WindDown
    waiting_room_ = false;
    if (deps_.observer != nullptr) deps_.observer->IngestWaited(map_name_, absl::Now() - waiting_since_);
    if (EndingLocked()) {
      slots_.pop_back();
      holding_ = false;
      return PumpLocked();
    }
  }
  SubmitHeld();
  base::MutexLock lock(&mutex_);
  PumpLocked();
}

void IngestStream::OnAck(Slot& slot, absl::StatusOr<storage::BatchAck> ack) {
  base::MutexLock lock(&mutex_);
  if (ack.ok()) {
    AckToResponse(*ack, slot.response);
    slot.ready = true;
    accepted_ += ack->accepted;
    rejected_ += ack->rejected;
  } else {
    // Not durable, and the store now refuses writes: end the stream once the earlier batches are
    // answered; the client resends this one and the later ones elsewhere or later.
    slot.failed = true;
    slot.failure = ack.status();
    EndLocked(ack.status());
  }
  PumpLocked();
}

void IngestStream::OnWriteDone(bool ok) {
  base::MutexLock lock(&mutex_);
  writing_ = false;
  if (ok) {
    slots_.pop_front();
    ++answered_;
  } else {
    cancelled_ = true;  // the client is gone
  }
  PumpLocked();
}

void IngestStream::OnCancel() {
  base::MutexLock lock(&mutex_);
  cancelled_ = true;
  PumpLocked();
}

void IngestStream::WindDown() {
  base::MutexLock lock(&mutex_);
  EndLocked(absl::UnavailableError(
      "fremend is shutting down; reconnect and resend the batches not acknowledged (repeats are recognised)"));
  if (waiting_room_) {
    waiting_room_ = false;
    holding_ = false;
    slots_.pop_back();
  }
  PumpLocked();
}

void IngestStream::OnDone() {
  if (tracker_id_) deps_.calls->EndStream(*tracker_id_);
  std::shared_ptr<IngestStream> self;
  {
    base::MutexLock lock(&mutex_);
    self.swap(self_);
  }
  // `self` may be the last owner: the stream is freed here unless the store still holds it.
}

void IngestStream::EndLocked(absl::Status status) {
  if (!end_status_) end_status_ = std::move(status);
}

void IngestStream::PumpLocked() {
  if (finished_) return;
  if (!writing_ && !cancelled_ && !slots_.empty() && slots_.front().ready) {
    writing_ = true;
    Slot& front = slots_.front();
    bool own_buffer = false;
    const grpc::Status serialized =
        grpc::SerializationTraits<v1::IngestResponse>::Serialize(front.response, &front.bytes, &own_buffer);
    if (!serialized.ok()) return FinishLocked(absl::InternalError(std::string(serialized.error_message())));
    StartWrite(&front.bytes);
  }
  if (!writing_) {
    if (cancelled_) return FinishLocked(absl::CancelledError("the client cancelled the stream"));
    if (!slots_.empty() && slots_.front().failed) return FinishLocked(slots_.front().failure);
    if (end_status_ && slots_.empty() && !holding_) return FinishLocked(*end_status_);
  }
  if (!reading_ && !holding_ && !EndingLocked() && slots_.size() < kMaxUnanswered) {
    reading_ = true;
    StartRead(&message_);
  }
}

void IngestStream::FinishLocked(const absl::Status& status) {
  finished_ = true;
  const grpc::Status converted = ToGrpcStatus(status);
  record_.Finish(converted,
                 absl::StrCat("batches=", answered_, " observations=", accepted_, " rejected=", rejected_));
  Finish(converted);
}

}  // namespace fremen::server
