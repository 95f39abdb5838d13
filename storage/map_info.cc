#include "storage/map_info.h"

#include <cmath>

#include "absl/strings/str_cat.h"
#include "storage/model/varint.h"

namespace fremen::storage {

using model::ByteReader;

namespace {

// Version 2 appended the order rule; version 1 records are still read (order_rule = margin 0.001).
constexpr uint8_t kMapInfoVersion = 2;
constexpr uint8_t kMapInfoVersionWithoutOrderRule = 1;
constexpr size_t kMaxNameLength = 128;
constexpr uint32_t kMaxShards = 256;
constexpr uint32_t kMaxGridSide = 1u << 21;

bool IsNameChar(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' ||
         c == '-';
}

bool PositiveFinite(double v) { return std::isfinite(v) && v > 0; }

}  // namespace

std::optional<std::array<uint32_t, 3>> GridGeometry::CellOf(double x, double y, double z) const {
  const double point[3] = {x, y, z};
  std::array<uint32_t, 3> cell;
  for (int a = 0; a < 3; ++a) {
    const double index = std::floor((point[a] - origin[a]) / resolution);
    if (!std::isfinite(index) || index < 0 || index >= size[a]) return std::nullopt;
    cell[a] = static_cast<uint32_t>(index);
  }
  return cell;
}

absl::Status ValidateMapInfo(const MapInfo& info) {
  if (info.name.empty() || info.name.size() > kMaxNameLength || info.name[0] == '.') {
    return absl::InvalidArgumentError(
        absl::StrCat("name must be 1 to 128 characters and not start with '.', got \"", info.name, "\""));
  }
  for (char c : info.name) {
    if (!IsNameChar(c)) {
      return absl::InvalidArgumentError(
          absl::StrCat("name may hold only letters, digits, '.', '_' and '-', got \"", info.name, "\""));
    }
  }
  if (info.kind != MapKind::kGrid && info.kind != MapKind::kGeneric) {
    return absl::InvalidArgumentError("kind must be grid or generic");
  }
  if (info.kind == MapKind::kGrid) {
    if (!PositiveFinite(info.grid.resolution)) {
      return absl::InvalidArgumentError(
          absl::StrCat("grid.resolution must be a positive number of metres, got ", info.grid.resolution));
    }
    static constexpr const char* kAxes[3] = {"x", "y", "z"};
    for (int a = 0; a < 3; ++a) {
      if (!std::isfinite(info.grid.origin[a])) {
        return absl::InvalidArgumentError(absl::StrCat("grid.origin.", kAxes[a], " must be finite"));
      }
      if (info.grid.size[a] < 1 || info.grid.size[a] > kMaxGridSide) {
        return absl::InvalidArgumentError(
            absl::StrCat("grid.size.", kAxes[a], " must be in [1, 2097152], got ", info.grid.size[a]));
      }
    }
  }
  // Checked even where explicit periods make the count unused: the catalog's encoding keeps at
  // most 65535, and a record it could not decode would fail the map at the next start.
  if (info.periods.count > 65535) {
    return absl::InvalidArgumentError(absl::StrCat("periods: period count must be in [1, 65535], got ", info.periods.count));
  }
  if (!info.periods.explicit_periods.empty()) {
    if (auto p = model::PeriodSet::FromPeriods(info.periods.explicit_periods); !p.ok()) {
      return absl::InvalidArgumentError(absl::StrCat("periods.", p.status().message()));
    }
  } else if (auto p = model::PeriodSet::Harmonics(info.periods.longest, static_cast<int>(info.periods.count),
                                                  info.periods.floor_periods);
             !p.ok()) {
    return absl::InvalidArgumentError(absl::StrCat("periods: ", p.status().message()));
  }
  if (info.max_order > model::kMaxMaxOrder) {
    return absl::InvalidArgumentError(absl::StrCat("max_order must be in [0, 64], got ", info.max_order));
  }
  if (!std::isfinite(info.error_half_life) || info.error_half_life < 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("error_half_life must be ≥ 0 seconds (0: since the last update), got ", info.error_half_life));
  }
  if (info.criterion != model::ErrorCriterion::kThreshold && info.criterion != model::ErrorCriterion::kSquared) {
    return absl::InvalidArgumentError("criterion must be threshold or squared");
  }
  const model::OrderRule& rule = info.order_rule;
  if (rule.selection != model::OrderSelection::kMargin && rule.selection != model::OrderSelection::kPaper &&
      rule.selection != model::OrderSelection::kWeighted) {
    return absl::InvalidArgumentError("order_selection must be margin, paper or weighted");
  }
  if (!std::isfinite(rule.margin) || rule.margin < 0) {
    return absl::InvalidArgumentError(absl::StrCat("order_margin must be finite and ≥ 0, got ", rule.margin));
  }
  if (!std::isfinite(rule.temperature) || rule.temperature <= 0) {
    return absl::InvalidArgumentError(absl::StrCat("order_temperature must be finite and > 0, got ", rule.temperature));
  }
  if (!std::isfinite(info.lossless_sampling_period) || info.lossless_sampling_period < 0) {
    return absl::InvalidArgumentError(absl::StrCat(
        "lossless_sampling_period must be ≥ 0 seconds (0: no lossless history), got ", info.lossless_sampling_period));
  }
  if (!std::isfinite(info.lossless_origin)) return absl::InvalidArgumentError("lossless_origin must be finite");
  if (info.shards > kMaxShards) {
    return absl::InvalidArgumentError(absl::StrCat("shards must be in [1, 256] (0: one per core), got ", info.shards));
  }
  return absl::OkStatus();
}

