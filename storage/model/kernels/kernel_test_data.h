// Generated inputs for the batch-kernel tests: float cell spectra with realistic content (a periodic
// Bernoulli signal, irregular times, varied counts and spans so that the 2/3-span gate matters) and
// the published models and error counters that go with them. Deterministic for a given seed.
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "storage/model/order_errors.h"
#include "storage/model/periods.h"
#include "storage/model/published_model.h"
#include "storage/model/spectrum.h"

namespace fremen::model::testing {

// A cell observed 0..max_observations times over a span of up to three weeks, starting near 1.7e9 s.
CompactSpectrum RandomCellSpectrum(const PeriodSet& periods, std::mt19937_64& rng, int max_observations = 200);

// `count` such cells.
std::vector<CompactSpectrum> RandomCellSpectra(const PeriodSet& periods, size_t count, uint64_t seed);

// Error counters with random decayed errors, so that BestOrder picks every order 0..max_order.
OrderErrors RandomOrderErrors(int max_order, std::mt19937_64& rng);

}  // namespace fremen::model::testing
