#include "storage/model/lossless/lossless_history.h"

#include <algorithm>
#include <cmath>
#include <optional>

#include "absl/strings/str_cat.h"
#include "storage/model/lossless/slot_estimator.h"
#include "storage/model/model_settings.h"
#include "storage/model/observation.h"

namespace fremen::model {

namespace {

// Slots estimated per step: the estimates stay in L1.
constexpr size_t kChunk = SlotEstimator::kChunk;

}  // namespace

absl::StatusOr<LosslessHistory> LosslessHistory::Create(double t0, double delta) {
  if (!std::isfinite(t0) || std::fabs(t0) > kMaxAbsTime) {
    return absl::InvalidArgumentError(absl::StrCat("t0 must be a finite time within ±1e13 s, got ", t0));
  }
  if (!std::isfinite(delta) || delta <= 0) {
    return absl::InvalidArgumentError(absl::StrCat("sampling period must be a positive number of seconds, got ", delta));
  }
  return LosslessHistory(t0, delta);
}

absl::StatusOr<uint64_t> LosslessHistory::SlotOf(double t) const {
  if (!std::isfinite(t) || std::fabs(t) > kMaxAbsTime) {
    return absl::InvalidArgumentError(absl::StrCat("t must be a finite time within ±1e13 s, got ", t));
  }
  if (t < t0_) {
    return absl::InvalidArgumentError(absl::StrCat("t = ", t, " is before the history's origin t0 = ", t0_));
  }
  const double slot = std::floor((t - t0_) / delta_);
  if (slot >= static_cast<double>(kMaxSlots)) {
    return absl::OutOfRangeError(absl::StrCat("t = ", t, " is slot ", slot, ", beyond the history's ", kMaxSlots,
                                              " slots of ", delta_, " s from t0 = ", t0_));
  }
  return static_cast<uint64_t>(slot);
}

absl::Status LosslessHistory::Add(double t, float s) {
  if (!(s >= 0.0f && s <= 1.0f)) {
    return absl::InvalidArgumentError(absl::StrCat("s must be in [0, 1], got ", s));
  }
  const absl::StatusOr<uint64_t> slot = SlotOf(t);
  if (!slot.ok()) return slot.status();
  return AddSlot(*slot, s >= 0.5f);
}

absl::Status LosslessHistory::AddSlot(uint64_t slot, bool s) {
  if (slot >= kMaxSlots) {
    return absl::OutOfRangeError(absl::StrCat("slot ", slot, " is beyond the history's ", kMaxSlots, " slots"));
  }
  const uint64_t m = slot_count();
  // Eq. 7 for the slot as it stands, eq. 8 if it differs.
  const bool reconstructed = model_.SlotEstimate(slot) != outliers_.contains(slot);
  if (reconstructed != s) {
    if (slot + 1 >= m) {
      // Nothing observed lies beyond: flipping the open tail is eq. 8's Δ-encoding, one point per
      // change of agreement, O(1).
      outliers_.Toggle(slot);
    } else {
      // A late or repeated observation among later ones: this slot alone.
      outliers_.Flip(slot);
    }
  }
  coverage_.Insert(slot);
  return absl::OkStatus();
}

absl::StatusOr<std::vector<SlotState>> LosslessHistory::Reconstruct(uint64_t begin, uint64_t end) const {
  if (begin > end || end > kMaxSlots) {
    return absl::InvalidArgumentError(
        absl::StrCat("slot range [", begin, ", ", end, ") must be ordered and end at most ", kMaxSlots));
  }
  std::vector<SlotState> out(end - begin);
  ReconstructInto(begin, out);
  return out;
}

void LosslessHistory::ReconstructInto(uint64_t begin, std::span<SlotState> out) const {
  std::fill(out.begin(), out.end(), SlotState::kUnobserved);
  const uint64_t limit = std::min<uint64_t>(begin + out.size(), slot_count());
  if (begin >= limit) return;
  const SlotEstimator estimator(model_);
  SlotSet::Cursor covered(coverage_), outlier(outliers_);
  bool estimates[kChunk];
  uint64_t x = begin;
  while (x < limit) {
    const bool observed = covered.Seek(x);
    const uint64_t run_end = std::min(covered.next_change(), limit);
    if (!observed) {
      x = run_end;
      continue;
    }
    for (uint64_t chunk = x; chunk < run_end; chunk += kChunk) {
      const uint64_t chunk_end = std::min<uint64_t>(chunk + kChunk, run_end);
      estimator.Estimates(chunk, std::span<bool>(estimates, chunk_end - chunk));
      for (uint64_t y = chunk; y < chunk_end;) {
        const bool flip = outlier.Seek(y);
        const uint64_t o_end = std::min(outlier.next_change(), chunk_end);
        for (; y < o_end; ++y) {
          const bool state = estimates[y - chunk] != flip;
          out[y - begin] = state ? SlotState::kOccupied : SlotState::kFree;
        }
      }
    }
    x = run_end;
  }
}

double LosslessHistory::Predict(double t, int order) const {
  return model_.Predict((t - t0_) / delta_, order);
}

absl::StatusOr<int> LosslessHistory::Update(int max_order, std::optional<int> order) {
  if (max_order < 0 || max_order > kMaxMaxOrder) {
    return absl::InvalidArgumentError(absl::StrCat("max_order must be in [0, ", kMaxMaxOrder, "], got ", max_order));
  }
  if (order && (*order < 0 || *order > max_order)) {
    return absl::InvalidArgumentError(absl::StrCat("order must be in [0, max_order = ", max_order, "], got ", *order));
  }
  const uint64_t m = slot_count();
  if (m == 0) return model_.order();

  // A constant history (a wall, a floor: most cells of a building) is updated from its toggle
  // points alone: no slot is reconstructed, transformed or evaluated.
  const std::optional<bool> constant = ConstantSignal();
  std::vector<SlotState> signal;
  if (!constant) {
    signal.resize(m);
    ReconstructInto(0, signal);
  }

  // The published P scores the orders on what it had not seen, before it is replaced
  // (docs/model.md, "Order selection").
  // A P without components (the first update, or nothing was eligible then) predicted nothing
  // worth scoring: the new components are scored on all data instead.
  std::vector<uint64_t> errors(max_order + 1, 0);
  const bool can_predict = !model_.components().empty();
  const bool seen_since = coverage_.Count(update_slot_, m) > 0;
  if (!order && can_predict && seen_since) ScoreSinceUpdate(signal, errors);

  const uint64_t observed = constant ? coverage_.Count(0, m) : 0;
  const SlotSpectrum spectrum = constant ? SlotSpectrum::Constant(m, observed, *constant) : SlotSpectrum::Compute(signal);
  const uint64_t first = coverage_.first_point();
  BinModel next = BinModel::FromSpectrum(spectrum, m - 1 - first, max_order);

  int chosen = 0;
  if (order) {
    chosen = *order;
  } else if (can_predict && !seen_since) {
    chosen = model_.order();  // nothing new to judge by
  } else {
    // A constant signal's new components all have zero amplitude: every order scores alike.
    if (!can_predict && !constant) SlotPredictor(next).CountErrors(0, signal, errors);
    // The first minimum: ties go to the lower order.
    chosen = static_cast<int>(std::min_element(errors.begin(), errors.end()) - errors.begin());
  }
  chosen = std::min<int>(chosen, static_cast<int>(next.components().size()));
  next.set_order(chosen);

  model_ = std::move(next);
  if (constant) {
    // P is α0 = the constant at every slot (its components have zero amplitude): nothing is wrong.
    outliers_.Clear();
  } else {
    RebuildOutliers(signal);
  }
  update_slot_ = m;
  return chosen;
}

std::optional<bool> LosslessHistory::ConstantSignal() const {
  if (!model_.IsConstant()) return std::nullopt;  // s' varies: only the slots can tell
  const uint64_t m = slot_count();
  const bool estimate = model_.alpha0() >= 0.5;
  const uint64_t wrong = CountCommon(outliers_, coverage_, 0, m);
  if (wrong == 0) return estimate;
  if (wrong == coverage_.Count(0, m)) return !estimate;
  return std::nullopt;
}

void LosslessHistory::ScoreSinceUpdate(std::span<const SlotState> signal, std::span<uint64_t> errors) const {
  const uint64_t m = slot_count();
  const int held = std::min<int>(static_cast<int>(model_.components().size()), static_cast<int>(errors.size()) - 1);
  // Components of zero amplitude leave p at α0 at every order: all orders score alike.
  if (signal.empty() && model_.IsConstant(held)) return;
  std::vector<SlotState> tail;
  std::span<const SlotState> since;
  if (signal.empty()) {
    tail.resize(m - update_slot_);
    ReconstructInto(update_slot_, tail);
    since = tail;
  } else {
    since = signal.subspan(update_slot_);
  }
  SlotPredictor(model_).CountErrors(update_slot_, since, errors);
}

void LosslessHistory::RebuildOutliers(std::span<const SlotState> signal) {
  SlotSet rebuilt;
  bool in_outliers = false;
  const SlotEstimator estimator(model_);
  bool estimates[kChunk];
  for (uint64_t chunk = 0; chunk < signal.size(); chunk += kChunk) {
    const size_t count = std::min<uint64_t>(kChunk, signal.size() - chunk);
    estimator.Estimates(chunk, std::span<bool>(estimates, count));
    for (size_t i = 0; i < count; ++i) {
      const SlotState s = signal[chunk + i];
      if (s == SlotState::kUnobserved) continue;
      // A toggle only where agreement changes between consecutive observations (eq. 8).
      const bool wrong = estimates[i] != (s == SlotState::kOccupied);
      if (wrong != in_outliers) {
        rebuilt.Toggle(chunk + i);
        in_outliers = wrong;
      }
    }
  }
  outliers_ = std::move(rebuilt);
}

LosslessHistory::Error LosslessHistory::ErrorBetween(uint64_t begin, uint64_t end) const {
  return {CountCommon(outliers_, coverage_, begin, end), coverage_.Count(begin, end)};
}

double LosslessHistory::Compression::ratio() const {
  const size_t bytes = model_bytes + outlier_bytes;
  return bytes > 0 ? static_cast<double>(raw_bits) / (8.0 * static_cast<double>(bytes)) : 0.0;
}

LosslessHistory::Compression LosslessHistory::CompressionFigures() const {
  Compression c;
  c.model_bytes = model_.encoded_size();
  c.outlier_bytes = outliers_.encoded_size();
  c.coverage_bytes = coverage_.encoded_size();
  c.record_bytes = encoded_size();
  c.raw_bits = slot_count();
  return c;
}

size_t LosslessHistory::encoded_size() const {
  return 1 + 8 + 8 + Varint64Length(update_slot_) + model_.encoded_size() + coverage_.encoded_size() +
         outliers_.encoded_size();
}

void LosslessHistory::EncodeTo(std::string* out) const {
  out->push_back(static_cast<char>(kFormatVersion));
  PutDouble(out, t0_);
  PutDouble(out, delta_);
  PutVarint64(out, update_slot_);
  model_.EncodeTo(out);
  coverage_.EncodeTo(out);
  outliers_.EncodeTo(out);
}

std::string LosslessHistory::Encode() const {
  std::string out;
  out.reserve(encoded_size());
  EncodeTo(&out);
  return out;
}

absl::StatusOr<LosslessHistory> LosslessHistory::Decode(std::string_view bytes) {
  ByteReader reader(bytes, "lossless history");
  const uint8_t version = reader.Byte("version");
  if (reader.ok() && version != kFormatVersion) {
    reader.Fail("version", absl::StrCat("unsupported version ", int{version}, " (expected ", int{kFormatVersion}, ")"));
  }
  const double t0 = reader.Double("t0");
  const double delta = reader.Double("delta");
  if (reader.ok() && (!std::isfinite(t0) || std::fabs(t0) > kMaxAbsTime)) {
    reader.Fail("t0", absl::StrCat(t0, " is not a finite time within ±1e13 s"));
  }
  if (reader.ok() && !(std::isfinite(delta) && delta > 0)) {
    reader.Fail("delta", absl::StrCat(delta, " is not a positive number of seconds"));
  }
  LosslessHistory history(t0, delta);
  history.update_slot_ = reader.Varint("update slot");
  history.model_ = BinModel::Decode(reader, "model");
  history.coverage_ = SlotSet::Decode(reader, "coverage");
  if (reader.ok() && history.coverage_.open()) reader.Fail("coverage", "ends with an open interval");
  const uint64_t m = history.slot_count();
  if (reader.ok() && m > kMaxSlots) reader.Fail("coverage", absl::StrCat("spans ", m, " slots, more than ", kMaxSlots));
  if (reader.ok() && history.update_slot_ > m) {
    reader.Fail("update slot", absl::StrCat(history.update_slot_, " is after the last observed slot ", m));
  }
  if (reader.ok() && history.model_.length() > m) {
    reader.Fail("model", absl::StrCat("length ", history.model_.length(), " exceeds the ", m, " slots observed"));
  }
  history.outliers_ = SlotSet::Decode(reader, "outliers");
  if (reader.ok() && !history.outliers_.empty() && history.outliers_.last_point() > m) {
    reader.Fail("outliers", absl::StrCat("toggle point ", history.outliers_.last_point(), " is after the ", m,
                                         " slots observed"));
  }
  if (absl::Status s = reader.Finish(); !s.ok()) return s;
  return history;
}

}  // namespace fremen::model
