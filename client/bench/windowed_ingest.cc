#include "client/bench/windowed_ingest.h"

#include <utility>

namespace fremen::bench {

WindowedIngest::WindowedIngest(v1::IngestService::Stub& stub, std::unique_ptr<grpc::ClientContext> context,
                               int window, NextBatch next, OnAck on_ack)
    : context_(std::move(context)), window_(window), next_(std::move(next)), on_ack_(std::move(on_ack)) {
  stub.async()->Ingest(context_.get(), this);
  StartRead(&ack_);
  {
    std::lock_guard lock(mutex_);
    PumpLocked();
  }
  StartCall();
}

WindowedIngest::~WindowedIngest() { Await(); }

void WindowedIngest::Stop() {
  std::lock_guard lock(mutex_);
  stopping_ = true;
  PumpLocked();
}

grpc::Status WindowedIngest::Await() {
  std::unique_lock lock(mutex_);
  done_changed_.wait(lock, [&] { return done_; });
  return status_;
}

bool WindowedIngest::Ended() {
  std::lock_guard lock(mutex_);
  return done_;
}

void WindowedIngest::PumpLocked() {
  // The reactions never run inline from StartWrite or StartWritesDone (gRPC's callback API), so
  // starting them under the mutex cannot deadlock.
  if (writing_ || writes_ended_) return;
  if (!stopping_ && unacknowledged_ < window_) {
    const v1::IngestRequest* batch = next_(sequence_);
    if (batch != nullptr) {
      ++sequence_;
      ++unacknowledged_;
      writing_ = true;
      StartWrite(batch);
      return;
    }
    stopping_ = true;
  }
  if (stopping_) {
    writes_ended_ = true;
    StartWritesDone();
  }
}

void WindowedIngest::OnWriteDone(bool ok) {
  std::lock_guard lock(mutex_);
  writing_ = false;
  // A failed write: the call is over, and OnDone brings its status.
  if (!ok) writes_ended_ = true;
  PumpLocked();
}

void WindowedIngest::OnReadDone(bool ok) {
  if (!ok) return;  // the daemon ended the stream: OnDone follows
  on_ack_(ack_);
  {
    std::lock_guard lock(mutex_);
    --unacknowledged_;
    PumpLocked();
  }
  StartRead(&ack_);
}

void WindowedIngest::OnDone(const grpc::Status& status) {
  std::lock_guard lock(mutex_);
  status_ = status;
  done_ = true;
  done_changed_.notify_all();
}

}  // namespace fremen::bench
