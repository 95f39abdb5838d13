#include "storage/model/lossless/bin_phasor.h"

#include <cmath>
#include <numbers>

namespace fremen::model {

namespace {

constexpr double Factorial(int k) {
  double f = 1;
  for (int i = 2; i <= k; ++i) f *= i;  // exact up to 18! < 2^53
  return f;
}

// Taylor coefficients of (sin x − x)/x³ and (cos x − 1)/x² in z = x², lowest power first. On
// |x| ≤ π/4 the first omitted terms are below 1e-19, far under an ulp.
constexpr double kSin[] = {-1 / Factorial(3),  1 / Factorial(5),  -1 / Factorial(7),  1 / Factorial(9),
                           -1 / Factorial(11), 1 / Factorial(13), -1 / Factorial(15), 1 / Factorial(17)};
constexpr double kCos[] = {-1 / Factorial(2),  1 / Factorial(4),  -1 / Factorial(6),
                           1 / Factorial(8),   -1 / Factorial(10), 1 / Factorial(12),
                           -1 / Factorial(14), 1 / Factorial(16), -1 / Factorial(18)};

template <size_t N>
double Horner(const double (&c)[N], double z) {
  double v = c[N - 1];
  for (size_t i = N - 1; i-- > 0;) v = std::fma(v, z, c[i]);
  return v;
}

}  // namespace

UnitPhasor BinPhasor(uint64_t r, uint64_t n) {
  // 2πr/n = (π/2)·(q + rem/n) with integer quadrant q and rem in [-n/2, n/2], all exact.
  const uint64_t u = 4 * r;
  uint64_t q = u / n;
  int64_t rem = static_cast<int64_t>(u - q * n);
  if (2 * static_cast<uint64_t>(rem) > n) {
    rem -= static_cast<int64_t>(n);
    ++q;
  }
  // |x| ≤ π/4.
  const double x = (std::numbers::pi / 2) * (static_cast<double>(rem) / static_cast<double>(n));
  const double z = x * x;
  const double s = std::fma(x * z, Horner(kSin, z), x);
  const double c = std::fma(z, Horner(kCos, z), 1.0);
  switch (q & 3) {
    case 0:
      return {c, s};
    case 1:
      return {-s, c};
    case 2:
      return {-c, -s};
    default:
      return {s, -c};
  }
}

}  // namespace fremen::model
