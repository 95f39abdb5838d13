#include "storage/model/record_codec.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <type_traits>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "storage/model/observation.h"
#include "storage/model/varint.h"

namespace fremen::model {

namespace {

// ---- Record identities ------------------------------------------------------------------------

struct RecordKind {
  RecordTag tag;
  uint8_t version;
  const char* name;  // names the record in error messages
};

constexpr RecordKind kSpectrumRecord{RecordTag::kSpectrum, 1, "spectrum"};
constexpr RecordKind kPublishedModelRecord{RecordTag::kPublishedModel, 1, "published model"};
constexpr RecordKind kPersistenceRecord{RecordTag::kPersistence, 1, "persistence"};
constexpr RecordKind kOrderErrorsRecord{RecordTag::kOrderErrors, 1, "order errors"};
constexpr RecordKind kStaticStateRecord{RecordTag::kStaticState, 1, "static state"};
constexpr RecordKind kStateModelRecord{RecordTag::kStateModel, 1, "state model"};
constexpr RecordKind kRecordKinds[] = {kSpectrumRecord,    kPublishedModelRecord, kPersistenceRecord,
                                       kOrderErrorsRecord, kStaticStateRecord,    kStateModelRecord};

const RecordKind* FindKind(uint8_t tag) {
  for (const RecordKind& kind : kRecordKinds) {
    if (static_cast<uint8_t>(kind.tag) == tag) return &kind;
  }
  return nullptr;
}

void PutByte(std::string* out, uint8_t v) { out->push_back(static_cast<char>(v)); }

void PutPreamble(const RecordKind& kind, std::string* out) {
  PutByte(out, static_cast<uint8_t>(kind.tag));
  PutByte(out, kind.version);
}

void ReadPreamble(ByteReader& r, const RecordKind& kind) {
  const uint8_t tag = r.Byte("tag");
  if (r.ok() && tag != static_cast<uint8_t>(kind.tag)) {
    const RecordKind* actual = FindKind(tag);
    r.Fail("tag", actual != nullptr ? absl::StrCat("holds a ", actual->name, " record")
                                    : absl::StrCat("unknown record tag ", tag));
  }
  const uint8_t version = r.Byte("version");
  if (r.ok() && version != kind.version) {
    r.Fail("version", absl::StrCat("unknown format version ", version, " (this build reads ", kind.version, ")"));
  }
}

// ---- Checked values -----------------------------------------------------------------------------

// The closed interval a decoded value must lie in. Finite bounds only: a value read against a range
// is finite, and NaN fails every comparison.
struct Range {
  double lo, hi;
};

constexpr double kLargest = std::numeric_limits<double>::max();
constexpr Range kNonNegative{0, kLargest};
constexpr Range kUnit{0, 1};
constexpr Range kZero{0, 0};
constexpr Range kTime{-kMaxAbsTime, kMaxAbsTime};
// Running means of unit phasors (times s ∈ [0, 1]) lie in [−1, 1]. The slack covers rounding; the
// bound still catches the corrupted exponents that make most bit flips in a real implausible.
constexpr double kMeanBound = 1.01;
constexpr Range kMean{-kMeanBound, kMeanBound};
// |γ_k| = |(1/n)·Σ(s_i − γ0)·e^{-jωt_i}| ≤ 1, so the parts of α = 2|γ| are within ±2 (plus slack).
constexpr Range kComponentPart{-2 * kMeanBound, 2 * kMeanBound};

// Parts of a state with nothing observed yet are zero: any other value is corruption.
Range IfObserved(bool observed, Range range) { return observed ? range : kZero; }

void PutReal(std::string* out, float v) { PutFloat(out, v); }
void PutReal(std::string* out, double v) { PutDouble(out, v); }

template <typename Real>
Real ReadReal(ByteReader& r, std::string_view field) {
  if constexpr (std::is_same_v<Real, float>) {
    return r.Float(field);
  } else {
    return r.Double(field);
  }
}

template <typename Real>
Real ReadRealIn(ByteReader& r, std::string_view field, Range range) {
  const Real v = ReadReal<Real>(r, field);
  if (!r.ok() || (v >= range.lo && v <= range.hi)) return v;
  if (!std::isfinite(v)) {
    r.Fail(field, absl::StrCat("is not finite (", v, ")"));
  } else if (range.lo == range.hi) {
    r.Fail(field, absl::StrCat("is ", v, ", must be ", range.lo));
  } else {
    r.Fail(field, absl::StrCat("is ", v, ", outside [", range.lo, ", ", range.hi, "]"));
  }
  return v;
}

// A count, required to equal what the caller's map settings imply.
uint64_t ReadExactCount(ByteReader& r, std::string_view field, uint64_t expected) {
  const uint64_t count = r.Varint(field);
  if (r.ok() && count != expected) r.Fail(field, absl::StrCat("is ", count, ", expected ", expected));
  return count;
}

absl::Status CheckMaxOrder(int max_order) {
  if (max_order < 0 || max_order > kMaxMaxOrder) {
    return absl::InvalidArgumentError(absl::StrCat("max_order must be in [0, ", kMaxMaxOrder, "], got ", max_order));
  }
  return absl::OkStatus();
}

// ---- Spectrum: precision u8 (bytes per real: 4 or 8) | K varint | n u32 | t_first f64 | t_last f64 |
//      Σs f64 | 4K reals (S̄.re, S̄.im, Ē.re, Ē.im per period). SpectrumHeader::reserved is not kept.

const char* PrecisionName(uint64_t bytes_per_real) {
  return bytes_per_real == 4 ? "float" : bytes_per_real == 8 ? "double" : "unknown";
}

template <typename Real>
void PutSpectrumFields(const BasicSpectrum<Real>& spectrum, std::string* out) {
  PutByte(out, static_cast<uint8_t>(sizeof(Real)));
  PutVarint64(out, spectrum.periods());
  const SpectrumHeader& h = spectrum.header();
  PutFixed32(out, h.n);
  PutDouble(out, h.t_first);
  PutDouble(out, h.t_last);
  PutDouble(out, h.sum_s);
  const size_t reals = spectrum.periods() * kRealsPerPeriod;
  for (size_t i = 0; i < reals; ++i) PutReal(out, spectrum.body()[i]);
}

SpectrumHeader ReadSpectrumHeader(ByteReader& r) {
  SpectrumHeader h;
  h.n = r.Fixed32("n");
  const bool observed = h.n > 0;
  h.t_first = ReadRealIn<double>(r, "t_first", IfObserved(observed, kTime));
  h.t_last = ReadRealIn<double>(r, "t_last", IfObserved(observed, Range{h.t_first, kTime.hi}));
  // Σs of n values in [0, 1], summed in double, stays within [0, n] exactly (rounding is monotone).
  h.sum_s = ReadRealIn<double>(r, "sum_s", Range{0, static_cast<double>(h.n)});
  return h;
}

template <typename Real>
std::optional<BasicSpectrum<Real>> ReadSpectrumFields(ByteReader& r, size_t periods) {
  const uint8_t precision = r.Byte("precision");
  if (r.ok() && precision != sizeof(Real)) {
    r.Fail("precision",
           absl::StrCat("holds ", PrecisionName(precision), " reals, expected ", PrecisionName(sizeof(Real))));
  }
  ReadExactCount(r, "periods", periods);
  const SpectrumHeader header = ReadSpectrumHeader(r);
  // Checked before allocating (and by division, so that a huge `periods` cannot overflow).
  if (r.ok() && periods > r.remaining() / (kRealsPerPeriod * sizeof(Real))) {
    r.Fail("body", absl::StrCat("truncated: ", periods, " periods do not fit in ", r.remaining(), " bytes"));
  }
  if (!r.ok()) return std::nullopt;
  BasicSpectrum<Real> spectrum(periods);
  spectrum.mutable_header() = header;
  const Range range = IfObserved(header.n > 0, kMean);
  for (size_t i = 0; i < periods * kRealsPerPeriod && r.ok(); ++i) {
    spectrum.body()[i] = ReadRealIn<Real>(r, "body", range);
  }
  if (!r.ok()) return std::nullopt;
  return spectrum;
}

// ---- Published model: α0 f32 | order u8 | count varint | count × (k varint | a f32 | b f32).
//      At L = 5 and K < 128: 2 + 51 bytes.

void PutPublishedFields(const PublishedModel& model, std::string* out) {
  PutFloat(out, model.alpha0());
  PutByte(out, static_cast<uint8_t>(model.order()));
  PutVarint64(out, model.components().size());
  for (const Component& c : model.components()) {
    PutVarint64(out, c.k);
    PutFloat(out, c.a);
    PutFloat(out, c.b);
  }
}

Component ReadComponent(ByteReader& r, size_t periods) {
  Component c;
  const uint64_t k = r.Varint("component k");
  // Below K, and within Component::k's 16 bits whatever K the caller claims.
  const uint64_t limit = std::min<uint64_t>(periods, uint64_t{1} << 16);
  if (r.ok() && k >= limit) r.Fail("component k", absl::StrCat("is ", k, ", not below K = ", limit));
  c.k = static_cast<uint16_t>(k);
  c.a = ReadRealIn<float>(r, "component a", kComponentPart);
  c.b = ReadRealIn<float>(r, "component b", kComponentPart);
  return c;
}

// REQUIRES: 0 <= max_order <= kMaxMaxOrder.
PublishedModel ReadPublishedFields(ByteReader& r, size_t periods, int max_order) {
  const float alpha0 = ReadRealIn<float>(r, "alpha0", kUnit);
  const uint8_t order = r.Byte("order");
  if (r.ok() && order > max_order) r.Fail("order", absl::StrCat("is ", order, ", above L = ", max_order));
  const uint64_t count = r.Varint("components");
  if (r.ok() && count > static_cast<uint64_t>(max_order)) {
    r.Fail("components", absl::StrCat("are ", count, ", more than L = ", max_order));
  }
  if (!r.ok()) return PublishedModel();
  std::vector<Component> components;
  components.reserve(count);  // ≤ L ≤ 64: checked above
  for (uint64_t j = 0; j < count && r.ok(); ++j) components.push_back(ReadComponent(r, periods));
  return PublishedModel::Restore(alpha0, order, std::move(components));
}

// ---- Persistence: observed u8 (0/1) | t_last f64 | s_last f32 | τ⁻¹ f32 | samples u32 (21 bytes).

void PutPersistenceFields(const Persistence& p, std::string* out) {
  PutByte(out, p.observed != 0 ? 1 : 0);
  PutDouble(out, p.t_last);
  PutFloat(out, p.s_last);
  PutFloat(out, p.inv_tau);
  PutFixed32(out, p.samples);
}

Persistence ReadPersistenceFields(ByteReader& r) {
  Persistence p;
  const uint8_t observed = r.Byte("observed");
  if (r.ok() && observed > 1) r.Fail("observed", absl::StrCat("is ", observed, ", not 0 or 1"));
  p.observed = observed;
  p.t_last = ReadRealIn<double>(r, "t_last", IfObserved(observed, kTime));
  p.s_last = ReadRealIn<float>(r, "s_last", IfObserved(observed, kUnit));
  p.inv_tau = ReadRealIn<float>(r, "inv_tau", IfObserved(observed, kNonNegative));
  p.samples = r.Fixed32("samples");
  if (r.ok() && !observed && p.samples != 0) r.Fail("samples", "nonzero before any observation");
  return p;
}

// ---- Order errors: t_ref f64 | weight f64 | count varint (= L + 1) | count × error f64.

void PutOrderErrorFields(const OrderErrors& errors, std::string* out) {
  PutDouble(out, errors.reference_time());
  PutDouble(out, errors.weight());
  PutVarint64(out, errors.errors().size());
  for (double e : errors.errors()) PutDouble(out, e);
}

// REQUIRES: 0 <= max_order <= kMaxMaxOrder.
OrderErrors ReadOrderErrorFields(ByteReader& r, int max_order) {
  OrderErrors out(max_order);
  const double t_ref = ReadRealIn<double>(r, "t_ref", kTime);
  const double weight = ReadRealIn<double>(r, "weight", kNonNegative);
  ReadExactCount(r, "errors", static_cast<uint64_t>(max_order) + 1);
  if (!r.ok()) return out;
  std::vector<double> errors(max_order + 1);  // the count was checked to be L + 1 ≤ 65
  for (double& e : errors) e = ReadRealIn<double>(r, "error", kNonNegative);
  out.Restore(t_ref, weight, std::move(errors));
  return out;
}

// ---- Static state: count_value u32 (n << 1 | value) | t_first f64 | span f32: 16 bytes. The count
//      comes first because it decides what the other fields may hold.

void PutStaticStateFields(const StaticState& s, std::string* out) {
  PutFixed32(out, s.count_value);
  PutDouble(out, s.t_first);
  PutFloat(out, s.span);
}

StaticState ReadStaticStateFields(ByteReader& r) {
  StaticState s;
  s.count_value = r.Fixed32("count_value");
  if (r.ok() && s.count() == 0 && s.count_value != 0) r.Fail("count_value", "holds a value but no observations");
  // Nothing observed has no time; one observation has no span.
  s.t_first = ReadRealIn<double>(r, "t_first", IfObserved(s.count() > 0, kTime));
  s.span = ReadRealIn<float>(r, "span", IfObserved(s.count() > 1, kNonNegative));
  return s;
}

// ---- State model: flags u8 (bit 0: has a published model) | spectrum fields | [published model
//      fields] | persistence fields | order-error fields.

constexpr uint8_t kHasPublishedFlag = 1;

template <typename Real>
void PutStateModelFields(const BasicStateModel<Real>& model, std::string* out) {
  PutByte(out, model.has_published() ? kHasPublishedFlag : 0);
  PutSpectrumFields(model.spectrum(), out);
  if (model.has_published()) PutPublishedFields(model.published(), out);
  PutPersistenceFields(model.persistence(), out);
  PutOrderErrorFields(model.order_errors(), out);
}

template <typename Real>
std::optional<BasicStateModel<Real>> ReadStateModelFields(ByteReader& r, const ModelSettings& settings) {
  const uint8_t flags = r.Byte("flags");
  if (r.ok() && (flags & ~kHasPublishedFlag) != 0) r.Fail("flags", absl::StrCat("unknown flags ", flags));
  std::optional<BasicSpectrum<Real>> spectrum = ReadSpectrumFields<Real>(r, settings.periods.size());
  if (!spectrum) return std::nullopt;
  BasicStateModel<Real> model(settings);
  model.mutable_spectrum() = std::move(*spectrum);
  if (flags & kHasPublishedFlag) {
    model.set_published(ReadPublishedFields(r, settings.periods.size(), settings.max_order));
  }
  model.mutable_persistence() = ReadPersistenceFields(r);
  model.mutable_order_errors() = ReadOrderErrorFields(r, settings.max_order);
  if (!r.ok()) return std::nullopt;
  return model;
}

// ---- Framing shared by every record.

// Preamble + fields, for an encoder `put(std::string*)`.
template <typename PutFields>
std::string EncodeRecord(const RecordKind& kind, PutFields put) {
  std::string out;
  PutPreamble(kind, &out);
  put(&out);
  return out;
}

// Checks the preamble, reads the fields with `read(ByteReader&)` (a T, or an optional<T> that is
// empty on error) and requires the input to end there.
template <typename T, typename ReadFields>
absl::StatusOr<T> DecodeRecord(std::string_view bytes, const RecordKind& kind, ReadFields read) {
  ByteReader r(bytes, kind.name);
  ReadPreamble(r, kind);
  if (!r.ok()) return r.status();
  auto value = read(r);
  if (absl::Status status = r.Finish(); !status.ok()) return status;
  if constexpr (std::is_same_v<decltype(value), T>) {
    return value;
  } else {
    return std::move(*value);
  }
}

}  // namespace

absl::StatusOr<RecordTag> PeekRecordTag(std::string_view bytes) {
  if (bytes.empty()) return absl::DataLossError("record: empty");
  const uint8_t tag = static_cast<uint8_t>(bytes[0]);
  if (FindKind(tag) == nullptr) return absl::DataLossError(absl::StrCat("record: unknown record tag ", tag));
  return static_cast<RecordTag>(tag);
}

template <typename Real>
std::string EncodeSpectrum(const BasicSpectrum<Real>& spectrum) {
  return EncodeRecord(kSpectrumRecord, [&](std::string* out) { PutSpectrumFields(spectrum, out); });
}

std::string EncodePublishedModel(const PublishedModel& model) {
  return EncodeRecord(kPublishedModelRecord, [&](std::string* out) { PutPublishedFields(model, out); });
}

std::string EncodePersistence(const Persistence& persistence) {
  return EncodeRecord(kPersistenceRecord, [&](std::string* out) { PutPersistenceFields(persistence, out); });
}

std::string EncodeOrderErrors(const OrderErrors& errors) {
  return EncodeRecord(kOrderErrorsRecord, [&](std::string* out) { PutOrderErrorFields(errors, out); });
}

std::string EncodeStaticState(const StaticState& state) {
  return EncodeRecord(kStaticStateRecord, [&](std::string* out) { PutStaticStateFields(state, out); });
}

template <typename Real>
std::string EncodeStateModel(const BasicStateModel<Real>& model) {
  return EncodeRecord(kStateModelRecord, [&](std::string* out) { PutStateModelFields(model, out); });
}

template <typename Real>
absl::StatusOr<BasicSpectrum<Real>> DecodeSpectrum(std::string_view bytes, size_t periods) {
  return DecodeRecord<BasicSpectrum<Real>>(bytes, kSpectrumRecord,
                                           [&](ByteReader& r) { return ReadSpectrumFields<Real>(r, periods); });
}

absl::StatusOr<PublishedModel> DecodePublishedModel(std::string_view bytes, size_t periods, int max_order) {
  if (absl::Status status = CheckMaxOrder(max_order); !status.ok()) return status;
  return DecodeRecord<PublishedModel>(bytes, kPublishedModelRecord,
                                      [&](ByteReader& r) { return ReadPublishedFields(r, periods, max_order); });
}

absl::StatusOr<Persistence> DecodePersistence(std::string_view bytes) {
  return DecodeRecord<Persistence>(bytes, kPersistenceRecord, ReadPersistenceFields);
}

absl::StatusOr<OrderErrors> DecodeOrderErrors(std::string_view bytes, int max_order) {
  if (absl::Status status = CheckMaxOrder(max_order); !status.ok()) return status;
  return DecodeRecord<OrderErrors>(bytes, kOrderErrorsRecord,
                                   [&](ByteReader& r) { return ReadOrderErrorFields(r, max_order); });
}

absl::StatusOr<StaticState> DecodeStaticState(std::string_view bytes) {
  return DecodeRecord<StaticState>(bytes, kStaticStateRecord, ReadStaticStateFields);
}

template <typename Real>
absl::StatusOr<BasicStateModel<Real>> DecodeStateModel(std::string_view bytes, const ModelSettings& settings) {
  if (absl::Status status = CheckMaxOrder(settings.max_order); !status.ok()) return status;
  return DecodeRecord<BasicStateModel<Real>>(bytes, kStateModelRecord,
                                             [&](ByteReader& r) { return ReadStateModelFields<Real>(r, settings); });
}

template std::string EncodeSpectrum(const BasicSpectrum<float>&);
template std::string EncodeSpectrum(const BasicSpectrum<double>&);
template std::string EncodeStateModel(const BasicStateModel<float>&);
template std::string EncodeStateModel(const BasicStateModel<double>&);
template absl::StatusOr<BasicSpectrum<float>> DecodeSpectrum(std::string_view, size_t);
template absl::StatusOr<BasicSpectrum<double>> DecodeSpectrum(std::string_view, size_t);
template absl::StatusOr<BasicStateModel<float>> DecodeStateModel(std::string_view, const ModelSettings&);
template absl::StatusOr<BasicStateModel<double>> DecodeStateModel(std::string_view, const ModelSettings&);

}  // namespace fremen::model
