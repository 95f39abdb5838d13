// cos and sin of the FFT-bin angle 2π·r/n, computed bit-reproducibly.
//
// The lossless history decides each reconstructed slot by p ≥ 0.5 (eq. 7), so the value of p at a
// slot must come out bit for bit the same whenever and wherever it is computed: at Add time, at
// Reconstruct time, after an encode/decode round trip on another machine. libm's cos/sin are not
// specified to the last bit (they differ between versions and vector variants), so this computes them
// from exact integer quadrant reduction and a fixed Taylor polynomial evaluated with explicit fma
// (IEEE-754 defines fma exactly; the compiler cannot contract or reorder it). Accuracy is within
// a few ulp of the true value. Changing this arithmetic changes stored records' reconstructions:
// it is part of the lossless record format.
// Thread-safety: pure functions.
#pragma once

#include <cmath>
#include <cstdint>

namespace fremen::model {

struct UnitPhasor {
  double cos = 1;
  double sin = 0;
};

// cos and sin of 2π·r/n. REQUIRES: 1 ≤ n ≤ 2^52, r < n.
UnitPhasor BinPhasor(uint64_t r, uint64_t n);

// The phasor of the sum of two angles, (a.cos + j a.sin)(b.cos + j b.sin), with a fixed rounding.
inline UnitPhasor Rotate(UnitPhasor a, UnitPhasor b) {
  const double sa_sb = a.sin * b.sin;
  const double ca_sb = a.cos * b.sin;
  return {std::fma(a.cos, b.cos, -sa_sb), std::fma(a.sin, b.cos, ca_sb)};
}

}  // namespace fremen::model
