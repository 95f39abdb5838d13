#include "server/services/ingest_service.h"

#include "server/services/ingest_stream.h"
#include "server/rpc/map_lookup.h"

namespace fremen::server {

namespace {

constexpr MethodSpec kLastSequence{"LastSequence", Access::kWrite, /*blocking=*/false};

}  // namespace

grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* IngestServiceImpl::Ingest(
    grpc::CallbackServerContext* context) {
  return IngestStream::Start(deps_, context);
}

grpc::ServerUnaryReactor* IngestServiceImpl::LastSequence(grpc::CallbackServerContext* context,
                                                          const v1::LastSequenceRequest* request,
                                                          v1::LastSequenceResponse* response) {
  return ServeUnary(deps_, context, kLastSequence, [this, context, request, response]() -> absl::Status {
    auto map = LookUpMap(*deps_.store, *context, request->map());
    if (!map.ok()) return map.status();
    // A writer asking where to continue is about to write: during a move, its answer is the new
    // owner's.
    if (!storage::TakesWrites((*map)->Move().state)) return storage::MovingError((*map)->info().name);
    response->set_last_sequence((*map)->LastSequence(request->writer_id()));
    return absl::OkStatus();
  });
}

}  // namespace fremen::server
