#include "storage/model/record_codec.h"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "absl/strings/match.h"
#include "storage/model/test_signals.h"
#include "storage/model/varint.h"

namespace fremen::model {
namespace {

using testing::RandomTimes;
using testing::SampleBernoulli;

constexpr double kDay = 86400.0;
constexpr double kEpoch = 1.7e9;

// A state observed for three weeks around an epoch-scale time, published after the first, so that
// every part (spectrum, P, persistence, decayed order errors) holds non-trivial values.
template <typename Real>
BasicStateModel<Real> TrainedModel(const ModelSettings& settings, uint64_t seed) {
  BasicStateModel<Real> model(settings);
  const auto obs = SampleBernoulli(
      RandomTimes(3000, kEpoch, 21 * kDay, seed),
      [](double t) { return 0.5 + 0.3 * std::cos(ReducedPhase(t, kDay)) + 0.15 * std::sin(ReducedPhase(t, kDay / 2)); },
      seed + 1);
  model.AddBatch(std::span(obs).first(1000));
  model.Publish(settings.max_order);
  model.AddBatch(std::span(obs).subspan(1000));
  model.Update();
  return model;
}

StaticState ObservedStaticState() {
  StaticState s;
  for (double t : RandomTimes(50, kEpoch, 3 * kDay, 4)) s.Observe(t, 1.0f);
  return s;
}

// Decodes a record of one kind and re-encodes what it got: equal bytes mean the decoded value is
// exactly what the record holds.
using Recode = std::function<absl::StatusOr<std::string>(std::string_view)>;

template <typename T, typename Decode, typename Encode>
Recode MakeRecode(Decode decode, Encode encode) {
  return [=](std::string_view bytes) -> absl::StatusOr<std::string> {
    absl::StatusOr<T> value = decode(bytes);
    if (!value.ok()) return value.status();
    return encode(*value);
  };
}

struct Case {
  std::string name;
  std::string bytes;
  Recode recode;
};

template <typename Real>
Recode SpectrumRecode(size_t periods) {
  return MakeRecode<BasicSpectrum<Real>>([=](std::string_view b) { return DecodeSpectrum<Real>(b, periods); },
                                         [](const BasicSpectrum<Real>& s) { return EncodeSpectrum(s); });
}

template <typename Real>
Recode StateModelRecode(const ModelSettings& settings) {
  return MakeRecode<BasicStateModel<Real>>(
      [&settings](std::string_view b) { return DecodeStateModel<Real>(b, settings); },
      [](const BasicStateModel<Real>& m) { return EncodeStateModel(m); });
}

// One valid record of every kind, with the function that decodes and re-encodes it.
std::vector<Case> AllCases(const ModelSettings& settings) {
  const auto compact = TrainedModel<float>(settings, 1);
  const auto exact = TrainedModel<double>(settings, 2);
  const size_t k = settings.periods.size();
  const int l = settings.max_order;
  std::vector<Case> cases;
  cases.push_back({"float spectrum", EncodeSpectrum(compact.spectrum()), SpectrumRecode<float>(k)});
  cases.push_back({"double spectrum", EncodeSpectrum(exact.spectrum()), SpectrumRecode<double>(k)});
  cases.push_back({"published model", EncodePublishedModel(exact.published()),
                   MakeRecode<PublishedModel>([=](std::string_view b) { return DecodePublishedModel(b, k, l); },
                                              EncodePublishedModel)});
  cases.push_back({"persistence", EncodePersistence(exact.persistence()),
                   MakeRecode<Persistence>(DecodePersistence, EncodePersistence)});
  cases.push_back(
      {"order errors", EncodeOrderErrors(exact.order_errors()),
       MakeRecode<OrderErrors>([=](std::string_view b) { return DecodeOrderErrors(b, l); }, EncodeOrderErrors)});
  cases.push_back({"static state", EncodeStaticState(ObservedStaticState()),
                   MakeRecode<StaticState>(DecodeStaticState, EncodeStaticState)});
  cases.push_back({"float state model", EncodeStateModel(compact), StateModelRecode<float>(settings)});
  cases.push_back({"double state model", EncodeStateModel(exact), StateModelRecode<double>(settings)});
  cases.push_back({"unpublished state model", EncodeStateModel(BasicStateModel<float>(settings)),
                   StateModelRecode<float>(settings)});
  return cases;
}

// ---- Round trips

TEST(RecordCodecTest, SpectrumRoundTripsInBothPrecisions) {
  ModelSettings settings;
  const auto compact = TrainedModel<float>(settings, 1);
  const auto exact = TrainedModel<double>(settings, 2);
  auto f = DecodeSpectrum<float>(EncodeSpectrum(compact.spectrum()), settings.periods.size());
  auto d = DecodeSpectrum<double>(EncodeSpectrum(exact.spectrum()), settings.periods.size());
  ASSERT_TRUE(f.ok()) << f.status();
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_EQ(*f, compact.spectrum());
  EXPECT_EQ(*d, exact.spectrum());
  // An empty spectrum is a valid record too.
  auto empty = DecodeSpectrum<float>(EncodeSpectrum(CompactSpectrum(24)), 24);
  ASSERT_TRUE(empty.ok()) << empty.status();
  EXPECT_EQ(*empty, CompactSpectrum(24));
}

TEST(RecordCodecTest, PartsRoundTrip) {
  ModelSettings settings;
  const auto model = TrainedModel<double>(settings, 3);
  ASSERT_EQ(model.published().components().size(), 5u);
  ASSERT_GT(model.order_errors().weight(), 0);

  auto p = DecodePublishedModel(EncodePublishedModel(model.published()), 24, 5);
  ASSERT_TRUE(p.ok()) << p.status();
  EXPECT_EQ(*p, model.published());

  auto persistence = DecodePersistence(EncodePersistence(model.persistence()));
  ASSERT_TRUE(persistence.ok()) << persistence.status();
  EXPECT_EQ(*persistence, model.persistence());

  auto errors = DecodeOrderErrors(EncodeOrderErrors(model.order_errors()), 5);
  ASSERT_TRUE(errors.ok()) << errors.status();
  EXPECT_EQ(*errors, model.order_errors());

  for (const StaticState& s : {StaticState(), ObservedStaticState()}) {
    auto decoded = DecodeStaticState(EncodeStaticState(s));
    ASSERT_TRUE(decoded.ok()) << decoded.status();
    EXPECT_EQ(*decoded, s);
  }
  // Mean-only and default models (no components) and the persistence of an unobserved state.
  for (const PublishedModel& m : {PublishedModel(), PublishedModel::MeanOnly(1.0)}) {
    auto decoded = DecodePublishedModel(EncodePublishedModel(m), 24, 5);
    ASSERT_TRUE(decoded.ok()) << decoded.status();
    EXPECT_EQ(*decoded, m);
  }
  auto unobserved = DecodePersistence(EncodePersistence(Persistence()));
  ASSERT_TRUE(unobserved.ok()) << unobserved.status();
  EXPECT_EQ(*unobserved, Persistence());
}

template <typename Real>
void ExpectSameModel(const BasicStateModel<Real>& a, const BasicStateModel<Real>& b) {
  EXPECT_EQ(a.spectrum(), b.spectrum());
  EXPECT_EQ(a.has_published(), b.has_published());
  EXPECT_EQ(a.published(), b.published());
  EXPECT_EQ(a.persistence(), b.persistence());
  EXPECT_EQ(a.order_errors(), b.order_errors());
}

template <typename Real>
void CheckStateModelRoundTrip() {
  ModelSettings settings;
  for (const auto& model : {TrainedModel<Real>(settings, 5), BasicStateModel<Real>(settings)}) {
    auto decoded = DecodeStateModel<Real>(EncodeStateModel(model), settings);
    ASSERT_TRUE(decoded.ok()) << decoded.status();
    ExpectSameModel(*decoded, model);
    // The decoded model predicts exactly as the original.
    for (double t : RandomTimes(20, kEpoch, 30 * kDay, 6)) {
      EXPECT_EQ(decoded->Predict(t, true), model.Predict(t, true));
    }
  }
}

TEST(RecordCodecTest, StateModelRoundTrips) {
  CheckStateModelRoundTrip<float>();
  CheckStateModelRoundTrip<double>();
}

TEST(RecordCodecTest, EveryRecordReencodesToTheSameBytes) {
  ModelSettings settings;
  for (const Case& c : AllCases(settings)) {
    auto recoded = c.recode(c.bytes);
    ASSERT_TRUE(recoded.ok()) << c.name << ": " << recoded.status();
    EXPECT_EQ(*recoded, c.bytes) << c.name;
  }
}

// ---- Sizes (K = 24, L = 5)

TEST(RecordCodecTest, EncodedSizes) {
  ModelSettings settings;
  const auto compact = TrainedModel<float>(settings, 1);
  const auto exact = TrainedModel<double>(settings, 2);
  const size_t k = settings.periods.size();
  ASSERT_EQ(k, 24u);
  ASSERT_EQ(settings.max_order, 5);

  const size_t float_spectrum = EncodeSpectrum(compact.spectrum()).size();
  EXPECT_LE(float_spectrum, 16 * k + 64);
  EXPECT_EQ(float_spectrum, 416u);  // 2 + 1 + 1 + 28 + 96·4
  EXPECT_EQ(EncodeSpectrum(exact.spectrum()).size(), 800u);
  // The compact P, read by every query: ≤ 64 B at L = 5.
  ASSERT_EQ(exact.published().components().size(), 5u);
  EXPECT_LE(EncodePublishedModel(exact.published()).size(), 64u);
  EXPECT_EQ(EncodePublishedModel(exact.published()).size(), 53u);  // 2 + 4 + 1 + 1 + 5·(1 + 8)
  EXPECT_EQ(EncodePersistence(exact.persistence()).size(), kPersistenceRecordBytes);
  EXPECT_EQ(kPersistenceRecordBytes, 23u);
  EXPECT_EQ(EncodeOrderErrors(exact.order_errors()).size(), 67u);  // 2 + 16 + 1 + 6·8
  // StaticState: a 16-byte payload behind the 2-byte preamble.
  EXPECT_EQ(EncodeStaticState(ObservedStaticState()).size(), kStaticStateRecordBytes);
  EXPECT_EQ(kStaticStateRecordBytes, 2 + 16u);
  EXPECT_EQ(EncodeStateModel(compact).size(), 554u);
  EXPECT_EQ(EncodeStateModel(exact).size(), 938u);
}

// The largest P at L = 5: period indices near the top of the 16-bit range take 3-byte varints.
TEST(RecordCodecTest, PublishedModelStaysWithin64BytesAtTheLargestK) {
  const size_t k_count = 65535;
  auto periods = PeriodSet::Harmonics(kWeekSeconds, k_count);
  ASSERT_TRUE(periods.ok());
  Spectrum spectrum(k_count);
  SpectrumHeader& h = spectrum.mutable_header();
  h.n = 1;
  h.sum_s = 0.5;
  h.t_first = 0;
  h.t_last = 4 * kWeekSeconds;
  for (size_t k = k_count - 5; k < k_count; ++k) spectrum.set_means(k, {0.1 * (k % 7 + 1), -0.2}, {0, 0});
  const PublishedModel p = PublishedModel::FromSpectrum(spectrum, *periods, 5, 5);
  ASSERT_EQ(p.components().size(), 5u);
  ASSERT_GE(p.components().back().k, 16384);  // a 3-byte varint
  const std::string bytes = EncodePublishedModel(p);
  EXPECT_EQ(bytes.size(), 63u);
  auto decoded = DecodePublishedModel(bytes, k_count, 5);
  ASSERT_TRUE(decoded.ok()) << decoded.status();
  EXPECT_EQ(*decoded, p);
}

// ---- Rejections

TEST(RecordCodecTest, EveryTruncationIsRejected) {
  ModelSettings settings;
  for (const Case& c : AllCases(settings)) {
    for (size_t length = 0; length < c.bytes.size(); ++length) {
      auto recoded = c.recode(std::string_view(c.bytes).substr(0, length));
      ASSERT_FALSE(recoded.ok()) << c.name << " truncated to " << length;
      EXPECT_EQ(recoded.status().code(), absl::StatusCode::kDataLoss) << c.name;
    }
  }
}

TEST(RecordCodecTest, TrailingBytesAreRejected) {
  ModelSettings settings;
  for (const Case& c : AllCases(settings)) {
    auto recoded = c.recode(c.bytes + std::string(1, '\0'));
    ASSERT_FALSE(recoded.ok()) << c.name;
    EXPECT_NE(recoded.status().message().find("trailing"), std::string_view::npos) << recoded.status();
  }
}

// A corrupted record either fails to decode, or decodes to a value that re-encodes to exactly the
// corrupted bytes (so nothing was silently dropped or invented). Under ASan this also shows that
// no input is read out of bounds.
void ExpectErrorOrFaithful(const Case& c, const std::string& bytes) {
  auto recoded = c.recode(bytes);
  if (recoded.ok()) {
    EXPECT_EQ(*recoded, bytes) << c.name;
  } else {
    EXPECT_EQ(recoded.status().code(), absl::StatusCode::kDataLoss) << c.name << ": " << recoded.status();
  }
}

TEST(RecordCodecTest, BitFlipsNeverCrashAndNeverDecodeToSomethingElse) {
  ModelSettings settings;
  std::mt19937_64 rng(17);
  for (const Case& c : AllCases(settings)) {
    int rejected = 0;
    for (int trial = 0; trial < 3000; ++trial) {
      std::string bytes = c.bytes;
      const int flips = 1 + static_cast<int>(rng() % 3);
      for (int f = 0; f < flips; ++f) bytes[rng() % bytes.size()] ^= static_cast<char>(1u << (rng() % 8));
      ExpectErrorOrFaithful(c, bytes);
      rejected += !c.recode(bytes).ok();
    }
    // Flips in the preamble, counts, flags and exponents are caught; mantissa flips cannot be.
    EXPECT_GT(rejected, 0) << c.name;
  }
}

TEST(RecordCodecTest, GarbageNeverCrashes) {
  ModelSettings settings;
  std::mt19937_64 rng(23);
  for (const Case& c : AllCases(settings)) {
    for (int trial = 0; trial < 2000; ++trial) {
      // Half the trials keep the valid preamble so that the garbage reaches the field decoders.
      std::string bytes = trial % 2 == 0 ? c.bytes.substr(0, 2) : "";
      const size_t length = rng() % (c.bytes.size() + 16);
      for (size_t i = 0; i < length; ++i) bytes.push_back(static_cast<char>(rng()));
      ExpectErrorOrFaithful(c, bytes);
      // Random bytes overwritten in place: the lengths stay plausible.
      std::string overwritten = c.bytes;
      for (int i = 0; i < 4; ++i) overwritten[rng() % overwritten.size()] = static_cast<char>(rng());
      ExpectErrorOrFaithful(c, overwritten);
    }
  }
}

TEST(RecordCodecTest, WrongTagIsRejectedNamingBothRecords) {
  ModelSettings settings;
  const std::string spectrum = EncodeSpectrum(CompactSpectrum(24));
  auto p = DecodePublishedModel(spectrum, 24, 5);
  ASSERT_FALSE(p.ok());
  EXPECT_EQ(p.status().code(), absl::StatusCode::kDataLoss);
  EXPECT_EQ(p.status().message(), "published model: tag: holds a spectrum record (at byte 1)");

  std::string unknown = spectrum;
  unknown[0] = static_cast<char>(200);
  auto s = DecodeSpectrum<float>(unknown, 24);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.status().message(), "spectrum: tag: unknown record tag 200 (at byte 1)");
}

TEST(RecordCodecTest, UnknownVersionIsRejectedNamingTheRecord) {
  ModelSettings settings;
  for (const Case& c : AllCases(settings)) {
    std::string bytes = c.bytes;
    bytes[1] = 2;
    auto recoded = c.recode(bytes);
    ASSERT_FALSE(recoded.ok()) << c.name;
    EXPECT_EQ(recoded.status().code(), absl::StatusCode::kDataLoss);
    EXPECT_NE(recoded.status().message().find("version: unknown format version 2"), std::string_view::npos)
        << recoded.status();
  }
  auto s = DecodeStaticState(std::string("\x05\x07") + std::string(16, '\0'));
  ASSERT_FALSE(s.ok());
  EXPECT_TRUE(absl::StartsWith(s.status().message(), "static state: version")) << s.status();
}

TEST(RecordCodecTest, PrecisionIsPartOfTheSpectrumRecord) {
  const std::string float_record = EncodeSpectrum(CompactSpectrum(24));
  auto as_double = DecodeSpectrum<double>(float_record, 24);
  ASSERT_FALSE(as_double.ok());
  EXPECT_EQ(as_double.status().message(), "spectrum: precision: holds float reals, expected double (at byte 3)");
  auto as_float = DecodeSpectrum<float>(EncodeSpectrum(Spectrum(24)), 24);
  ASSERT_FALSE(as_float.ok());
  EXPECT_NE(as_float.status().message().find("holds double reals, expected float"), std::string_view::npos);
}

TEST(RecordCodecTest, CountsMustMatchTheMapSettings) {
  // The settings of maps made before the weighted rule, under which this model's order is above 3.
  ModelSettings settings;
  settings.criterion = ErrorCriterion::kThreshold;
  settings.error_half_life = 7 * 86400.0;
  settings.order_rule = OrderRule{OrderSelection::kMargin};
  const auto model = TrainedModel<double>(settings, 7);
  auto spectrum = DecodeSpectrum<double>(EncodeSpectrum(model.spectrum()), 23);
  ASSERT_FALSE(spectrum.ok());
  EXPECT_NE(spectrum.status().message().find("periods: is 24, expected 23"), std::string_view::npos)
      << spectrum.status();

  // Five components do not fit a map with L = 3, nor index a map with K = 2.
  auto p = DecodePublishedModel(EncodePublishedModel(model.published()), 24, 3);
  ASSERT_FALSE(p.ok());
  EXPECT_NE(p.status().message().find("above L = 3"), std::string_view::npos) << p.status();
  EXPECT_FALSE(DecodePublishedModel(EncodePublishedModel(model.published()), 2, 5).ok());

  auto errors = DecodeOrderErrors(EncodeOrderErrors(model.order_errors()), 4);
  ASSERT_FALSE(errors.ok());
  EXPECT_NE(errors.status().message().find("errors: is 6, expected 5"), std::string_view::npos) << errors.status();

  // Impossible expectations are the caller's error, not the record's.
  EXPECT_EQ(DecodeOrderErrors(EncodeOrderErrors(model.order_errors()), 65).status().code(),
            absl::StatusCode::kInvalidArgument);
  ModelSettings other = settings;
  other.periods = *PeriodSet::Harmonics(kWeekSeconds, 12);
  EXPECT_FALSE(DecodeStateModel<double>(EncodeStateModel(model), other).ok());
}

// A corrupted count must be caught before anything is allocated for it.
TEST(RecordCodecTest, HugeCountsAreRejectedWithoutAllocating) {
  std::string bytes = {1, 1, 4};  // spectrum v1, float
  const uint64_t huge = uint64_t{1} << 60;
  PutVarint64(&bytes, huge);
  bytes.append(28, '\0');  // an empty header
  auto s = DecodeSpectrum<float>(bytes, huge);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.status().message().find("do not fit"), std::string_view::npos) << s.status();

