#include "storage/model/kernels/wide_bodies.h"

#include <algorithm>

#include "absl/strings/str_cat.h"
#include "storage/model/kernels/cpu_dispatch.h"
#include "storage/model/varint.h"

namespace fremen::model {

double* WideBodies::RowFor(uint32_t record) {
  if (record >= row_of_.size()) row_of_.resize(record + 1, kNone);
  if (row_of_[record] == kNone) {
    row_of_[record] = static_cast<uint32_t>(rows_++);
    bodies_.resize(rows_ * reals_);
  }
  return Row(record);
}

void WideBodies::Widen(uint32_t record, const float* body) { std::copy(body, body + reals_, RowFor(record)); }

// Cloned for AVX2: a state widened by a long history folds every observation of it here.
FREMEN_KERNEL_CLONES void WideBodies::Fold(uint32_t record, SpectrumHeader& header, float* body,
                                           const PhasorTable& table, float s) {
  double* __restrict wide = Row(record);
  const double d = FoldHeader(header, table.time(), s);
  const double sv = s;
  for (size_t k = 0; k < table.size(); ++k) {
    const double c = table.cos(k), minus_s = -table.sin(k);
    double* __restrict b = wide + k * kRealsPerPeriod;
    // FoldObservation's body[i] += d·(s·qs[i] + qe[i] − body[i]) with qs = [c, −sin, 0, 0] and
    // qe = [0, 0, c, −sin], the zeros written out: the same operations, so the same bits.
    b[0] += d * (sv * c + 0.0 - b[0]);
    b[1] += d * (sv * minus_s + 0.0 - b[1]);
    b[2] += d * (sv * 0.0 + c - b[2]);
    b[3] += d * (sv * 0.0 + minus_s - b[3]);
  }
  for (size_t i = 0; i < reals_; ++i) body[i] = static_cast<float>(wide[i]);
}

namespace {
constexpr uint8_t kWideVersion = 1;
}  // namespace

std::string WideBodies::Encode(uint32_t record) const {
  const double* wide = Row(record);
  std::string out;
  out.reserve(1 + reals_ * sizeof(double));
  out.push_back(static_cast<char>(kWideVersion));
  for (size_t i = 0; i < reals_; ++i) PutDouble(&out, wide[i]);
  return out;
}

absl::Status WideBodies::Decode(uint32_t record, std::string_view bytes) {
  ByteReader r(bytes, "wide spectrum body");
  if (const uint8_t version = r.Byte("version"); r.ok() && version != kWideVersion) {
    r.Fail("version", absl::StrCat("unknown version ", version));
  }
  if (r.ok() && r.remaining() != reals_ * sizeof(double)) {
    r.Fail("body", absl::StrCat(r.remaining(), " bytes for ", reals_, " doubles"));
  }
  std::vector<double> body(reals_);
  for (double& v : body) v = r.Double("body");
  if (absl::Status s = r.Finish(); !s.ok()) return s;
  std::copy(body.begin(), body.end(), RowFor(record));
  return absl::OkStatus();
}

}  // namespace fremen::model
