#include "server/convert/query_convert.h"

#include <cmath>
#include <algorithm>

#include "storage/model/lossless/lossless_history.h"
#include "storage/model/state_model.h"

namespace fremen::server {

namespace {

void SetComponent(double period, double amplitude, double phase, v1::Component& out) {
  out.set_period_seconds(period);
  out.set_amplitude(amplitude);
  out.set_phase(phase);
}

void SetInterval(double start, double end, v1::TimeInterval& out) {
  out.set_start(start);
  out.set_end(end);
}

void DynamicToProto(const model::ModelSettings& settings, const model::CompactStateModel& m, bool include_spectrum,
                    v1::StateModel& out) {
  const model::CompactSpectrum& spectrum = m.spectrum();
  out.set_observations(spectrum.count());
  out.set_first_time(spectrum.header().t_first);
  out.set_last_time(spectrum.header().t_last);
  out.set_mean(spectrum.gamma0());
  const model::PeriodSet& periods = settings.periods;
  if (include_spectrum) {
    for (size_t k = 0; k < spectrum.periods(); ++k) {
      const std::complex<double> gamma = spectrum.gamma(k);
      // One-sided amplitude 2|γ_k|, as P holds it (docs/model.md, "Published model P").
      SetComponent(periods.period(k), 2 * std::abs(gamma), std::arg(gamma), *out.add_spectrum());
    }
  }
  // A state with no P yet predicts γ0 (docs/model.md, "Published model P").
  const model::PublishedModel& p = m.published();
  out.set_published_mean(m.has_published() ? p.alpha0() : spectrum.gamma0());
  out.set_selected_order(m.has_published() ? p.order() : 0);
  if (m.has_published()) {
    for (const model::Component& c : p.components()) {
      SetComponent(periods.period(c.k), c.amplitude(), c.phase(), *out.add_published());
    }
  }
  const model::OrderErrors& errors = m.order_errors();
  for (int l = 0; l <= errors.max_order(); ++l) {
    v1::OrderError& e = *out.add_order_errors();
    e.set_order(l);
    e.set_error(errors.ErrorRate(l));
    e.set_weight(errors.weight());
  }
  const model::Persistence& persistence = m.persistence();
  v1::Persistence& pe = *out.mutable_persistence();
  pe.set_last_time(persistence.t_last);
  pe.set_last_value(persistence.s_last);
  pe.set_tau_seconds(persistence.inv_tau > 0 ? 1.0 / persistence.inv_tau : 0.0);
}

void LosslessToProto(const model::LosslessHistory& h, v1::LosslessModel& out) {
  const uint64_t m = h.slot_count();
  out.set_origin(h.t0());
  out.set_sampling_seconds(h.delta());
  out.set_slot_count(m);
  bool truncated = false;
  h.outliers().ForEachInterval([&](const model::SlotSet::Interval& i) {
    if (i.begin >= m) return;
    if (static_cast<size_t>(out.outliers_size()) == kMaxModelIntervals) {
      truncated = true;
      return;
    }
    SetInterval(h.SlotTime(i.begin), h.SlotTime(std::min(i.end, m)), *out.add_outliers());
  });
  // The gaps of the coverage before slot m.
  uint64_t covered_to = 0;
  const auto gap = [&](uint64_t begin, uint64_t end) {
    if (begin >= end) return;
    if (static_cast<size_t>(out.unobserved_size()) == kMaxModelIntervals) {
      truncated = true;
      return;
    }
    SetInterval(h.SlotTime(begin), h.SlotTime(end), *out.add_unobserved());
  };
  h.coverage().ForEachInterval([&](const model::SlotSet::Interval& i) {
    gap(covered_to, i.begin);
    covered_to = i.end;
  });
  gap(covered_to, m);
  out.set_truncated(truncated);
  out.set_estimation_error(h.EstimationError().rate());
  out.set_prediction_error(h.PredictionError().rate());
  const model::BinModel& p = h.model();
  out.set_published_mean(p.alpha0());
  out.set_selected_order(p.order());
  for (const model::BinComponent& c : p.components()) {
    // Bin k of an n-slot transform: period n·Δ/k.
    SetComponent(static_cast<double>(p.length()) * h.delta() / c.k, c.amplitude(), c.phase(), *out.add_published());
  }
}

}  // namespace

void StateModelToProto(const storage::MapInfo& map, const model::ModelSettings& settings, uint64_t key,
                       const storage::StateSnapshot& snapshot, bool include_spectrum, v1::StateModel& out) {
  out.set_id(key);
  if (map.kind == storage::MapKind::kGrid) {
    const std::array<uint32_t, 3> cell = map.grid.keys().Cell(key);
    out.mutable_cell()->set_x(cell[0]);
    out.mutable_cell()->set_y(cell[1]);
    out.mutable_cell()->set_z(cell[2]);
  }
  out.set_name(snapshot.name);
  out.set_group(snapshot.group);
  if (snapshot.is_static || !snapshot.model) {
    // Never changed: its counters say everything (γ0 = its value, no spectrum, P of order 0).
    const model::StaticState& s = snapshot.static_state;
    out.set_never_changed(true);
    out.set_observations(s.count());
    out.set_first_time(s.t_first);
    out.set_last_time(s.t_last());
    out.set_mean(s.value());
    out.set_published_mean(s.value());
    out.set_selected_order(0);
    v1::Persistence& pe = *out.mutable_persistence();
    pe.set_last_time(s.t_last());
    pe.set_last_value(s.value());
  } else {
    DynamicToProto(settings, *snapshot.model, include_spectrum, out);
  }
  if (snapshot.lossless) LosslessToProto(*snapshot.lossless, *out.mutable_lossless());
}

void MapStatsToProto(const storage::MapStats& stats, v1::MapStats& out) {
  const storage::ShardStats& t = stats.totals;
  out.set_states(t.states);
  out.set_dynamic_states(t.dynamic_states);
  out.set_observations(t.observations);
  out.set_disk_bytes(t.disk_bytes);
  out.set_memory_bytes(t.memory_bytes);
  out.mutable_order_histogram()->Add(t.order_histogram.begin(), t.order_histogram.end());
  out.set_mean_prediction_error(stats.mean_prediction_error);
  out.set_compression_ratio(stats.compression_ratio);
  out.set_log_bytes(stats.log_bytes);
  out.set_lossless_estimation_error(stats.estimation_error);
  out.set_lossless_prediction_error(stats.lossless_prediction_error);
  if (stats.last_update) UpdateRecordToProto(*stats.last_update, *out.mutable_last_update());
}

void UpdateRecordToProto(const storage::UpdateRecord& u, v1::MapUpdate& m) {
  const double whole = std::floor(u.start_time);
  m.mutable_start_time()->set_seconds(static_cast<int64_t>(whole));
  m.mutable_start_time()->set_nanos(static_cast<int32_t>((u.start_time - whole) * 1e9));
  m.set_duration_seconds(u.duration_seconds);
  m.set_states_updated(u.states_updated);
  m.set_prediction_error_before(u.prediction_error_before);
  m.set_prediction_error_after(u.prediction_error_after);
  m.mutable_order_histogram()->Add(u.order_histogram.begin(), u.order_histogram.end());
}

}  // namespace fremen::server
