#include "storage/static_bricks.h"

#include <bit>

#include "absl/strings/str_cat.h"
#include "storage/model/varint.h"

namespace fremen::storage {

namespace {
constexpr uint8_t kVersion = 1;
constexpr size_t kBitmapBytes = 64;
}  // namespace

std::string StaticBrick::Encode() const {
  std::string out(1 + kBitmapBytes, '\0');
  out[0] = static_cast<char>(kVersion);
  for (const Entry& e : entries_) out[1 + e.index / 8] = static_cast<char>(out[1 + e.index / 8] | (1 << (e.index % 8)));
  for (const Entry& e : entries_) {
    model::PutDouble(&out, e.state.t_first);
    model::PutFloat(&out, e.state.span);
    model::PutFixed32(&out, e.state.count_value);
  }
  return out;
}

absl::StatusOr<StaticBrick> StaticBrick::Decode(std::string_view bytes) {
  model::ByteReader r(bytes, "static brick");
  if (const uint8_t version = r.Byte("version"); r.ok() && version != kVersion) {
    r.Fail("version", absl::StrCat("unknown version ", version));
  }
  const std::string_view bitmap = r.Bytes(kBitmapBytes, "bitmap");
  size_t present = 0;
  for (char c : bitmap) present += std::popcount(static_cast<uint8_t>(c));
  if (r.ok() && present * 16 != r.remaining()) r.Fail("states", "the bitmap and the record's length disagree");
  StaticBrick brick;
  for (uint32_t i = 0; r.ok() && i < 512; ++i) {
    if (!(static_cast<uint8_t>(bitmap[i / 8]) >> (i % 8) & 1)) continue;
    model::StaticState state;
    state.t_first = r.Double("t_first");
    state.span = r.Float("span");
    state.count_value = r.Fixed32("count");
    if (r.ok() && (!std::isfinite(state.t_first) || !(state.span >= 0) || state.count() == 0)) {
      r.Fail("state", absl::StrCat("state ", i, " is not a plausible never-changed state"));
    }
    brick.Add(i, state);
  }
  if (absl::Status s = r.Finish(); !s.ok()) return s;
  return brick;
}

}  // namespace fremen::storage
