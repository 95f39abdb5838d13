#include "storage/model/lossless/bin_model.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>

#include "absl/strings/str_cat.h"
#include "storage/model/kernels/cpu_dispatch.h"
#include "storage/model/model_settings.h"

namespace fremen::model {

namespace {

// The split of an angle index r < n into coarse and fine parts: b = ⌈bit_width(n)/2⌉ fine bits keeps
// both tables near √n entries. Part of the record format: the rounding depends on it.
int FineBits(uint64_t n) { return (std::bit_width(n) + 1) / 2; }

// k·slot mod n, the angle index of bin k at `slot`. k < n < 2^32, so the product fits.
uint64_t AngleIndex(uint64_t k, uint64_t slot, uint64_t n) { return k * (slot % n) % n; }

// One component's term, accumulated in a fixed order with explicit fma: v + a·cos − b·sin.
inline double AddTerm(double v, const BinComponent& c, UnitPhasor ph) {
  v = std::fma(static_cast<double>(c.a), ph.cos, v);
  return std::fma(-static_cast<double>(c.b), ph.sin, v);
}

// Components kept while scanning bins: the best `capacity` by power, ties to the lower bin.
struct Best {
  size_t k;
  double power;
};

}  // namespace

double BinComponent::amplitude() const { return std::hypot(static_cast<double>(a), static_cast<double>(b)); }
double BinComponent::phase() const { return std::atan2(static_cast<double>(b), static_cast<double>(a)); }

BinModel BinModel::FromSpectrum(const SlotSpectrum& spectrum, uint64_t span, int max_order) {
  BinModel model;
  const uint64_t n = spectrum.length();
  model.length_ = n;
  model.alpha0_ = static_cast<float>(spectrum.gamma0());
  if (spectrum.observed() == 0 || max_order <= 0) return model;

  // Bins scanned in increasing k and inserted only when strictly stronger, so ties keep the lower k.
  std::vector<Best> best;
  best.reserve(max_order + 1);
  const size_t capacity = static_cast<size_t>(max_order);
  for (size_t k = 1; k <= n / 2; ++k) {
    // Period n/k slots must not exceed 2/3 of the span: 3n ≤ 2k·span (exact in integers).
    if (3 * n > 2 * k * span) continue;
    // All powers 0: no later bin is strictly stronger, so the first `capacity` eligible bins stay.
    if (best.size() == capacity && spectrum.all_zero()) break;
    const double power = spectrum.power(k);
    if (best.size() == capacity && !(power > best.back().power)) continue;
    auto at = std::upper_bound(best.begin(), best.end(), power,
                               [](double p, const Best& b) { return p > b.power; });
    best.insert(at, Best{k, power});
    if (best.size() > capacity) best.pop_back();
  }
  for (const Best& b : best) {
    // One-sided amplitude 2|γ|; the Nyquist bin has no mirror image to fold in.
    const double factor = (2 * b.k == n) ? 1.0 : 2.0;
    const std::complex<double> g = factor * spectrum.gamma(b.k);
    model.components_.push_back(
        {static_cast<uint32_t>(b.k), static_cast<float>(g.real()), static_cast<float>(g.imag())});
  }
  model.order_ = static_cast<uint8_t>(model.components_.size());
  return model;
}

double BinModel::SlotValue(uint64_t slot, int order) const {
  const size_t used = std::min(order < 0 ? order_ : static_cast<size_t>(order), components_.size());
  double v = alpha0_;
  if (used == 0) return v;
  const int fine_bits = FineBits(length_);
  const uint64_t fine_mask = (uint64_t{1} << fine_bits) - 1;
  for (size_t j = 0; j < used; ++j) {
    const uint64_t r = AngleIndex(components_[j].k, slot, length_);
    const UnitPhasor ph = Rotate(BinPhasor(r & ~fine_mask, length_), BinPhasor(r & fine_mask, length_));
    v = AddTerm(v, components_[j], ph);
  }
  return v;
}

bool BinModel::IsConstant(int order) const {
  const size_t used = std::min(order < 0 ? order_ : static_cast<size_t>(order), components_.size());
  return std::all_of(components_.begin(), components_.begin() + used,
                     [](const BinComponent& c) { return c.a == 0 && c.b == 0; });
}

double BinModel::Predict(double x, int order) const {
  const size_t used = std::min(order < 0 ? order_ : static_cast<size_t>(order), components_.size());
  double v = alpha0_;
  for (size_t j = 0; j < used; ++j) {
    const BinComponent& c = components_[j];
    // Range-reduce k·x modulo n before scaling (fmod is exact), as for ReducedPhase.
    const double angle =
        2.0 * std::numbers::pi * (std::fmod(c.k * x, static_cast<double>(length_)) / static_cast<double>(length_));
    v += c.a * std::cos(angle) - c.b * std::sin(angle);
  }
  return std::clamp(v, 0.0, 1.0);
}

size_t BinModel::encoded_size() const {
  if (length_ == 0) return 1;
  size_t size = Varint64Length(length_) + 4 + 1 + Varint64Length(components_.size());
  for (const BinComponent& c : components_) size += Varint64Length(c.k) + 8;
  return size;
}

void BinModel::EncodeTo(std::string* out) const {
  PutVarint64(out, length_);
  if (length_ == 0) return;  // no model yet: nothing else to say
  PutFloat(out, alpha0_);
  out->push_back(static_cast<char>(order_));
  PutVarint64(out, components_.size());
  for (const BinComponent& c : components_) {
    PutVarint64(out, c.k);
    PutFloat(out, c.a);
    PutFloat(out, c.b);
  }
}

BinModel BinModel::Decode(ByteReader& reader, std::string_view field) {
  BinModel model;
  model.length_ = reader.Varint(std::string(field) + " length");
  if (!reader.ok() || model.length_ == 0) return BinModel();
  if (model.length_ > kMaxBinLength) {
    reader.Fail(field, absl::StrCat("length ", model.length_, " exceeds ", kMaxBinLength));
    return BinModel();
  }
  model.alpha0_ = reader.Float(std::string(field) + " alpha0");
  const uint8_t order = reader.Byte(std::string(field) + " order");
  const uint64_t count = reader.Varint(std::string(field) + " component count");
  if (!reader.ok()) return BinModel();
  if (!(model.alpha0_ >= 0 && model.alpha0_ <= 1)) {
    reader.Fail(field, absl::StrCat("alpha0 ", model.alpha0_, " is not in [0, 1]"));
  } else if (count > static_cast<uint64_t>(kMaxMaxOrder)) {
    reader.Fail(field, absl::StrCat("component count ", count, " exceeds ", kMaxMaxOrder));
  } else if (order > count) {
    reader.Fail(field, absl::StrCat("order ", int{order}, " exceeds the ", count, " components held"));
  }
  if (!reader.ok()) return BinModel();
  model.order_ = order;
  const std::string component_field = std::string(field) + " component";
  for (uint64_t j = 0; j < count && reader.ok(); ++j) {
    BinComponent c;
    const uint64_t k = reader.Varint(component_field);
    c.a = reader.Float(component_field);
    c.b = reader.Float(component_field);
    if (!reader.ok()) break;
    if (k == 0 || k > model.length_ / 2) {
      reader.Fail(component_field, absl::StrCat(j, ": bin ", k, " is not in [1, ", model.length_ / 2, "]"));
    } else if (!std::isfinite(c.a) || !std::isfinite(c.b)) {
      reader.Fail(component_field, absl::StrCat(j, ": coefficients are not finite"));
    }
    c.k = static_cast<uint32_t>(k);
    model.components_.push_back(c);
  }
  if (!reader.ok()) return BinModel();
  return model;
}

SlotPredictor::SlotPredictor(const BinModel& model) : model_(model) {
  const uint64_t n = model.length();
  if (n == 0 || model.components().empty()) return;
  fine_bits_ = FineBits(n);
  const uint64_t fine_size = std::min<uint64_t>(uint64_t{1} << fine_bits_, n);
  fine_.resize(fine_size);
  for (uint64_t f = 0; f < fine_size; ++f) fine_[f] = BinPhasor(f, n);
  coarse_.resize(((n - 1) >> fine_bits_) + 1);
  for (uint64_t q = 0; q < coarse_.size(); ++q) coarse_[q] = BinPhasor(q << fine_bits_, n);
}

// Cloned for FMA (cpu_dispatch.h): the order scoring evaluates every slot since the last update here.
FREMEN_FMA_CLONES void SlotPredictor::AddComponent(size_t j, uint64_t begin, std::span<double> out) const {
  const BinComponent& c = model_.components()[j];
  const uint64_t n = model_.length();
  const uint64_t k = c.k;
  const uint64_t fine_mask = (uint64_t{1} << fine_bits_) - 1;
  const UnitPhasor* coarse = coarse_.data();
  const UnitPhasor* fine = fine_.data();
  uint64_t r = AngleIndex(k, begin, n);
  for (double& v : out) {
    v = AddTerm(v, c, Rotate(coarse[r >> fine_bits_], fine[r & fine_mask]));
    r += k;
    if (r >= n) r -= n;
  }
}

void SlotPredictor::Values(uint64_t begin, int order, std::span<double> out) const {
  std::fill(out.begin(), out.end(), static_cast<double>(model_.alpha0()));
  for (int j = 0; j < order; ++j) AddComponent(j, begin, out);
}

void SlotPredictor::CountErrors(uint64_t begin, std::span<const SlotState> truth, std::span<uint64_t> errors) const {
  if (errors.empty()) return;
  const size_t held = std::min(model_.components().size(), errors.size() - 1);
  // Chunks keep the running values in L1 while each component is added in turn.
  constexpr size_t kChunk = 2048;
  double values[kChunk];
  for (size_t at = 0; at < truth.size(); at += kChunk) {
    const size_t count = std::min(kChunk, truth.size() - at);
    const std::span<double> v(values, count);
    const std::span<const SlotState> t = truth.subspan(at, count);
    std::fill(v.begin(), v.end(), static_cast<double>(model_.alpha0()));
    for (size_t l = 0;; ++l) {
      uint64_t wrong = 0;
      for (size_t i = 0; i < count; ++i) {
        if (t[i] == SlotState::kUnobserved) continue;
        wrong += (v[i] >= 0.5) != (t[i] == SlotState::kOccupied);
      }
      errors[l] += wrong;
      if (l == held) {
        for (size_t above = l + 1; above < errors.size(); ++above) errors[above] += wrong;
        break;
      }
      AddComponent(l, begin + at, v);
    }
  }
}

}  // namespace fremen::model
