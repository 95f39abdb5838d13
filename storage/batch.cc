#include "storage/batch.h"

#include <xxhash.h>

#include <bit>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "storage/cell_key.h"
#include "storage/model/observation.h"
#include "storage/model/varint.h"

namespace fremen::storage {

namespace {
constexpr uint8_t kBatchVersion = 1;         // a scan
constexpr uint8_t kCompactBatchVersion = 2;  // compact cells instead of keys and values
constexpr uint8_t kHistoryVersion = 3;       // a history: version 1's fields, then the times
constexpr uint8_t kCompactOccupied = 0, kCompactProbabilities = 1;
// A batch is one message of at most a few hundred MB; more observations than this is corruption.
constexpr uint64_t kMaxBatchObservations = 1ull << 28;

bool ValueOk(float v) { return v >= 0.0f && v <= 1.0f; }  // false for NaN
}  // namespace

namespace {
absl::Status ValidateHistory(const MapInfo& map, const ObservationBatch& batch) {
  if (map.kind != MapKind::kGeneric) return absl::InvalidArgumentError("a history (times) is only for generic maps");
  if (batch.time != 0) {
    return absl::InvalidArgumentError(absl::StrCat(
        "time must be 0 for a history, whose observations carry their own times; got ", batch.time));
  }
  if (batch.times.size() != batch.keys.size()) {
    return absl::InvalidArgumentError(absl::StrCat("times must hold one time per state: ", batch.times.size(),
                                                   " times for ", batch.keys.size(), " states"));
  }
  if (batch.patch.values.size() > 0) return absl::InvalidArgumentError("a history has no patch");
  for (size_t i = 0; i < batch.times.size(); ++i) {
    // The loop's common case is one comparison pair; the message is built only for a bad time.
    if (!(batch.times[i] >= 0.0 && batch.times[i] <= model::kMaxAbsTime)) {
      return CheckTime(batch.times[i], absl::StrCat("times[", i, "]"));
    }
  }
  return absl::OkStatus();
}
}  // namespace

absl::Status CheckTime(double t, absl::string_view field) {
  // Written so that NaN fails too.
  if (t >= 0.0 && t <= model::kMaxAbsTime) return absl::OkStatus();
  return absl::InvalidArgumentError(
      absl::StrCat(field, " must be a time in seconds since the Unix epoch, finite, in [0, 1e13]; got ", t));
}

absl::Status ValidateBatch(const MapInfo& map, const ObservationBatch& batch) {
  if (absl::Status s = CheckTime(batch.time, "time"); !s.ok()) return s;
  if (batch.keys.size() != batch.values.size()) {
    return absl::InvalidArgumentError(absl::StrCat("values must hold one value per state: ", batch.values.size(),
                                                   " values for ", batch.keys.size(), " states"));
  }
  if (!batch.compact.empty() && batch.keys.empty()) {
    return absl::InternalError("compact cells must be expanded (ExpandCompact) before the batch is submitted");
  }
  const DensePatch& patch = batch.patch;
  const uint64_t patch_cells = uint64_t{patch.size[0]} * patch.size[1] * patch.size[2];
  if (patch_cells != patch.values.size()) {
    return absl::InvalidArgumentError(absl::StrCat("patch.values must hold size.x·size.y·size.z = ", patch_cells,
                                                   " values, got ", patch.values.size()));
  }
  if (batch.observation_count() > kMaxBatchObservations) {
    return absl::InvalidArgumentError(absl::StrCat("a batch may hold at most 2^28 observations, got ",
                                                   batch.observation_count()));
  }
  if (batch.is_history()) {
    if (absl::Status s = ValidateHistory(map, batch); !s.ok()) return s;
  }
  if (patch_cells > 0) {
    if (map.kind != MapKind::kGrid) return absl::InvalidArgumentError("patch is only for grid maps");
    static constexpr const char* kAxes[3] = {"x", "y", "z"};
    for (int a = 0; a < 3; ++a) {
      if (uint64_t{patch.origin[a]} + patch.size[a] > map.grid.size[a]) {
        return absl::OutOfRangeError(absl::StrCat("patch along ", kAxes[a], " covers cells ", patch.origin[a], "..",
                                                  uint64_t{patch.origin[a]} + patch.size[a] - 1,
                                                  ", outside the grid's 0..", map.grid.size[a] - 1));
      }
    }
  }
  if (!batch.labels.empty() && map.kind != MapKind::kGeneric) {
    return absl::InvalidArgumentError("labels (names and groups) are only for generic maps");
  }
  for (size_t i = 0; i < batch.labels.size(); ++i) {
    if (batch.labels[i].name.size() > kMaxLabelLength || batch.labels[i].group.size() > kMaxLabelLength) {
      return absl::InvalidArgumentError(absl::StrCat("labels[", i, "]: name and group may be at most 256 bytes"));
    }
  }
  return absl::OkStatus();
}

absl::Status ExpandCompact(const MapInfo& map, ObservationBatch& batch) {
  if (batch.compact.empty()) return absl::OkStatus();
  if (map.kind != MapKind::kGrid) return absl::InvalidArgumentError("compact cells are only for grid maps");
  size_t outside = 0;
  absl::Status expanded =
      ExpandCompactCells(map.grid, batch.compact, kMaxBatchObservations, batch.keys, batch.values, &outside);
  batch.keys_from_grid.set = expanded.ok();
  if (expanded.ok()) batch.keys_from_grid.outside = outside;
  return expanded;
}

BatchAck Classify(const MapInfo& map, const ObservationBatch& batch, std::vector<uint8_t>& accept) {
  BatchAck ack;
  ack.sequence = batch.sequence;
  accept.assign(batch.observation_count(), 1);
  const auto reject = [&](size_t i, RejectReason reason) {
    accept[i] = 0;
    ++ack.rejected;
    if (ack.rejections.size() < kMaxReportedRejections) ack.rejections.push_back({static_cast<uint32_t>(i), reason});
  };
  const GridKeys keys = map.grid.keys();
  const bool from_grid = map.kind == MapKind::kGrid && batch.keys_from_grid.set;
  // Keys made from cell indices and values in range, the usual batch, are checked in one
  // branch-free pass that the compiler vectorises; only a batch with something to reject takes the
  // loop that says what and where.
  // A compact scan's expansion counted its keys past the grid, and values expanded from its
  // occupied bits are 0 or 1 by construction: nothing to read (office workload under callgrind:
  // Classify 13 instructions a cell checking keys and values, 3 reading the keys, none now).
  size_t bad = 0;
  const bool values_from_bits =
      from_grid && batch.keys_from_grid.outside.has_value() && batch.compact.probabilities.empty();
  if (values_from_bits) {
    bad = *batch.keys_from_grid.outside;
  } else if (from_grid) {
    for (size_t i = 0; i < batch.keys.size(); ++i) {
      bad += static_cast<size_t>(!ValueOk(batch.values[i])) | static_cast<size_t>(batch.keys[i] == kNotACellKey);
    }
  }
  const bool check_each = !from_grid || bad > 0;
  for (size_t i = 0; check_each && i < batch.keys.size(); ++i) {
    if (!ValueOk(batch.values[i])) {
      reject(i, RejectReason::kValueOutOfRange);
    } else if (from_grid) {
      if (batch.keys[i] == kNotACellKey) reject(i, RejectReason::kOutsideMap);
    } else if (map.kind == MapKind::kGrid) {
      const auto cell = keys.Cell(batch.keys[i]);
      if (!keys.IsCellKey(batch.keys[i]) || !map.grid.Contains(cell[0], cell[1], cell[2])) {
        reject(i, RejectReason::kOutsideMap);
      }
    }
  }
  for (size_t j = 0; j < batch.patch.values.size(); ++j) {
    if (!ValueOk(batch.patch.values[j])) reject(batch.keys.size() + j, RejectReason::kValueOutOfRange);
  }
  ack.accepted = accept.size() - ack.rejected;
  return ack;
}

namespace {

void PutBytes(std::string* out, std::string_view bytes) {
  model::PutVarint64(out, bytes.size());
  out->append(bytes);
}

// What follows the keys and values in both versions: the patch and the labels.
void EncodePatchAndLabels(const ObservationBatch& batch, std::string& out) {
  for (uint32_t o : batch.patch.origin) model::PutVarint64(&out, o);
  for (uint32_t s : batch.patch.size) model::PutVarint64(&out, s);
  model::PutFloats(&out, batch.patch.values);
  model::PutVarint64(&out, batch.labels.size());
  for (const StateLabel& label : batch.labels) {
    model::PutVarint64(&out, label.key);
    PutBytes(&out, label.name);
    PutBytes(&out, label.group);
  }
}

uint64_t BitsOf(double t) { return std::bit_cast<uint64_t>(t); }

void PutTimes(std::string* out, const std::vector<double>& times) {
  const size_t at = out->size();
  out->resize(at + times.size() * model::kMaxVarint64Bytes);
  char* end = out->data() + at;
  uint64_t previous = 0, previous_delta = 0;
  for (double t : times) {
    const uint64_t bits = BitsOf(t);
    const uint64_t delta = bits - previous;  // wraps: exact in modular arithmetic
    end = model::EncodeVarint64(end, model::ZigZagEncode64(static_cast<int64_t>(delta - previous_delta)));
    previous = bits;
    previous_delta = delta;
  }
  out->resize(end - out->data());
}
}  // namespace

// Layout (version 1, a scan): version u8 | writer varint | sequence varint | time f64 |
// key count varint | keys (delta-zigzag varints: scans are spatially sorted, so deltas are small) |
// values f32 each | patch origin 3×varint | patch size 3×varint | patch values f32 each |
// label count varint | labels (key varint, name, group as length-prefixed bytes).
// Version 2 (compact cells): version u8 | writer | sequence | time | compact.indices as
// length-prefixed bytes | value kind u8 (0 occupied bits, 1 probability bytes) | the values as
// length-prefixed bytes | then as version 1 from the patch on.
// Version 3, a history: as version 1, then one time per key, as the zigzag varints of the second
// differences of the times' IEEE-754 bits (integer arithmetic modulo 2^64, starting from 0): exact
// for any doubles, and a log sampled at a steady rate (a minute apart: the bits of times of one
// binade step by the same integer) takes a byte a time instead of 8; an irregular one 4-5 bytes.
// One state's history's keys, all the same, take a byte each.
std::string EncodeBatch(const ObservationBatch& batch) {
  std::string out;
  const bool compact = !batch.compact.empty();
  out.reserve(32 +
              (compact ? batch.compact.indices.size() + batch.compact.occupied.size() +
                             batch.compact.probabilities.size()
                       : (batch.keys.size() + batch.times.size()) * model::kMaxVarint64Bytes + batch.keys.size() * 4) +
              batch.patch.values.size() * 4);
  out.push_back(static_cast<char>(compact ? kCompactBatchVersion : batch.is_history() ? kHistoryVersion : kBatchVersion));
  model::PutVarint64(&out, batch.writer_id);
  model::PutVarint64(&out, batch.sequence);
  model::PutDouble(&out, batch.time);
  if (compact) {
    const bool soft = !batch.compact.probabilities.empty();
    PutBytes(&out, batch.compact.indices);
    out.push_back(static_cast<char>(soft ? kCompactProbabilities : kCompactOccupied));
    PutBytes(&out, soft ? batch.compact.probabilities : batch.compact.occupied);
    EncodePatchAndLabels(batch, out);
    return out;
  }
  model::PutVarint64(&out, batch.keys.size());
  // The keys' deltas into room for the longest varints, then cut to what they took.
  const size_t keys_at = out.size();
  out.resize(keys_at + batch.keys.size() * model::kMaxVarint64Bytes);
  char* end = out.data() + keys_at;
  uint64_t previous = 0;
  for (uint64_t key : batch.keys) {
    end = model::EncodeVarint64(end, model::ZigZagEncode64(static_cast<int64_t>(key - previous)));
    previous = key;
  }
  out.resize(end - out.data());
  model::PutFloats(&out, batch.values);
  EncodePatchAndLabels(batch, out);
  if (batch.is_history()) PutTimes(&out, batch.times);
  return out;
}

absl::StatusOr<ObservationBatch> DecodeBatch(std::string_view bytes) {
  model::ByteReader r(bytes, "batch");
  ObservationBatch batch;
  const uint8_t version = r.Byte("version");
  if (r.ok() && version != kBatchVersion && version != kCompactBatchVersion && version != kHistoryVersion) {
    r.Fail("version", absl::StrCat("unknown version ", version));
  }
  batch.writer_id = r.Varint("writer_id");
  batch.sequence = r.Varint("sequence");
  batch.time = r.Double("time");
  if (version == kCompactBatchVersion) {
    const uint64_t indices_length = r.Varint("compact.indices length");
    batch.compact.indices = std::string(r.Bytes(indices_length, "compact.indices"));
    const uint8_t kind = r.Byte("compact value kind");
    if (r.ok() && kind != kCompactOccupied && kind != kCompactProbabilities) {
      r.Fail("compact value kind", absl::StrCat("unknown kind ", kind));
    }
    const uint64_t values_length = r.Varint("compact values length");
    // Empty probabilities re-encode as empty bits: refused, so that every record round-trips.
    if (r.ok() && kind == kCompactProbabilities && values_length == 0) r.Fail("compact values length", "0 probabilities");
    (kind == kCompactProbabilities ? batch.compact.probabilities : batch.compact.occupied) =
        std::string(r.Bytes(values_length, "compact values"));
    // A compact batch of no cells is logged as version 1; encoded so, it would not round-trip.
    if (r.ok() && batch.compact.empty()) r.Fail("compact.indices", "empty");
  }
  const uint64_t key_count = version == kCompactBatchVersion ? 0 : r.Varint("key count");
  // Each key takes at least one byte and its value four: a count beyond that is corruption.
  // (Divided, not multiplied: a count near 2^64 / 5 would wrap round to a small product.)
  if (r.ok() && key_count > r.remaining() / 5) r.Fail("key count", "more than the bytes left");
  batch.keys.resize(r.ok() ? key_count : 0);
  uint64_t previous = 0;
  for (uint64_t& key : batch.keys) {
    key = previous + static_cast<uint64_t>(model::ZigZagDecode64(r.Varint("key")));
    previous = key;
  }
  batch.values.resize(batch.keys.size());
  for (float& v : batch.values) v = r.Float("value");
  for (uint32_t& o : batch.patch.origin) o = static_cast<uint32_t>(r.Varint("patch.origin"));
  uint64_t cells = 1;
  for (uint32_t& s : batch.patch.size) {
    const uint64_t v = r.Varint("patch.size");
    if (r.ok() && v > kMaxGridIndex + 1) r.Fail("patch.size", "larger than a grid side");
    s = static_cast<uint32_t>(v);
    cells *= s;
  }
  // Three sides up to 2^21 + 1 make up to 2^63 cells, whose 4 bytes each would wrap a uint64_t.
  if (r.ok() && cells > r.remaining() / 4) r.Fail("patch.size", "more cells than the bytes left");
  batch.patch.values.resize(r.ok() ? cells : 0);
  for (float& v : batch.patch.values) v = r.Float("patch.value");
  const uint64_t label_count = r.Varint("label count");
  if (r.ok() && label_count * 3 > r.remaining()) r.Fail("label count", "more than the bytes left");
  for (uint64_t i = 0; r.ok() && i < label_count; ++i) {
    StateLabel label;
    label.key = r.Varint("label.key");
    const uint64_t name_length = r.Varint("label.name length");
    if (r.ok() && name_length > kMaxLabelLength) r.Fail("label.name length", "longer than 256");
    label.name = std::string(r.Bytes(r.ok() ? name_length : 0, "label.name"));
    const uint64_t group_length = r.Varint("label.group length");
    if (r.ok() && group_length > kMaxLabelLength) r.Fail("label.group length", "longer than 256");
    label.group = std::string(r.Bytes(r.ok() ? group_length : 0, "label.group"));
    batch.labels.push_back(std::move(label));
  }
  if (r.ok() && version == kHistoryVersion) {
    // One time per key, each at least a byte; a history without a time is no history.
    if (batch.keys.empty()) r.Fail("times", "a history without observations");
    if (r.ok() && batch.keys.size() > r.remaining()) r.Fail("times", "more than the bytes left");
    batch.times.resize(r.ok() ? batch.keys.size() : 0);
    uint64_t previous = 0, delta = 0;
    for (double& t : batch.times) {
      delta += static_cast<uint64_t>(model::ZigZagDecode64(r.Varint("time")));
      previous += delta;
      t = std::bit_cast<double>(previous);
    }
  }
  if (absl::Status s = r.Finish(); !s.ok()) return s;
  if (batch.observation_count() > kMaxBatchObservations) return absl::DataLossError("batch: too many observations");
  return batch;
}

uint64_t BatchFingerprint(std::string_view encoded) { return XXH3_64bits(encoded.data(), encoded.size()); }

}  // namespace fremen::storage