  std::string p = {2, 1, 0, 0, 0, 0, 0};  // P: α0 = 0, order 0
  PutVarint64(&p, huge);
  auto decoded = DecodePublishedModel(p, 24, 5);
  ASSERT_FALSE(decoded.ok());
  EXPECT_NE(decoded.status().message().find("more than L = 5"), std::string_view::npos) << decoded.status();
}

TEST(RecordCodecTest, NonFiniteValuesAreRejected) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  ModelSettings settings;
  auto model = TrainedModel<float>(settings, 8);

  CompactSpectrum spectrum = model.spectrum();
  spectrum.body()[5] = nan;
  auto s = DecodeSpectrum<float>(EncodeSpectrum(spectrum), 24);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.status().message().find("spectrum: body: is not finite"), std::string_view::npos) << s.status();

  Persistence persistence = model.persistence();
  persistence.inv_tau = static_cast<float>(inf);
  auto p = DecodePersistence(EncodePersistence(persistence));
  ASSERT_FALSE(p.ok());
  EXPECT_NE(p.status().message().find("persistence: inv_tau: is not finite"), std::string_view::npos) << p.status();

  OrderErrors errors = model.order_errors();
  std::vector<double> values = errors.errors();
  values[2] = -inf;
  errors.Restore(errors.reference_time(), errors.weight(), values);
  EXPECT_FALSE(DecodeOrderErrors(EncodeOrderErrors(errors), 5).ok());

  StaticState state = ObservedStaticState();
  state.t_first = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(DecodeStaticState(EncodeStaticState(state)).ok());
}

