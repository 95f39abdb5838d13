// RecordArena: the float spectrum working records (SpectrumHeader + 4K floats, as in CompactSpectrum)
// of the changing cells of a map or shard, in one contiguous, 64-byte-aligned array of structs.
//
// Layout of record i, at i·stride(): the 4K-float body first, then the 32-byte header, then padding
// to a multiple of 64 bytes. The body first so that it is cache-line aligned (the vector loop of
// FoldObservation never splits a load across lines) while the header fills the tail: at K = 24 the
// record is 384 + 32 = 416 B, stride 448 B = 7 lines (≤ 16·K + 64). Array of structs, not struct of
// arrays: one scan touches scattered cells, and each cell's record is then a few adjacent lines
// (docs/performance.md, "One scan shares its phasors": struct of arrays with scattered cells is
// 10-25x slower).
//
// A new record is an empty spectrum (all zero: n = 0), equal to CompactSpectrum(periods).
// Thread-safety: none; one writer owns an arena (readers only while nothing writes). Resize and
// Append may reallocate and invalidate pointers from header()/body().
#pragma once

#include <cstddef>
#include <cstdint>

#include "storage/model/kernels/record_buffer.h"
#include "storage/model/spectrum.h"

namespace fremen::model {

class RecordArena {
 public:
  // Bytes per record for `periods` periods.
  static constexpr size_t StrideFor(size_t periods) {
    return (BodyBytes(periods) + sizeof(SpectrumHeader) + 63) / 64 * 64;
  }

  explicit RecordArena(size_t periods, size_t size = 0);

  size_t periods() const { return periods_; }
  size_t size() const { return buffer_.size(); }
  size_t stride() const { return buffer_.stride(); }
  // Bytes allocated (capacity, not size).
  size_t bytes() const { return buffer_.bytes(); }

  float* body(size_t i) { return reinterpret_cast<float*>(buffer_.record(i)); }
  const float* body(size_t i) const { return reinterpret_cast<const float*>(buffer_.record(i)); }
  SpectrumHeader& header(size_t i) { return *reinterpret_cast<SpectrumHeader*>(buffer_.record(i) + body_bytes_); }
  const SpectrumHeader& header(size_t i) const {
    return *reinterpret_cast<const SpectrumHeader*>(buffer_.record(i) + body_bytes_);
  }
  // The start of record i (64-byte aligned), for prefetching its stride() bytes.
  const std::byte* record(size_t i) const { return buffer_.record(i); }

  // Grows with empty records or shrinks to n records.
  void Resize(size_t n) { buffer_.Resize(n); }
  void Reserve(size_t n) { buffer_.Reserve(n); }
  // Adds one empty record; returns its index.
  size_t Append();

  // Copies a spectrum in or out of record i. REQUIRES: spectrum.periods() == periods().
  void Store(size_t i, const CompactSpectrum& spectrum);
  void Load(size_t i, CompactSpectrum& spectrum) const;

 private:
  static constexpr size_t BodyBytes(size_t periods) { return periods * kRealsPerPeriod * sizeof(float); }

  size_t periods_;
  size_t body_bytes_;
  RecordBuffer buffer_;
};

}  // namespace fremen::model
