// What the metrics' end-to-end tests share: an HTTP client for a daemon's HTTP port (tests/http_client.h), and a map
// created and fed through the daemon's gRPC services (so that every count comes from real calls).
#pragma once

#include <httplib.h>

#include <string>
#include <utility>
#include <vector>

#include "fremen/v1/ingest.grpc.pb.h"
#include "fremen/v1/maps.grpc.pb.h"
#include "gtest/gtest.h"
#include "tests/fremend_fixture.h"
#include "tests/http_client.h"
#include "tests/map_specs.h"

namespace fremen::testing {

using Metadata = std::vector<std::pair<std::string, std::string>>;

// Creates the 20x10 grid map `name` over gRPC.
inline void CreateGridMap(FremendProcess& daemon, const std::string& name, const Metadata& metadata = {}) {
  auto maps = v1::MapService::NewStub(daemon.NewChannel());
  v1::CreateMapRequest request;
  *request.mutable_map() = GridMapSpec(name, 20, 10, 0.5);
  v1::CreateMapResponse created;
  const grpc::Status status = maps->CreateMap(CallContext(metadata).get(), request, &created);
  ASSERT_TRUE(status.ok()) << status.error_message();
}

// Sends `batches` batches of `cells` valid cell observations each to map `name` on one Ingest
// stream, each acknowledged; returns the observations sent.
inline uint64_t IngestCells(FremendProcess& daemon, const std::string& name, int batches, uint32_t cells,
                            const Metadata& metadata = {}) {
  auto ingest = v1::IngestService::NewStub(daemon.NewChannel());
  auto context = CallContext(metadata);
  auto stream = ingest->Ingest(context.get());
  uint64_t sent = 0;
  for (int b = 0; b < batches; ++b) {
    v1::IngestRequest request;
    request.set_map(name);
    request.set_writer_id(7);
    request.set_sequence(b + 1);
    request.set_time(1.7e9 + 600.0 * b);
    for (uint32_t i = 0; i < cells; ++i) {
      request.mutable_cells()->mutable_cells()->add_x(i % 20);
      request.mutable_cells()->mutable_cells()->add_y((i / 20) % 10);
      request.mutable_cells()->add_values(static_cast<float>((i + b) % 2));
    }
    EXPECT_TRUE(stream->Write(request));
    v1::IngestResponse response;
    EXPECT_TRUE(stream->Read(&response));
    EXPECT_EQ(response.accepted(), cells) << response.DebugString();
    sent += cells;
  }
  stream->WritesDone();
  const grpc::Status status = stream->Finish();
  EXPECT_TRUE(status.ok()) << status.error_message();
  return sent;
}

}  // namespace fremen::testing
