#include "storage/model/kernels/wide_bodies.h"

#include <algorithm>

#include "absl/strings/str_cat.h"
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

void WideBodies::Fold(uint32_t record, SpectrumHeader& header, float* body, const ScanPhasors<double>& phasors,
                      float s) {
  double* wide = Row(record);
  FoldObservation(header, wide, phasors, s);
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
