// Every record a shard keeps (storage/model/record_codec.h, storage/static_bricks.h, the lossless
// history and the wide bodies of storage/model/), decoded as Shard::Load reads them from LMDB. A
// record that decodes must re-encode to a record that decodes to the same bytes, and a decoded
// model must be usable as the shard uses it (predictions, one more observation, an update). Input:
// a byte choosing the record type and the map (K, L), then the record's bytes.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "fuzz/fuzz_map.h"
#include "fuzz/fuzz_util.h"
#include "storage/map_info.h"
#include "storage/model/lossless/lossless_history.h"
#include "storage/model/record_codec.h"
#include "storage/model/state_model.h"
#include "storage/model/kernels/wide_bodies.h"
#include "storage/static_bricks.h"

namespace {

using namespace fremen;

// Whole-history work is one FFT of the history's length; a length with a large prime factor costs
// FFTW many times a power of two's (about 6 s for a 2^20-slot one under this build's sanitizers,
// past libFuzzer's 10-s limit on a loaded machine), so the property runs on up to 2^18 slots.
constexpr uint64_t kMaxWholeHistorySlots = uint64_t{1} << 18;

template <typename Real>
void UseModel(model::BasicStateModel<Real>& m) {
  const double times[] = {0, 1.7e9, m.spectrum().header().t_last, m.persistence().t_last + 3600};
  for (double t : times) {
    if (!std::isfinite(t) || std::abs(t) > 1e13) continue;
    for (int order = -1; order <= m.settings().max_order; ++order) {
      const double p = m.Predict(t, m.settings().persistence, order);
      FUZZ_CHECK(std::isfinite(p), "a decoded model predicts a number");
    }
  }
  m.Observe(1.7e9, 1.0f);
  m.Update();
}

template <typename Real>
void StateModel(std::string_view bytes, const model::ModelSettings& settings) {
  auto m = model::DecodeStateModel<Real>(bytes, settings);
  if (!m.ok()) return;
  const std::string encoded = model::EncodeStateModel(*m);
  auto again = model::DecodeStateModel<Real>(encoded, settings);
  FUZZ_CHECK(again.ok(), again.status().ToString());
  FUZZ_CHECK(model::EncodeStateModel(*again) == encoded, "state model round trip");
  UseModel(*m);
}

template <typename Real>
void Spectrum(std::string_view bytes, size_t periods) {
  auto s = model::DecodeSpectrum<Real>(bytes, periods);
  if (!s.ok()) return;
  const std::string encoded = model::EncodeSpectrum(*s);
  auto again = model::DecodeSpectrum<Real>(encoded, periods);
  FUZZ_CHECK(again.ok() && model::EncodeSpectrum(*again) == encoded, "spectrum round trip");
}

void Lossless(std::string_view bytes, int max_order) {
  auto h = model::LosslessHistory::Decode(bytes);
  if (!h.ok()) return;
  const std::string encoded = h->Encode();
  FUZZ_CHECK(encoded.size() == h->encoded_size(), "encoded_size is the encoding's size");
  auto again = model::LosslessHistory::Decode(encoded);
  FUZZ_CHECK(again.ok() && *again == *h, "lossless history round trip");
  const uint64_t m = h->slot_count();
  // Whole-history work (errors, an update) takes time and memory linear in the slots, up to 2^30
  // by design (LosslessHistory::kMaxSlots): run it on histories of at most kMaxWholeHistorySlots.
  if (m > kMaxWholeHistorySlots) return;
  const uint64_t begin = m > 64 ? m - 64 : 0;
  auto states = h->Reconstruct(begin, m);
  FUZZ_CHECK(states.ok(), states.status().ToString());
  (void)h->EstimationError();
  (void)h->PredictionError();
  (void)h->Predict(h->SlotTime(m));
  (void)h->Update(max_order);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const storage::MapInfo map = fuzz::FuzzMap(data[0] / 16);
  const model::ModelSettings settings = *storage::ModelSettingsOf(map);
  const size_t k = settings.periods.size();
  const int l = settings.max_order;
  const std::string_view bytes = fuzz::AsView(data + 1, size - 1);
  switch (data[0] % 16) {
    case 0:
      (void)model::PeekRecordTag(bytes);
      break;
    case 1:
      Spectrum<float>(bytes, k);
      break;
    case 2:
      Spectrum<double>(bytes, k);
      break;
    case 3:
      if (auto p = model::DecodePublishedModel(bytes, k, l); p.ok()) {
        auto again = model::DecodePublishedModel(model::EncodePublishedModel(*p), k, l);
        FUZZ_CHECK(again.ok() && *again == *p, "published model round trip");
      }
      break;
    case 4:
      if (auto p = model::DecodePersistence(bytes); p.ok()) {
        auto again = model::DecodePersistence(model::EncodePersistence(*p));
        FUZZ_CHECK(again.ok() && *again == *p, "persistence round trip");
      }
      break;
    case 5:
      if (auto e = model::DecodeOrderErrors(bytes, l); e.ok()) {
        auto again = model::DecodeOrderErrors(model::EncodeOrderErrors(*e), l);
        FUZZ_CHECK(again.ok() && *again == *e, "order errors round trip");
      }
      break;
    case 6:
      if (auto s = model::DecodeStaticState(bytes); s.ok()) {
        auto again = model::DecodeStaticState(model::EncodeStaticState(*s));
        FUZZ_CHECK(again.ok() && *again == *s, "static state round trip");
        // As a shard does on the state's first change.
        model::BasicStateModel<float> m(settings);
        s->Promote(settings, m);
        UseModel(m);
      }
      break;
    case 7:
      StateModel<float>(bytes, settings);
      break;
    case 8:
      StateModel<double>(bytes, settings);
      break;
    case 9:
      if (auto b = storage::StaticBrick::Decode(bytes); b.ok()) {
        const std::string encoded = b->Encode();
        auto again = storage::StaticBrick::Decode(encoded);
        FUZZ_CHECK(again.ok() && again->Encode() == encoded, "static brick round trip");
      }
      break;
    case 10:
      Lossless(bytes, l);
      break;
    case 11: {
      model::WideBodies wide(k);
      if (wide.Decode(3, bytes).ok()) {
        FUZZ_CHECK(wide.wide(3), "a decoded wide body is wide");
        const std::string encoded = wide.Encode(3);
        model::WideBodies again(k);
        FUZZ_CHECK(again.Decode(0, encoded).ok() && again.Encode(0) == encoded, "wide body round trip");
      }
      break;
    }
    default:
      break;
  }
  return 0;
}
