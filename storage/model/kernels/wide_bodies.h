// WideBodies: double bodies for the float spectrum records (RecordArena) that have outgrown float.
//
// A float running mean loses increments once n is large: measured on a two-period Ω, the error of
// γ is 9e-7 after 2^20 observations, 1.7e-4 after 2^22, 8e-3 after 2^24 and 0.1 after 2^26 — and a
// cell in view of a 10 Hz scanner reaches 2^20 in about a day. So once a record holds
// kCompactRecordLimit observations its owner widens it here: later observations are folded into a
// double body, which is then mirrored (rounded once) into the float record. Everything that reads
// records — prediction, publication, checkpoints, snapshots — keeps reading the float record and
// is unchanged; only the fold of a wide record runs in double. Checkpoints keep the double body
// too (Encode/Decode), so that a recovered state equals one that never restarted, bit for bit.
//
// Memory: 4K doubles per wide record (768 B at K = 24) beside its float record, plus 4 bytes per
// record index up to the highest wide one.
// Thread-safety: none; the owner of the arena owns its wide bodies.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "storage/model/spectrum.h"

namespace fremen::model {

class WideBodies {
 public:
  explicit WideBodies(size_t periods) : reals_(periods * kRealsPerPeriod) {}

  bool wide(uint32_t record) const { return record < row_of_.size() && row_of_[record] != kNone; }
  // Records held wide.
  size_t size() const { return rows_; }
  size_t bytes() const { return bodies_.capacity() * sizeof(double) + row_of_.capacity() * sizeof(uint32_t); }

  // Makes `record` wide, its double body starting as `body` (4K floats); a wide record's double
  // body is replaced.
  void Widen(uint32_t record, const float* body);
  // Folds value s at the table's time into the wide record's header and double body, then mirrors
  // the double body into the float `body`: bit for bit FoldObservation with the table's
  // ScanPhasors<double>, without building them (a history pays that per observation).
  // REQUIRES: wide(record).
  void Fold(uint32_t record, SpectrumHeader& header, float* body, const PhasorTable& table, float s);

  // The double body of a wide record, for checkpoints: a version byte, then 4K little-endian
  // doubles. REQUIRES: wide(record).
  std::string Encode(uint32_t record) const;
  // Makes `record` wide with the encoded body; DataLoss on damaged bytes (the record is unchanged).
  absl::Status Decode(uint32_t record, std::string_view bytes);

 private:
  static constexpr uint32_t kNone = UINT32_MAX;
  // The double body of `record`, a new (zero) row when it is not wide yet.
  double* RowFor(uint32_t record);
  double* Row(uint32_t record) { return bodies_.data() + size_t{row_of_[record]} * reals_; }
  const double* Row(uint32_t record) const { return bodies_.data() + size_t{row_of_[record]} * reals_; }

  size_t reals_;
  size_t rows_ = 0;
  std::vector<uint32_t> row_of_;  // record → row of bodies_, kNone when not wide
  std::vector<double> bodies_;    // reals_ per row
};

}  // namespace fremen::model
