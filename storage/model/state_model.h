// The complete incremental FreMEn model of one state (docs/model.md): spectrum, published model,
// persistence and prequential order errors, composed.
//
// Observations update the spectrum, the persistence state and the error counters at once; the
// published model only changes on Update() (the nightly job) or Publish(). Predictions read the
// published model. Thread-safety: none; one owner at a time.
#pragma once

#include <span>

#include "storage/model/model_settings.h"
#include "storage/model/observation.h"
#include "storage/model/order_errors.h"
#include "storage/model/persistence.h"
#include "storage/model/published_model.h"
#include "storage/model/spectrum.h"

namespace fremen::model {

template <typename Real>
class BasicStateModel {
 public:
  // `settings` must outlive the model.
  explicit BasicStateModel(const ModelSettings& settings);

  // One observation at the time of `phasors` (scored, then folded in).
  void Observe(const PhasorTable& phasors, float s);
  void Observe(double t, float s) { Observe(PhasorTable(settings_->periods, t), s); }
  // Many observations at any times, in any order. The result equals observing them one by one in
  // time order, whatever their order in the span and however they are split into batches.
  void AddBatch(std::span<const Observation> observations);

  // The nightly update: choose the order with the lowest decayed error (ties to the lower) and
  // republish P from the spectrum with it. Returns the chosen order.
  int Update();
  // Republish P from the spectrum with a given order (REQUIRES: 0 <= order <= L).
  void Publish(int order);

  // p(t) from the published model at `order` (-1: the selected one), optionally with persistence.
  double Predict(double t, bool with_persistence = false, int order = -1) const;
  double Predict(const PhasorTable& phasors, bool with_persistence = false, int order = -1) const;

  const ModelSettings& settings() const { return *settings_; }
  const BasicSpectrum<Real>& spectrum() const { return spectrum_; }
  const PublishedModel& published() const { return published_; }
  bool has_published() const { return has_published_; }
  const Persistence& persistence() const { return persistence_; }
  const OrderErrors& order_errors() const { return errors_; }

  // For decoders and the store: replace a part wholesale.
  BasicSpectrum<Real>& mutable_spectrum() { return spectrum_; }
  void set_published(PublishedModel p) {
    published_ = std::move(p);
    has_published_ = true;
  }
  Persistence& mutable_persistence() { return persistence_; }
  OrderErrors& mutable_order_errors() { return errors_; }

 private:
  // Scores s at the phasors' time against the published model, if there is one.
  void Score(const PhasorTable& phasors, float s);

  const ModelSettings* settings_;
  BasicSpectrum<Real> spectrum_;
  PublishedModel published_;
  bool has_published_ = false;
  Persistence persistence_;
  OrderErrors errors_;
};

// Generic states (doors, edges, features): double, exact.
using StateModel = BasicStateModel<double>;
// One grid cell: float working record.
using CompactStateModel = BasicStateModel<float>;

extern template class BasicStateModel<float>;
extern template class BasicStateModel<double>;

}  // namespace fremen::model
