// Binary encodings of the model records the store keeps: the spectrum (float or double), the
// published model P, persistence, the order-error counters, the static state and a whole state model.
//
// Every record is [tag: 1 byte][format version: 1 byte][fields], little-endian, written field by
// field (never a memcpy of a struct, whose padding and byte order are the compiler's), float and
// double by their IEEE-754 bits, counts and period indices as canonical varints (varint.h). The
// layout of each record is given beside its encoder in record_codec.cc.
//
// Decoders treat their input as untrusted (a torn write, a flipped bit, a record of another type):
// they check the tag and version, every count against the caller's expectation (K, L) before
// allocating, every value against the range the model can produce (finite times within ±1e13 s,
// means of unit phasors within ±1, Σs within [0, n], ...), and reject trailing bytes. A problem is an
// absl::DataLossError "<record>: <field>: <what is wrong> (at byte i)"; a caller passing impossible
// expectations (L > 64) gets InvalidArgument. Decoding never reads out of bounds and never trusts a
// length it has not checked.
//
// Encoded sizes at K = 24, L = 5 (pinned by record_codec_test): spectrum 416 B as float, 800 B as
// double; published model 53 B (≤ 63 B for any K ≤ 65535); persistence 23 B; order errors 67 B;
// static state 18 B; state model 554 B (float) or 938 B (double) when published.
//
// Versioning: a record's version changes whenever its layout or meaning does; decoders accept only
// the versions they know. The state-model record embeds the others' fields without their own
// preambles, so changing any part's layout bumps the state-model version too.
// Thread-safety: pure functions.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "absl/status/statusor.h"
#include "storage/model/model_settings.h"
#include "storage/model/order_errors.h"
#include "storage/model/persistence.h"
#include "storage/model/published_model.h"
#include "storage/model/spectrum.h"
#include "storage/model/state_model.h"
#include "storage/model/static_state.h"

namespace fremen::model {

// The first byte of every record. Stored on disk: never renumber, never reuse a retired value.
enum class RecordTag : uint8_t {
  kSpectrum = 1,
  kPublishedModel = 2,
  kPersistence = 3,
  kOrderErrors = 4,
  kStaticState = 5,
  kStateModel = 6,
};

// Sizes of the fixed-size records (preamble included), for the store's size accounting (eq. 16).
inline constexpr size_t kPersistenceRecordBytes = 2 + 21;
inline constexpr size_t kStaticStateRecordBytes = 2 + 16;

// The tag of an encoded record, so that a store can tell what a value holds (e.g. a grid cell is a
// static state until its first change, then a state model). DataLoss when empty or unknown.
absl::StatusOr<RecordTag> PeekRecordTag(std::string_view bytes);

// Encoders. The spectrum record carries its precision: a float record does not decode as double.
template <typename Real>
std::string EncodeSpectrum(const BasicSpectrum<Real>& spectrum);
std::string EncodePublishedModel(const PublishedModel& model);
std::string EncodePersistence(const Persistence& persistence);
std::string EncodeOrderErrors(const OrderErrors& errors);
std::string EncodeStaticState(const StaticState& state);
template <typename Real>
std::string EncodeStateModel(const BasicStateModel<Real>& model);

// Decoders. `periods` is the map's K = |Ω|, `max_order` its L (0..64): the record must agree.
template <typename Real>
absl::StatusOr<BasicSpectrum<Real>> DecodeSpectrum(std::string_view bytes, size_t periods);
absl::StatusOr<PublishedModel> DecodePublishedModel(std::string_view bytes, size_t periods, int max_order);
absl::StatusOr<Persistence> DecodePersistence(std::string_view bytes);
absl::StatusOr<OrderErrors> DecodeOrderErrors(std::string_view bytes, int max_order);
absl::StatusOr<StaticState> DecodeStaticState(std::string_view bytes);
// The model refers to `settings` (K, L and the rest), which must outlive it.
template <typename Real>
absl::StatusOr<BasicStateModel<Real>> DecodeStateModel(std::string_view bytes, const ModelSettings& settings);

extern template std::string EncodeSpectrum(const BasicSpectrum<float>&);
extern template std::string EncodeSpectrum(const BasicSpectrum<double>&);
extern template std::string EncodeStateModel(const BasicStateModel<float>&);
extern template std::string EncodeStateModel(const BasicStateModel<double>&);
extern template absl::StatusOr<BasicSpectrum<float>> DecodeSpectrum(std::string_view, size_t);
extern template absl::StatusOr<BasicSpectrum<double>> DecodeSpectrum(std::string_view, size_t);
extern template absl::StatusOr<BasicStateModel<float>> DecodeStateModel(std::string_view, const ModelSettings&);
extern template absl::StatusOr<BasicStateModel<double>> DecodeStateModel(std::string_view, const ModelSettings&);

}  // namespace fremen::model