TEST(RecordCodecTest, ImplausibleValuesAreRejected) {
  Spectrum spectrum(24);
  spectrum.mutable_header().sum_s = 1;  // Σs without observations
  auto s = DecodeSpectrum<double>(EncodeSpectrum(spectrum), 24);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.status().message().find("sum_s: is 1, must be 0"), std::string_view::npos) << s.status();

  spectrum.mutable_header() = {.t_first = 10, .t_last = 5, .sum_s = 1, .n = 2};
  EXPECT_FALSE(DecodeSpectrum<double>(EncodeSpectrum(spectrum), 24).ok());  // t_last before t_first

  Persistence persistence;
  persistence.observed = 1;
  persistence.s_last = 1.5f;
  EXPECT_FALSE(DecodePersistence(EncodePersistence(persistence)).ok());

  StaticState state;
  state.count_value = 1;  // a value without observations
  EXPECT_FALSE(DecodeStaticState(EncodeStaticState(state)).ok());
}

TEST(RecordCodecTest, PeekRecordTagTellsStaticStatesFromStateModels) {
  ModelSettings settings;
  EXPECT_EQ(*PeekRecordTag(EncodeStaticState(StaticState())), RecordTag::kStaticState);
  EXPECT_EQ(*PeekRecordTag(EncodeStateModel(BasicStateModel<float>(settings))), RecordTag::kStateModel);
  EXPECT_FALSE(PeekRecordTag("").ok());
  EXPECT_FALSE(PeekRecordTag("\x63").ok());
}

}  // namespace
}  // namespace fremen::model
