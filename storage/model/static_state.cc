#include "storage/model/static_state.h"

#include <algorithm>
#include <cmath>
#include <complex>

namespace fremen::model {

namespace {
// The mean of e^{-jω t_i} over n times evenly spread over [t0, t0 + span]: a geometric series.
std::complex<double> MeanPhasorOfEvenTimes(double period, double t0, double span, uint32_t n) {
  const std::complex<double> first = std::polar(1.0, -ReducedPhase(t0, period));
  if (n < 2 || span == 0) return first;
  const double step_phase = ReducedPhase(span / (n - 1), period);
  const std::complex<double> ratio = std::polar(1.0, -step_phase);
  const std::complex<double> denominator = 1.0 - ratio;
  if (std::abs(denominator) < 1e-12) return first;  // the step is a whole number of periods
  // ratio^n as the phasor of n steps: std::pow of a complex goes through the complex log, whose
  // |z| ≈ 1 path in glibc (__x2y2m1) sorts its terms with qsort; promotions spent about a fifth of
  // a recovery's samples there (docs/storage.md, "Recovery").
  const std::complex<double> nth = std::polar(1.0, -step_phase * static_cast<double>(n));
  return first * (1.0 - nth) / (static_cast<double>(n) * denominator);
}
}  // namespace

template <typename Real>
void StaticState::Promote(const ModelSettings& settings, BasicStateModel<Real>& out) const {
  out = BasicStateModel<Real>(settings);
  if (count() == 0) return;
  BasicSpectrum<Real>& spectrum = out.mutable_spectrum();
  SpectrumHeader& h = spectrum.mutable_header();
  h.n = count();
  h.sum_s = value() * static_cast<double>(count());
  h.t_first = t_first;
  h.t_last = t_last();
  for (size_t k = 0; k < settings.periods.size(); ++k) {
    const std::complex<double> e = MeanPhasorOfEvenTimes(settings.periods.period(k), t_first, span, count());
    spectrum.set_means(k, static_cast<double>(value()) * e, e);
  }
  Persistence& persistence = out.mutable_persistence();
  persistence.observed = 1;
  persistence.t_last = t_last();
  persistence.s_last = value();
  persistence.samples = count() - 1;
}

template void StaticState::Promote(const ModelSettings&, BasicStateModel<float>&) const;
template void StaticState::Promote(const ModelSettings&, BasicStateModel<double>&) const;

}  // namespace fremen::model
