// fremen.v1.Map → storage::MapInfo (server/convert/map_convert.h), as CreateMap takes it, then what a map
// the daemon accepted must keep: its model settings exist, and the map survives the catalog's
// encoding and the way back to the proto unchanged. Input: a serialized fremen.v1.Map.
#include <cstddef>
#include <cstdint>

#include "fremen/v1/maps.pb.h"
#include "fuzz/fuzz_util.h"
#include "server/convert/map_convert.h"
#include "storage/map_info.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fremen;
  v1::Map proto;
  if (!proto.ParseFromArray(data, static_cast<int>(size))) return 0;
  auto info = server::MapInfoFromProto(proto);
  if (!info.ok()) {
    FUZZ_CHECK(absl::IsInvalidArgument(info.status()), info.status().ToString());
    return 0;
  }
  FUZZ_CHECK(storage::ValidateMapInfo(*info).ok(), "an accepted map is valid");
  auto settings = storage::ModelSettingsOf(*info);
  FUZZ_CHECK(settings.ok(), settings.status().ToString());
  v1::Map back;
  server::MapInfoToProto(*info, back);
  auto again = server::MapInfoFromProto(back);
  FUZZ_CHECK(again.ok(), again.status().ToString());
  FUZZ_CHECK(*again == *info, "MapInfoToProto then MapInfoFromProto gives the map back");
  auto decoded = storage::DecodeMapInfo(storage::EncodeMapInfo(*info));
  FUZZ_CHECK(decoded.ok(), decoded.status().ToString());
  FUZZ_CHECK(*decoded == *info, "the catalog encoding round-trips");
  return 0;
}
