// The QueryService's conversions, without a store: a request's checks and state references
// (server/convert/query_args.h, server/convert/state_refs.h), a PredictRegion request's box and chunk plan
// (server/services/region_plan.h), and a state's stored model as GetStateModel shows it
// (server/convert/query_convert.h, from records decoded as a shard decodes them).
//
// Input: a byte choosing the case and the map, then
//   0: a serialized PredictRequest (Predict's checks, in the service's order);
//   1: a serialized PredictRegionRequest (its box, output and chunking; the chunks must tile the
//      box in order, each within the message limit);
//   2: u16 length, a state-model record, then a lossless-history record (StateModelToProto).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "fremen/v1/query.pb.h"
#include "fuzz/fuzz_map.h"
#include "fuzz/fuzz_util.h"
#include "server/convert/query_args.h"
#include "server/convert/query_convert.h"
#include "server/services/region_plan.h"
#include "server/convert/state_refs.h"
#include "storage/model/lossless/lossless_history.h"
#include "storage/model/record_codec.h"

namespace {

using namespace fremen;

// The fuzz maps, and a grid as large as a map may be (2^21 cells a side) for the region plans.
storage::MapInfo QueryMap(uint8_t choice) {
  if (choice % 4 < 3) return fuzz::FuzzMap(choice % 4);
  storage::MapInfo info = fuzz::FuzzMap(0);
  info.grid.size = {1u << 21, 1u << 21, 4};
  return info;
}

void Predict(const storage::MapInfo& map, const uint8_t* data, size_t size) {
  v1::PredictRequest request;
  if (!request.ParseFromArray(data, static_cast<int>(size))) return;
  if (!server::CheckTimes(server::SpanOf(request.times()), "times").ok()) return;
  if (request.has_confidence() && !server::CheckConfidence(request.confidence(), 0, 1, "confidence").ok()) return;
  if (!server::PredictOptionsOf(map, request.options(), "options").ok()) return;
  if (!server::CheckPredictionCount(server::RefCount(request.states()), request.times_size()).ok()) return;
  auto keys = server::KeysOfRefs(map, request.states(), "states");
  if (!keys.ok()) return;
  FUZZ_CHECK(keys->size() == server::RefCount(request.states()), "one key per reference");
}

void Region(const storage::MapInfo& map, const uint8_t* data, size_t size) {
  v1::PredictRegionRequest request;
  if (!request.ParseFromArray(data, static_cast<int>(size))) return;
  auto box = server::RegionBoxOf(map, request.lo(), request.hi());
  if (!box.ok()) return;
  auto output = server::RegionOutputOf(request.output());
  if (!output.ok()) return;
  const uint64_t max_cells = server::ChunkCells(request.chunk_cells(), *output);
  FUZZ_CHECK(max_cells >= 1 && max_cells * server::BytesPerCell(*output) <= server::kMaxChunkBytes, "a chunk fits");
  const server::RegionPlan plan(*box, max_cells);
  FUZZ_CHECK(plan.box_cells() == box->cell_count() && plan.chunk_count() >= 1, "a plan of the box");
  // The first chunks and the last: each inside the box, within the limit, following the previous.
  const uint64_t count = plan.chunk_count();
  const auto check_run = [&](uint64_t begin, uint64_t end) {
    uint64_t next_offset = plan.chunk(begin).offset;
    for (uint64_t i = begin; i < end; ++i) {
      const server::RegionPlan::Chunk c = plan.chunk(i);
      for (int a = 0; a < 3; ++a) {
        FUZZ_CHECK(box->lo[a] <= c.box.lo[a] && c.box.lo[a] < c.box.hi[a] && c.box.hi[a] <= box->hi[a],
                   "a non-empty chunk inside the box");
      }
      FUZZ_CHECK(c.box.cell_count() <= max_cells, "a chunk within the limit");
      FUZZ_CHECK(c.offset == next_offset, "chunks follow one another");
      next_offset = c.offset + c.box.cell_count();
    }
    return next_offset;
  };
  FUZZ_CHECK(plan.chunk(0).offset == 0, "the first chunk starts the box");
  const uint64_t end = count <= 512 ? check_run(0, count) : (check_run(0, 256), check_run(count - 256, count));
  FUZZ_CHECK(end == box->cell_count(), "the last chunk ends the box");
  const server::RegionPlan::Chunk first = plan.chunk(0);
  if (first.box.cell_count() <= 4096) {
    std::vector<float> p(first.box.cell_count());
    for (size_t i = 0; i < p.size(); ++i) p[i] = static_cast<float>(i % 101) / 100.0f;
    v1::PredictRegionResponse response;
    server::EncodeRegionValues(*output, request.confidence(), p, response);
    FUZZ_CHECK(static_cast<size_t>(response.float_values_size()) + response.bytes_values().size() == p.size(),
               "one value per cell");
  }
}

void StateModel(const storage::MapInfo& map, const uint8_t* data, size_t size) {
  if (size < 2) return;
  const size_t length = std::min<size_t>(data[0] | data[1] << 8, size - 2);
  const std::string_view record = fuzz::AsView(data + 2, length);
  const std::string_view lossless = fuzz::AsView(data + 2 + length, size - 2 - length);
  const model::ModelSettings settings = *storage::ModelSettingsOf(map);
  storage::StateSnapshot snapshot;
  if (auto tag = model::PeekRecordTag(record); tag.ok() && *tag == model::RecordTag::kStaticState) {
    auto state = model::DecodeStaticState(record);
    if (!state.ok()) return;
    snapshot.static_state = *state;
  } else {
    auto m = model::DecodeStateModel<float>(record, settings);
    if (!m.ok()) return;
    snapshot.is_static = false;
    snapshot.model = *std::move(m);
    if (map.lossless_sampling_period > 0) {
      auto h = model::LosslessHistory::Decode(lossless);
      // The errors of the view are linear in the slots (up to 2^30 by design): small ones only.
      if (!h.ok() || h->slot_count() > (uint64_t{1} << 20)) return;
      snapshot.lossless = *std::move(h);
    }
  }
  snapshot.name = "door";
  v1::StateModel out;
  server::StateModelToProto(map, settings, 42, snapshot, true, out);
  FUZZ_CHECK(!out.SerializeAsString().empty(), "a model to send");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const storage::MapInfo map = QueryMap(data[0] / 4);
  switch (data[0] % 4) {
    case 0:
      Predict(map, data + 1, size - 1);
      break;
    case 1:
      Region(map, data + 1, size - 1);
      break;
    case 2:
      StateModel(map.kind == storage::MapKind::kGrid && map.grid.size[0] > 4096 ? fuzz::FuzzMap(2) : map, data + 1,
                 size - 1);
      break;
    default:
      break;
  }
  return 0;
}
