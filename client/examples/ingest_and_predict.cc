// Example: create a small grid map, ingest two weeks of scans of a door that opens in the day, and
// predict the door's cell at noon and at midnight of the day after.
//
//   ingest_and_predict [ADDRESS] [TOKEN]      (default 127.0.0.1:50051, no token)
#include <cmath>
#include <cstdio>
#include <string>

#include "client/lib/client.h"

namespace fc = fremen::client;

int main(int argc, char** argv) {
  fc::ConnectionOptions options;
  if (argc > 1) options.address = argv[1];
  if (argc > 2) options.token = argv[2];
  auto client = fc::Client::Connect(options);
  if (!client.ok()) return std::fprintf(stderr, "%s\n", client.status().ToString().c_str()), 1;

  // A 20 m × 10 m floor of 0.5 m cells (an existing map of that name is reused).
  fremen::v1::Map map;
  map.set_name("example-floor");
  map.set_kind(fremen::v1::MAP_KIND_GRID);
  map.mutable_grid()->set_resolution(0.5);
  map.mutable_grid()->mutable_size()->set_x(40);
  map.mutable_grid()->mutable_size()->set_y(20);
  if (auto created = client->CreateMap(map); !created.ok() && !absl::IsAlreadyExists(created.status())) {
    return std::fprintf(stderr, "CreateMap: %s\n", created.status().ToString().c_str()), 1;
  }

  // Two weeks of hourly scans: the door cell (10, 5) is open (0, free) from 8:00 to 18:00 UTC. The
  // update job after each week chooses the model order by how well each order predicted the week
  // (the first update has nothing to score yet and publishes order 0), as the paper's robots do
  // every night.
  const double start = 1.7e9 - std::fmod(1.7e9, 86400.0);
  for (int week = 0; week < 2; ++week) {
    auto session = client->OpenIngest(map.name());
    if (!session.ok()) return std::fprintf(stderr, "OpenIngest: %s\n", session.status().ToString().c_str()), 1;
    for (int hour = week * 168; hour < (week + 1) * 168; ++hour) {
      const int h = hour % 24;
      fc::ScanBuilder scan(start + hour * 3600.0);
      scan.AddCell({10, 5, 0}, h >= 8 && h < 18 ? 0.0f : 1.0f);
      scan.AddCell({11, 5, 0}, 1.0f);  // the wall beside it
      auto built = scan.Build();
      if (!built.ok()) return std::fprintf(stderr, "scan: %s\n", built.status().ToString().c_str()), 1;
      if (auto sent = (*session)->Send(*std::move(built)); !sent.ok()) {
        return std::fprintf(stderr, "Send: %s\n", sent.status().ToString().c_str()), 1;
      }
    }
    // Waits for every acknowledgement; the session resends batches across reconnects.
    if (absl::Status closed = (*session)->Close(absl::Seconds(60)); !closed.ok()) {
      return std::fprintf(stderr, "Close: %s\n", closed.ToString().c_str()), 1;
    }
    const fc::IngestTotals totals = (*session)->totals();
    std::printf("week %d: %llu scans, %llu observations accepted, %llu rejected\n", week + 1,
                static_cast<unsigned long long>(totals.acknowledged), static_cast<unsigned long long>(totals.accepted),
                static_cast<unsigned long long>(totals.rejected));
    auto op = client->RunUpdate(map.name());
    if (op.ok()) op = client->WaitOperation(map.name(), op->name());
    if (!op.ok()) return std::fprintf(stderr, "update: %s\n", op.status().ToString().c_str()), 1;
  }

  const double noon = start + 14 * 86400 + 12 * 3600, midnight = start + 14 * 86400;
  auto p = client->Predict(map.name(), fc::StateSet::Cells({{10, 5, 0}}), {noon, midnight});
  if (!p.ok()) return std::fprintf(stderr, "Predict: %s\n", p.status().ToString().c_str()), 1;
  std::printf("door cell occupied: p = %.2f at noon, %.2f at midnight\n", p->probability(0, 0), p->probability(1, 0));
  return 0;
}