absl::StatusOr<model::ModelSettings> ModelSettingsOf(const MapInfo& info) {
  model::ModelSettings settings;
  auto periods = info.periods.explicit_periods.empty()
                     ? model::PeriodSet::Harmonics(info.periods.longest, static_cast<int>(info.periods.count),
                                                   info.periods.floor_periods)
                     : model::PeriodSet::FromPeriods(info.periods.explicit_periods);
  if (!periods.ok()) return periods.status();
  settings.periods = *std::move(periods);
  settings.max_order = static_cast<int>(info.max_order);
  settings.persistence = info.persistence;
  settings.error_half_life = info.error_half_life;
  settings.criterion = info.criterion;
  settings.order_rule = info.order_rule;
  return settings;
}

// Layout (version 1): version u8 | name (varint length, bytes) | id varint | kind u8 |
// resolution f64 | origin 3×f64 | size 3×varint | longest f64 | count varint | floor u8 |
// explicit periods (varint count, f64 each) | max_order varint | persistence u8 | half-life f64 |
// criterion u8 | lossless period f64 | lossless origin f64 | shards varint | created zigzag varint.
// Version 2 appends: order selection u8 | order margin f64 | order temperature f64.
std::string EncodeMapInfo(const MapInfo& info) {
  std::string out;
  out.push_back(static_cast<char>(kMapInfoVersion));
  model::PutVarint64(&out, info.name.size());
  out += info.name;
  model::PutVarint64(&out, info.id);
  out.push_back(static_cast<char>(info.kind));
  model::PutDouble(&out, info.grid.resolution);
  for (double o : info.grid.origin) model::PutDouble(&out, o);
  for (uint32_t s : info.grid.size) model::PutVarint64(&out, s);
  model::PutDouble(&out, info.periods.longest);
  model::PutVarint64(&out, info.periods.count);
  out.push_back(info.periods.floor_periods ? 1 : 0);
  model::PutVarint64(&out, info.periods.explicit_periods.size());
  for (double p : info.periods.explicit_periods) model::PutDouble(&out, p);
  model::PutVarint64(&out, info.max_order);
  out.push_back(info.persistence ? 1 : 0);
  model::PutDouble(&out, info.error_half_life);
  out.push_back(static_cast<char>(info.criterion));
  model::PutDouble(&out, info.lossless_sampling_period);
  model::PutDouble(&out, info.lossless_origin);
  model::PutVarint64(&out, info.shards);
  model::PutVarint64(&out, model::ZigZagEncode64(info.created_unix));
  out.push_back(static_cast<char>(info.order_rule.selection));
  model::PutDouble(&out, info.order_rule.margin);
  model::PutDouble(&out, info.order_rule.temperature);
  return out;
}

absl::StatusOr<MapInfo> DecodeMapInfo(std::string_view bytes) {
  ByteReader r(bytes, "map info");
  MapInfo info;
  const uint8_t version = r.Byte("version");
  if (r.ok() && version != kMapInfoVersion && version != kMapInfoVersionWithoutOrderRule) {
    r.Fail("version", absl::StrCat("unknown version ", version));
  }
  const uint64_t name_length = r.Varint("name length");
  if (r.ok() && name_length > kMaxNameLength) r.Fail("name length", "longer than 128");
  info.name = std::string(r.Bytes(r.ok() ? name_length : 0, "name"));
  info.id = r.Varint("id");
  info.kind = static_cast<MapKind>(r.Byte("kind"));
  info.grid.resolution = r.Double("grid.resolution");
  for (double& o : info.grid.origin) o = r.Double("grid.origin");
  for (uint32_t& s : info.grid.size) {
    const uint64_t v = r.Varint("grid.size");
    if (r.ok() && v > kMaxGridSide) r.Fail("grid.size", "larger than 2^21");
    s = static_cast<uint32_t>(v);
  }
  info.periods.longest = r.Double("periods.longest");
  const uint64_t count = r.Varint("periods.count");
  if (r.ok() && count > 65535) r.Fail("periods.count", "more than 65535");
  info.periods.count = static_cast<uint32_t>(count);
  info.periods.floor_periods = r.Byte("periods.floor_periods") != 0;
  const uint64_t explicit_count = r.Varint("periods.explicit count");
  if (r.ok() && explicit_count * 8 > r.remaining()) r.Fail("periods.explicit count", "more than the bytes left");
  for (uint64_t i = 0; r.ok() && i < explicit_count; ++i) {
    info.periods.explicit_periods.push_back(r.Double("periods.explicit"));
  }
  info.max_order = static_cast<uint32_t>(r.Varint("max_order"));
  info.persistence = r.Byte("persistence") != 0;
  info.error_half_life = r.Double("error_half_life");
  info.criterion = static_cast<model::ErrorCriterion>(r.Byte("criterion"));
  info.lossless_sampling_period = r.Double("lossless_sampling_period");
  info.lossless_origin = r.Double("lossless_origin");
  info.shards = static_cast<uint32_t>(r.Varint("shards"));
  info.created_unix = model::ZigZagDecode64(r.Varint("created"));
  if (version == kMapInfoVersionWithoutOrderRule) {
    info.order_rule = model::OrderRule{model::OrderSelection::kMargin, model::kDefaultOrderMargin};
  } else {
    info.order_rule.selection = static_cast<model::OrderSelection>(r.Byte("order_selection"));
    info.order_rule.margin = r.Double("order_margin");
    info.order_rule.temperature = r.Double("order_temperature");
  }
  if (absl::Status s = r.Finish(); !s.ok()) return s;
  if (absl::Status s = ValidateMapInfo(info); !s.ok()) {
    return absl::DataLossError(absl::StrCat("map info: stored record is invalid: ", s.message()));
  }
  return info;
}

}  // namespace fremen::storage
