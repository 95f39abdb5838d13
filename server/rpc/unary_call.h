// How every unary RPC is served, so that handlers hold only their method's logic: the call is
// counted (server/rpc/call_tracker.h: refused while the daemon drains), the token is checked, the
// handler's body runs — inline when it is quick and never waits, on the blocking pool
// when it may wait on disk — and the call is finished with the body's status, converted once
// (server/rpc/status_convert.h) and written to the access log.
//
// A handler:
//   grpc::ServerUnaryReactor* MapServiceImpl::GetMap(grpc::CallbackServerContext* context,
//                                                    const GetMapRequest* request, GetMapResponse* response) {
//     return ServeUnary(deps_, context, kGetMap, [=]() -> absl::Status { ...fill *response... });
//   }
// The body may use request, response and context until it returns: the call is finished after.
// Thread-safety: the body runs once, on a gRPC thread or a blocking-pool thread.
#pragma once

#include <grpcpp/server_context.h>
#include <grpcpp/support/server_callback.h>

#include <chrono>
#include <utility>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/string_view.h"
#include "absl/time/time.h"
#include "server/rpc/access_log.h"
#include "server/rpc/auth.h"
#include "server/rpc/blocking_pool.h"
#include "server/rpc/call_observer.h"
#include "server/rpc/call_tracker.h"
#include "server/rpc/status_convert.h"
#include "server/rpc/store_handle.h"

namespace fremen::server {

// The call's deadline, for work that must not outlive it (a forked verifier, storage/isolated_child.h);
// InfiniteFuture when the client set none.
inline absl::Time CallDeadline(const grpc::ServerContextBase& context) {
  const std::chrono::system_clock::time_point deadline = context.deadline();
  if (deadline == std::chrono::system_clock::time_point::max()) return absl::InfiniteFuture();
  return absl::FromChrono(deadline);
}

// What the services need from the daemon. Owned by the daemon; outlives the gRPC server.
struct ServiceDeps {
  CallTracker* calls = nullptr;
  const Authenticator* auth = nullptr;
  BlockingPool* blocking = nullptr;
  const StoreHandle* store = nullptr;
  CallObserver* observer = nullptr;  // the metrics; null: none
};

// One method: its name (in logs and errors), the access it needs, and whether its body may wait on
// disk (then it must not run on a gRPC thread).
struct MethodSpec {
  absl::string_view name;
  Access access = Access::kRead;
  bool blocking = false;
};

// One unary call from its start to its one Finish.
class UnaryCall {
 public:
  UnaryCall(grpc::CallbackServerContext* context, const MethodSpec& method, const ServiceDeps& deps)
      : reactor_(context->DefaultReactor()), record_(method.name, *context, deps.observer), calls_(deps.calls) {}

  grpc::ServerUnaryReactor* reactor() const { return reactor_; }
  // Logs the call, hands its status to gRPC and, when `counted`, ends it in the tracker.
  void Finish(const absl::Status& status, bool counted = true) const {
    const grpc::Status converted = ToGrpcStatus(status);
    record_.Finish(converted);
    reactor_->Finish(converted);
    if (counted) calls_->End();
  }

 private:
  grpc::ServerUnaryReactor* reactor_;
  CallRecord record_;
  CallTracker* calls_;
};

// Body: absl::Status(), filling the response.
template <typename Body>
grpc::ServerUnaryReactor* ServeUnary(const ServiceDeps& deps, grpc::CallbackServerContext* context,
                                     const MethodSpec& method, Body body) {
  const UnaryCall call(context, method, deps);
  if (absl::Status refused = deps.calls->Begin(); !refused.ok()) {
    call.Finish(refused, /*counted=*/false);
    return call.reactor();
  }
  if (absl::Status denied = deps.auth->Authorize(*context, method.access, method.name); !denied.ok()) {
    call.Finish(denied);
    return call.reactor();
  }
  if (!method.blocking) {
    call.Finish(body());
    return call.reactor();
  }
  const bool queued = deps.blocking->Post([call, context, body = std::move(body)]() mutable {
    // A client that gave up (deadline, cancellation) while the call queued is not worth the disk work.
    if (context->IsCancelled()) {
      call.Finish(absl::CancelledError("cancelled or past its deadline before it started"));
      return;
    }
    call.Finish(body());
  });
  if (!queued) {
    call.Finish(absl::ResourceExhaustedError(
        absl::StrCat("fremend is busy (too many calls waiting on disk); retry ", method.name, " later")));
  }
  return call.reactor();
}

}  // namespace fremen::server
