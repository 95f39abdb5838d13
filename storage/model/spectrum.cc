#include "storage/model/spectrum.h"

#include <algorithm>
#include <cmath>

namespace fremen::model {

template <typename Real>
ScanPhasors<Real>::ScanPhasors(const PhasorTable& table) {
  Reset(table);
}

template <typename Real>
void ScanPhasors<Real>::Reset(const PhasorTable& table) {
  time_ = table.time();
  const size_t reals = table.size() * kRealsPerPeriod;
  // Only the cos and −sin entries change with the time: the zeros stay when the size does.
  if (qs_.size() != reals) {
    qs_.assign(reals, Real(0));
    qe_.assign(reals, Real(0));
  }
  for (size_t k = 0; k < table.size(); ++k) {
    const Real c = static_cast<Real>(table.cos(k));
    const Real minus_s = static_cast<Real>(-table.sin(k));
    qs_[k * kRealsPerPeriod + 0] = c;
    qs_[k * kRealsPerPeriod + 1] = minus_s;
    qe_[k * kRealsPerPeriod + 2] = c;
    qe_[k * kRealsPerPeriod + 3] = minus_s;
  }
}

template <typename Real>
void BasicSpectrum<Real>::set_means(size_t k, std::complex<double> s_mean, std::complex<double> e_mean) {
  Real* p = &body_[k * kRealsPerPeriod];
  p[0] = static_cast<Real>(s_mean.real());
  p[1] = static_cast<Real>(s_mean.imag());
  p[2] = static_cast<Real>(e_mean.real());
  p[3] = static_cast<Real>(e_mean.imag());
}

template <typename Real>
void BasicSpectrum<Real>::AddBatch(std::span<const Observation> observations, const PeriodSet& periods) {
  if (observations.empty()) return;
  const size_t k_count = periods.size();
  std::vector<std::complex<double>> s_sums(k_count), e_sums(k_count);
  double sum_s = 0;
  double t_first = observations.front().t, t_last = observations.front().t;
  PhasorTable table(periods, t_first);
  for (const Observation& o : observations) {
    sum_s += o.s;
    t_first = std::min(t_first, o.t);
    t_last = std::max(t_last, o.t);
    table.Reset(periods, o.t);
    for (size_t k = 0; k < k_count; ++k) {
      const std::complex<double> e = table.conj_phasor(k);
      e_sums[k] += e;
      s_sums[k] += static_cast<double>(o.s) * e;
    }
  }
  MergeSums(static_cast<uint32_t>(observations.size()), sum_s, t_first, t_last, s_sums, e_sums);
}

template <typename Real>
void BasicSpectrum<Real>::MergeSums(uint32_t n2, double sum_s2, double t_first2, double t_last2,
                                    const std::vector<std::complex<double>>& s_sums,
                                    const std::vector<std::complex<double>>& e_sums) {
  const double n1 = header_.n;
  const double total = n1 + n2;
  for (size_t k = 0; k < periods(); ++k) {
    set_means(k, (mean_s_phasor(k) * n1 + s_sums[k]) / total, (mean_phasor(k) * n1 + e_sums[k]) / total);
  }
  if (header_.n == 0) {
    header_.t_first = t_first2;
    header_.t_last = t_last2;
  } else {
    header_.t_first = std::min(header_.t_first, t_first2);
    header_.t_last = std::max(header_.t_last, t_last2);
  }
  header_.sum_s += sum_s2;
  header_.n += n2;
}

template class ScanPhasors<float>;
template class ScanPhasors<double>;
template class BasicSpectrum<float>;
template class BasicSpectrum<double>;

}  // namespace fremen::model
