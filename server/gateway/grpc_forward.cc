#include "server/gateway/grpc_forward.h"

#include <string>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"

namespace fremen::server {

grpc::Status IngestOne(const std::shared_ptr<grpc::Channel>& channel, grpc::ClientContext& context,
                       const v1::IngestRequest& request, v1::IngestResponse& response) {
  v1::IngestService::Stub stub(channel);
  auto stream = stub.Ingest(&context);
  // A failed write or read means the call ended: Finish says why.
  if (stream->Write(request)) {
    stream->WritesDone();
    stream->Read(&response);
  }
  return stream->Finish();
}

grpc::Status WholeRegion(const std::shared_ptr<grpc::Channel>& channel, grpc::ClientContext& context,
                         const v1::PredictRegionRequest& request, v1::PredictRegionResponse& response) {
  v1::QueryService::Stub stub(channel);
  auto reader = stub.PredictRegion(&context, request);
  v1::PredictRegionResponse chunk;
  bool first = true;
  while (reader->Read(&chunk)) {
    if (first) {
      first = false;
      if (chunk.box_cells() > kMaxJoinedRegionCells) {
        context.TryCancel();
        (void)reader->Finish();
        return grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED,
                            absl::StrCat("the box [lo, hi) has ", chunk.box_cells(), " cells; one JSON answer holds at most ",
                                         kMaxJoinedRegionCells, " (ask for smaller boxes, or stream it over gRPC)"));
      }
      response.set_box_cells(chunk.box_cells());
      if (chunk.float_values_size() > 0) response.mutable_float_values()->Reserve(static_cast<int>(chunk.box_cells()));
    }
    response.mutable_float_values()->Add(chunk.float_values().begin(), chunk.float_values().end());
    response.mutable_bytes_values()->append(chunk.bytes_values());
  }
  return reader->Finish();
}

std::unique_ptr<grpc::ClientContext> ForwardedContext(const httplib::Request& http) {
  auto context = std::make_unique<grpc::ClientContext>();
  if (http.has_header("Authorization")) {
    // Metadata values may not hold control characters: such a header is dropped, and the call is
    // then refused as one without a token.
    const std::string value = http.get_header_value("Authorization");
    bool printable = true;
    for (char c : value) printable = printable && absl::ascii_isprint(static_cast<unsigned char>(c));
    context->AddMetadata("authorization", printable ? value : "invalid");
  }
  return context;
}

}  // namespace fremen::server
