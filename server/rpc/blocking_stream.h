// Streaming calls whose body is a plain loop on the blocking pool — ExportMap writes a map's files,
// ImportMap reads them — rather than a state machine of reactions: the body calls Write or Read,
// which starts the operation and waits (on the pool thread, never on a gRPC thread) for its
// completion. As ServeUnary does for unary calls, the call is counted in the CallTracker, its token
// checked, the body's status converted once and written to the access log.
//
//   return ServeServerStream<v1::MapChunk>(deps_, context, kExportMap,
//       [=](StreamWriter<v1::MapChunk>& out) -> absl::Status { ... out.Write(chunk) ... });
//
// Thread-safety: the body runs on one pool thread; gRPC's reactions only hand it completions
// through a mutex. Finish is called once, after the body has returned and no operation is in
// flight, so nothing touches the reactor after OnDone deletes it.
#pragma once

#include <grpcpp/server_context.h>
#include <grpcpp/support/server_callback.h>

#include <functional>
#include <utility>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "base/mutex.h"
#include "server/rpc/unary_call.h"

namespace fremen::server {

// One operation at a time in flight, waited for by the body's thread.
class StreamCompletion {
 public:
  void Start() ABSL_LOCKS_EXCLUDED(mutex_) {
    base::MutexLock lock(&mutex_);
    pending_ = true;
  }
  void Done(bool ok) ABSL_LOCKS_EXCLUDED(mutex_) {
    base::MutexLock lock(&mutex_);
    pending_ = false;
    ok_ = ok;
    changed_.SignalAll();
  }
  bool Wait() ABSL_LOCKS_EXCLUDED(mutex_) {
    base::MutexLock lock(&mutex_);
    while (pending_) changed_.Wait(&mutex_);
    return ok_;
  }

 private:
  base::Mutex mutex_;
  base::CondVar changed_;
  bool pending_ ABSL_GUARDED_BY(mutex_) = false;
  bool ok_ ABSL_GUARDED_BY(mutex_) = true;
};

template <typename Response>
class StreamWriter {
 public:
  virtual ~StreamWriter() = default;
  // Sends one message and waits until gRPC has taken it; false when the client has gone.
  virtual bool Write(const Response& message) = 0;
};

template <typename Request>
class StreamReader {
 public:
  virtual ~StreamReader() = default;
  // The next message; false at the end of the client's stream (or when the call failed).
  virtual bool Read(Request& message) = 0;
};

namespace internal {

// Posts `body` to the pool after the tracker and the token let the call in; `finish` ends it.
template <typename Body, typename Finish>
void StartBlockingStream(const ServiceDeps& deps, grpc::CallbackServerContext* context, const MethodSpec& method,
                         Body body, Finish finish) {
  if (absl::Status refused = deps.calls->Begin(); !refused.ok()) return finish(refused, /*counted=*/false);
  if (absl::Status denied = deps.auth->Authorize(*context, method.access, method.name); !denied.ok()) {
    return finish(denied, true);
  }
  const bool queued = deps.blocking->Post([body = std::move(body), finish, context]() mutable {
    if (context->IsCancelled()) return finish(absl::CancelledError("cancelled or past its deadline before it started"), true);
    finish(body(), true);
  });
  if (!queued) {
    finish(absl::ResourceExhaustedError(
               absl::StrCat("fremend is busy (too many calls waiting on disk); retry ", method.name, " later")),
           true);
  }
}

// What both kinds of reactor share: the access log's record, the tracker, the one Finish.
template <typename Reactor>
class BlockingReactor : public Reactor {
 public:
  BlockingReactor(grpc::CallbackServerContext* context, const MethodSpec& method, const ServiceDeps& deps)
      : record_(method.name, *context, deps.observer), calls_(deps.calls) {}

  void OnDone() override { delete this; }
  void End(const absl::Status& status, bool counted) {
    const grpc::Status converted = ToGrpcStatus(status);
    record_.Finish(converted);
    CallTracker* const calls = calls_;
    this->Finish(converted);  // `this` may be gone once Finish returns
    if (counted) calls->End();
  }

 private:
  CallRecord record_;
  CallTracker* const calls_;
};

template <typename Response>
class BlockingWriteReactor final : public BlockingReactor<grpc::ServerWriteReactor<Response>>,
                                   public StreamWriter<Response> {
 public:
  using BlockingReactor<grpc::ServerWriteReactor<Response>>::BlockingReactor;

  bool Write(const Response& message) override {
    written_.Start();
    this->StartWrite(&message);
    return written_.Wait();
  }
  void OnWriteDone(bool ok) override { written_.Done(ok); }

 private:
  StreamCompletion written_;
};

template <typename Request>
class BlockingReadReactor final : public BlockingReactor<grpc::ServerReadReactor<Request>>,
                                  public StreamReader<Request> {
 public:
  using BlockingReactor<grpc::ServerReadReactor<Request>>::BlockingReactor;

  bool Read(Request& message) override {
    if (ended_) return false;
    read_.Start();
    this->StartRead(&message);
    if (!read_.Wait()) ended_ = true;
    return !ended_;
  }
  void OnReadDone(bool ok) override { read_.Done(ok); }

 private:
  StreamCompletion read_;
  bool ended_ = false;  // the body's thread only
};

}  // namespace internal

// A server-streaming call: Body is absl::Status(StreamWriter<Response>&).
template <typename Response, typename Body>
grpc::ServerWriteReactor<Response>* ServeServerStream(const ServiceDeps& deps, grpc::CallbackServerContext* context,
                                                      const MethodSpec& method, Body body) {
  auto* reactor = new internal::BlockingWriteReactor<Response>(context, method, deps);
  internal::StartBlockingStream(
      deps, context, method, [reactor, body = std::move(body)]() mutable { return body(*reactor); },
      [reactor](const absl::Status& status, bool counted) { reactor->End(status, counted); });
  return reactor;
}

// A client-streaming call: Body is absl::Status(StreamReader<Request>&, Response&), filling
// `response` (the generated method's: gRPC sends it with an OK status).
template <typename Request, typename Response, typename Body>
grpc::ServerReadReactor<Request>* ServeClientStream(const ServiceDeps& deps, grpc::CallbackServerContext* context,
                                                    const MethodSpec& method, Response* response, Body body) {
  auto* reactor = new internal::BlockingReadReactor<Request>(context, method, deps);
  internal::StartBlockingStream(
      deps, context, method, [reactor, response, body = std::move(body)]() mutable { return body(*reactor, *response); },
      [reactor](const absl::Status& status, bool counted) { reactor->End(status, counted); });
  return reactor;
}

}  // namespace fremen::server
