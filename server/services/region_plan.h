// PredictRegion's arithmetic, apart from the streaming: the request's box checked against the map,
// its split into chunks that each fit a message, and the encoding of a chunk's probabilities in the
// requested output (FLOAT, UINT8, ENTROPY, STATES).
//
// A chunk is a run of consecutive cells of the box in its order (x fastest, then y, then z) that is
// itself a box — whole z-planes, whole rows of one plane, or part of one row — so that each is one
// MapStore::PredictBox call and memory stays bounded by the chunk, whatever the size of the box.
// Pure functions and value types; thread-safe.
#pragma once

#include <cstdint>
#include <span>
#include <string>

#include "absl/status/statusor.h"
#include "fremen/v1/query.pb.h"
#include "storage/map_info.h"
#include "storage/queries.h"

namespace fremen::server {

// Payload of one chunk at most: leaves room for the response's other fields within the smallest
// message limit the daemon allows (1 MiB).
inline constexpr uint64_t kMaxChunkBytes = (uint64_t{1} << 20) - 1024;

// Cells computed by one PredictBox call: large enough that the shards' threads pay off (~1 ms of
// work), small enough that a 1M-cell box is several blocks, so that computing the next overlaps
// sending this one (measured: 1M FLOAT cells 105M → 133-160M cells/s, UINT8 146M → 172-246M,
// against 1M-cell blocks), and memory stays bounded (1 MiB of floats a block).
inline constexpr uint64_t kRegionBlockCells = uint64_t{1} << 18;

// A block this small is computed inline on the thread that asks for it (well under a millisecond):
// the hop to the pool would cost more than the work.
inline constexpr uint64_t kInlineRegionCells = 1 << 15;

// The box [lo, hi) of a request. FailedPrecondition on a generic map; OutOfRange naming lo.x / hi.x
// ... unless lo < hi ≤ the grid's size on every axis. On a 2-D grid, lo.z = hi.z = 0 is taken as
// the one plane [0, 1) (clients leave z unset).
absl::StatusOr<storage::CellBox> RegionBoxOf(const storage::MapInfo& map, const v1::CellIndex& lo,
                                             const v1::CellIndex& hi);

// The output asked for (UNSPECIFIED = FLOAT); InvalidArgument naming `output` for unknown values.
absl::StatusOr<v1::RegionOutput> RegionOutputOf(int output);

// Bytes per cell of an output: 4 for floats, 1 for bytes.
uint64_t BytesPerCell(v1::RegionOutput output);

// Cells per chunk: `requested` (0 = the most), at most what fits kMaxChunkBytes.
uint64_t ChunkCells(uint64_t requested, v1::RegionOutput output);

// The box cells a PredictRegionSeries base chunk covers: at most `max_cells` (ChunkCells), a
// multiple of 8 (whole bytes of the varying mask), and few enough that the mask and the values fit
// kMaxChunkBytes.
uint64_t BaseChunkCells(uint64_t max_cells, v1::RegionOutput output);

class RegionPlan {
 public:
  struct Chunk {
    storage::CellBox box;
    uint64_t offset = 0;  // of its first cell in the whole box
  };

  // REQUIRES: a non-empty box, max_cells ≥ 1.
  RegionPlan(const storage::CellBox& box, uint64_t max_cells);

  uint64_t chunk_count() const { return count_; }
  uint64_t box_cells() const { return box_.cell_count(); }
  // REQUIRES: i < chunk_count().
  Chunk chunk(uint64_t i) const;

 private:
  enum class Unit { kPlanes, kRows, kRowParts };
  storage::CellBox box_;
  uint64_t nx_, ny_, nz_;
  Unit unit_;
  uint64_t per_;        // planes, rows or cells per chunk
  uint64_t per_line_;   // chunks per plane (kRows) or per row (kRowParts)
  uint64_t count_;
};

// Sets `floats` or `bytes` (per `output`; clears the other) from the probabilities of a chunk's
// cells; `confidence` is for STATES (p ≥ c → 1).
void EncodeRegionValues(v1::RegionOutput output, float confidence, std::span<const float> p,
                        google::protobuf::RepeatedField<float>& floats, std::string& bytes);
// The values of a response: float_values or bytes_values.
template <typename Response>
void EncodeRegionValues(v1::RegionOutput output, float confidence, std::span<const float> p, Response& out) {
  EncodeRegionValues(output, confidence, p, *out.mutable_float_values(), *out.mutable_bytes_values());
}

}  // namespace fremen::server
