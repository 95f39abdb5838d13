#include "storage/model/kernels/publication.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <complex>

#include "storage/model/model_settings.h"
#include "storage/model/published_model.h"

namespace fremen::model {
namespace {

// Whether a candidate with |γ|² = norm (and γ = re + j·im) ranks above a kept one, FromSpectrum's order:
// a strictly larger |γ|, ties to the lower period index (the kept one: candidates come in index
// order). |γ|² decides unless the two are within rounding of each other; then std::abs, FromSpectrum's
// own key, decides, so that near-ties resolve identically.
bool RanksAbove(double norm, double re, double im, double kept_norm, double kept_re, double kept_im) {
  constexpr double kRelativeRounding = 1e-12;
  if (std::fabs(norm - kept_norm) > kRelativeRounding * std::max(norm, kept_norm)) return norm > kept_norm;
  return std::abs(std::complex<double>(re, im)) > std::abs(std::complex<double>(kept_re, kept_im));
}

// The strongest eligible components so far, strongest first. Structure of arrays of plain doubles:
// an insertion shifts a few scalars, and no std::complex goes through memory (a 16-byte store
// re-read as two 8-byte halves stalls store forwarding).
struct TopComponents {
  double norm[kMaxMaxOrder];
  double re[kMaxMaxOrder];
  double im[kMaxMaxOrder];
  uint16_t k[kMaxMaxOrder];
  int kept = 0;

  // Offers component `index` (offered in increasing index order) to a list of at most `limit`.
  void Offer(int limit, uint16_t index, double c_re, double c_im) {
    const double c_norm = c_re * c_re + c_im * c_im;
    int pos = kept < limit ? kept : limit - 1;
    if (kept == limit && !RanksAbove(c_norm, c_re, c_im, norm[pos], re[pos], im[pos])) return;
    while (pos > 0 && RanksAbove(c_norm, c_re, c_im, norm[pos - 1], re[pos - 1], im[pos - 1])) {
      norm[pos] = norm[pos - 1];
      re[pos] = re[pos - 1];
      im[pos] = im[pos - 1];
      k[pos] = k[pos - 1];
      --pos;
    }
    norm[pos] = c_norm;
    re[pos] = c_re;
    im[pos] = c_im;
    k[pos] = index;
    if (kept < limit) ++kept;
  }
};

}  // namespace

Publisher::Publisher(const PeriodSet& periods, int max_order) : max_order_(max_order), periods_(periods.periods()) {
  assert(max_order >= 0 && max_order <= kMaxMaxOrder);
}

void Publisher::Publish(const CompactSpectrum& spectrum, int order, CompactModels& models, size_t out) const {
  assert(spectrum.periods() == periods_.size() && models.max_order() == max_order_);
  // γ0, γ_k and the span come from BasicSpectrum's own inline functions, as FromSpectrum takes them:
  // rewriting γ_k = S̄_k − γ0·Ē_k here would be free to round differently (the compiler may fuse the
  // product into the subtraction in one place and not in the other), and publication must be exact.
  models.SetUnpublished(out, static_cast<float>(spectrum.gamma0()));
  models.MarkPublished(out);
  CompactModelHeader& h = models.header(out);
  h.order = static_cast<uint8_t>(order);
  if (spectrum.count() == 0 || max_order_ == 0) return;

  const double longest_estimable = kSpanGate * spectrum.span();
  TopComponents top;
  for (size_t k = 0; k < periods_.size(); ++k) {
    if (periods_[k] > longest_estimable) continue;
    const std::complex<double> gamma = spectrum.gamma(k);
    top.Offer(max_order_, static_cast<uint16_t>(k), gamma.real(), gamma.imag());
  }
  h.count = static_cast<uint16_t>(top.kept);
  uint16_t* k_out = models.k(out);
  float* a_out = models.a(out);
  float* b_out = models.b(out);
  for (int j = 0; j < top.kept; ++j) {
    // One-sided spectrum: amplitude 2|γ|, phase arg γ.
    k_out[j] = top.k[j];
    a_out[j] = static_cast<float>(2.0 * top.re[j]);
    b_out[j] = static_cast<float>(2.0 * top.im[j]);
  }
}

template <typename OrderOf>
void Publisher::PublishRecords(const RecordArena& spectra, size_t first, size_t count, CompactModels& models,
                               OrderOf order_of) const {
  // One scratch spectrum for the whole range: a record is copied in (416 B at K = 24, cheap next to
  // reading it from memory) so that the spectrum's own accessors apply, without an allocation per state.
  CompactSpectrum scratch(spectra.periods());
  for (size_t i = first; i < first + count; ++i) {
    spectra.Load(i, scratch);
    Publish(scratch, order_of(i), models, i);
  }
}

void Publisher::PublishRange(const RecordArena& spectra, const OrderErrorTable& errors, size_t first, size_t count,
                             CompactModels& models, const OrderRule& rule) const {
  PublishRecords(spectra, first, count, models, [&](size_t i) { return errors.BestOrder(i, rule); });
}

void Publisher::PublishRange(const RecordArena& spectra, std::span<const OrderErrors> errors, size_t first,
                             size_t count, CompactModels& models, const OrderRule& rule) const {
  PublishRecords(spectra, first, count, models, [&](size_t i) { return errors[i].BestOrder(rule); });
}

}  // namespace fremen::model
