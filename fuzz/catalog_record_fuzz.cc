// A catalog record (storage/map_info.h DecodeMapInfo, what storage/catalog.cc reads for every map
// at Get and List), then what the daemon does with a map it found in its catalog: validate it,
// derive its model settings, show it as a fremen.v1.Map. A record that decodes encodes back to a
// record that decodes to the same map. Input: the record's bytes.
#include <cstddef>
#include <cstdint>
#include <string>

#include "fremen/v1/maps.pb.h"
#include "fuzz/fuzz_util.h"
#include "server/convert/map_convert.h"
#include "storage/map_info.h"

namespace {

// The first field in which two maps differ, for the failure message.
std::string FirstDifference(const fremen::storage::MapInfo& a, const fremen::storage::MapInfo& b) {
  if (a.name != b.name) return "name";
  if (a.kind != b.kind) return "kind";
  if (!(a.grid == b.grid)) return "grid";
  if (!(a.periods == b.periods)) return "periods";
  if (a.max_order != b.max_order) return "max_order";
  if (a.persistence != b.persistence) return "persistence";
  if (a.error_half_life != b.error_half_life) return "error_half_life";
  if (a.criterion != b.criterion) return "criterion";
  if (a.order_rule != b.order_rule) return "order_rule";
  if (a.lossless_sampling_period != b.lossless_sampling_period) return "lossless_sampling_period";
  if (a.lossless_origin != b.lossless_origin) return "lossless_origin";
  if (a.shards != b.shards) return "shards";
  return "id or created_unix";
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fremen;
  auto info = storage::DecodeMapInfo(fuzz::AsView(data, size));
  if (!info.ok()) {
    FUZZ_CHECK(absl::IsDataLoss(info.status()), info.status().ToString());
    return 0;
  }
  // Compared encoded (bit for bit): a generic map's unchecked grid may hold a NaN.
  const std::string encoded = storage::EncodeMapInfo(*info);
  auto again = storage::DecodeMapInfo(encoded);
  FUZZ_CHECK(again.ok() && storage::EncodeMapInfo(*again) == encoded, "a decoded record re-encodes to itself");
  if (!storage::ValidateMapInfo(*info).ok()) return 0;
  auto settings = storage::ModelSettingsOf(*info);
  FUZZ_CHECK(settings.ok(), settings.status().ToString());
  v1::Map proto;
  server::MapInfoToProto(*info, proto);
  auto back = server::MapInfoFromProto(proto);
  FUZZ_CHECK(back.ok(), back.status().ToString());
  // The catalog's own fields: the proto has no id, and its create_time is output only. A generic
  // map's record carries a grid too, which means nothing and which the proto leaves out.
  back->id = info->id;
  back->created_unix = info->created_unix;
  if (info->kind == storage::MapKind::kGeneric) back->grid = info->grid;
  FUZZ_CHECK(storage::EncodeMapInfo(*back) == encoded, "a valid catalog map shows as a fremen.v1.Map that reads back as itself, but " +
                                 FirstDifference(*back, *info) + " differs");
  return 0;
}
