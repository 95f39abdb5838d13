// Region prediction (docs/model.md, "Queries"): p(t) of many compact models at one time t.
//
// The per-query table cos ω_k t, sin ω_k t (float, from a PhasorTable built once per query in double
// with range reduction) turns each state's prediction into l multiply-adds: no trigonometry per state
// (docs/performance.md, "One scan shares its phasors": a cosf per cell is ~15x slower). float is
// ample: the result is within ~1e-6 of PublishedModel::Predict's double, and a served probability is
// float or a byte anyway.
// Thread-safety: pure functions; concurrent calls on the same unchanging CompactModels are fine.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "storage/model/kernels/compact_models.h"
#include "storage/model/kernels/model_columns.h"
#include "storage/model/phasor.h"

namespace fremen::model {

// A probability in [0, 1] as the byte round(p·255), the wire form of a region result (a quarter of a
// float's bandwidth; resolution 1/255, finer than any model's accuracy).
// Through int32: the same byte for every p in [0, 1], and a float -> int32 conversion vectorises on
// any x86-64 (cvttps2dq), where g++ vectorises float -> uint8 only with AVX-512.
inline uint8_t QuantizeProbability(float p) { return static_cast<uint8_t>(static_cast<int32_t>(p * 255.0f + 0.5f)); }

// out[i] = p(t) of record first + i, for i < count, clamped to [0, 1]. `order`: -1 for each state's
// selected order, else that order for all (an order above L uses all components).
// REQUIRES: phasors of the models' Ω; first + count <= models.size().
void PredictRegion(const CompactModels& models, size_t first, size_t count, const PhasorTable& phasors, int order,
                   float* out);
// The same, quantised (QuantizeProbability).
void PredictRegionU8(const CompactModels& models, size_t first, size_t count, const PhasorTable& phasors, int order,
                     uint8_t* out);

// out[i] = p(t) of record records[i], for i < records.size(), clamped to [0, 1]: the same kernel for
// records that are not consecutive (the cells of a box, as a shard holds them). `order` as above.
// REQUIRES: phasors of the models' Ω; every records[i] < models.size().
void PredictRecords(const CompactModels& models, std::span<const uint32_t> records, const PhasorTable& phasors,
                    int order, float* out);

// out[i] = p(t) of model first + i of `columns` at its own order, clamped to [0, 1]: bit for bit what
// PredictRecords gives for the same records at order -1. `terms`: the components computed for each
// model, at least the highest own order among them (the zeros past a model's own order add nothing).
// REQUIRES: phasors of the models' Ω; first + count <= columns.size(); terms <= columns.max_order().
void PredictColumns(const ModelColumns& columns, size_t first, size_t count, int terms, const PhasorTable& phasors,
                    float* out);
// The same, quantised (QuantizeProbability).
void PredictColumnsU8(const ModelColumns& columns, size_t first, size_t count, int terms,
                      const PhasorTable& phasors, uint8_t* out);

// The ways PredictColumns can sum a run, each giving the same bits: with Ω's cosines and sines held
// in vector registers and looked up by permutes, sixteen models at a time (AVX-512) or eight (AVX2),
// for an Ω of up to 32 periods; or one model at a time.
enum class ColumnsPath { kAvx512, kAvx2, kScalar };
// The fastest path this machine and build can take for an Ω of `periods` periods: the one
// PredictColumns takes.
ColumnsPath PredictColumnsPath(size_t periods);
// Whether they can take `path` for such an Ω (kScalar always).
bool PredictColumnsCan(ColumnsPath path, size_t periods);
// PredictColumns (PredictColumnsU8) on a given path, for tests and benchmarks.
// REQUIRES: PredictColumnsCan(path, phasors.size()).
void PredictColumnsOn(ColumnsPath path, const ModelColumns& columns, size_t first, size_t count, int terms,
                      const PhasorTable& phasors, float* out);
void PredictColumnsOn(ColumnsPath path, const ModelColumns& columns, size_t first, size_t count, int terms,
                      const PhasorTable& phasors, uint8_t* out);

// Every record of `models`.
inline void PredictRegion(const CompactModels& models, const PhasorTable& phasors, int order, float* out) {
  PredictRegion(models, 0, models.size(), phasors, order, out);
}
inline void PredictRegionU8(const CompactModels& models, const PhasorTable& phasors, int order, uint8_t* out) {
  PredictRegionU8(models, 0, models.size(), phasors, order, out);
}

}  // namespace fremen::model
