// A ROS map_server snapshot as fremenctl ingest --map-server turns it into observations
// (client/formats/map_server_snapshots.h): its YAML and PGM parsed, placed on a map's grid, and cut
// into batches. Every observed cell lies on the grid; no batch is over its limit. Input: u16 length
// of the YAML text, the YAML text, then the PGM file's bytes.
#include <cstddef>
#include <cstdint>
#include <string>

#include "client/formats/map_server_snapshots.h"
#include "client/formats/map_yaml.h"
#include "client/formats/pgm.h"
#include "fuzz/fuzz_util.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fremen;
  if (size < 2) return 0;
  const size_t length = std::min<size_t>(data[0] | data[1] << 8, size - 2);
  formats::Snapshot snapshot;
  auto metadata = formats::ParseMapYaml(std::string(fuzz::AsView(data + 2, length)), "fuzz.yaml");
  if (!metadata.ok()) return 0;
  auto image = formats::ParsePgm(std::string(fuzz::AsView(data + 2 + length, size - 2 - length)), "fuzz.pgm");
  if (!image.ok()) return 0;
  snapshot.metadata = *metadata;
  snapshot.image = *std::move(image);
  const formats::GridPlacement grid{0.05, -10, -10, 2048, 2048};
  uint32_t offset_x = 0, offset_y = 0;
  if (!formats::PlaceSnapshot(snapshot, grid, "fuzz", offset_x, offset_y).ok()) return 0;
  constexpr size_t kMaxCells = 1000;
  for (const formats::CellBatch& batch : formats::SnapshotBatches(snapshot, 1.7e9, offset_x, offset_y, kMaxCells)) {
    FUZZ_CHECK(batch.size() <= kMaxCells && batch.x.size() == batch.size() && batch.y.size() == batch.size(),
               "a batch within its limit");
    for (size_t i = 0; i < batch.size(); ++i) {
      FUZZ_CHECK(batch.x[i] < grid.size_x && batch.y[i] < grid.size_y, "a cell on the grid");
      FUZZ_CHECK(batch.values[i] >= 0 && batch.values[i] <= 1, "an observation in [0, 1]");
    }
  }
  return 0;
}
