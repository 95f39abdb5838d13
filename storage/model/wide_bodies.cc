#include "storage/model/wide_bodies.h"

#include <algorithm>

#include "absl/strings/str_cat.h"
#include "storage/model/varint.h"

namespace fremen::model {

void WideBodies::Widen(uint32_t record, const float* body) {
  if (record >= row_of_.size()) row_of_.resize(record + 1, kNone);
  if (row_of_[record] == kNone) {
    row_of_[record] = static_cast<uint32_t>(size());
    bodies_.resize(bodies_.size() + reals_);
  }
  double* wide = bodies_.data() + size_t{row_of_[record]} * reals_;
  for (size_t i = 0; i < reals_; ++i) wide[i] = body[i];
}

void WideBodies::Fold(uint32_t record, SpectrumHeader& header, float* body, const ScanPhasors<double>& phasors,
                      float s) {
  double* wide = bodies_.data() + size_t{row_of_[record]} * reals_;
  FoldObservation(header, wide, phasors, s);
  for (size_t i = 0; i < reals_; ++i) body[i] = static_cast<float>(wide[i]);
}

namespace {
constexpr uint8_t kWideVersion = 1;
}  // namespace

std::string WideBodies::Encode(uint32_t record) const {
  const double* wide = bodies_.data() + size_t{row_of_[record]} * reals_;
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
  std::vector<float> unused(reals_);
  Widen(record, unused.data());
  std::copy(body.begin(), body.end(), bodies_.begin() + size_t{row_of_[record]} * reals_);
  return absl::OkStatus();
}

}  // namespace fremen::model
