#include "storage/update_record.h"

#include "absl/strings/str_cat.h"
#include "storage/model/varint.h"

namespace fremen::storage {

namespace {

constexpr uint8_t kVersion = 1;
// Orders 0..L with L ≤ 64: a longer histogram is corruption.
constexpr uint64_t kMaxHistogram = 65;

}  // namespace

std::string EncodeUpdateRecord(const UpdateRecord& r) {
  std::string out(1, static_cast<char>(kVersion));
  model::PutDouble(&out, r.start_time);
  model::PutDouble(&out, r.duration_seconds);
  model::PutVarint64(&out, r.states_updated);
  model::PutDouble(&out, r.prediction_error_before);
  model::PutDouble(&out, r.prediction_error_after);
  model::PutVarint64(&out, r.order_histogram.size());
  for (uint64_t n : r.order_histogram) model::PutVarint64(&out, n);
  return out;
}

absl::StatusOr<UpdateRecord> DecodeUpdateRecord(std::string_view bytes) {
  model::ByteReader in(bytes, "update record");
  if (const uint8_t version = in.Byte("version"); in.ok() && version != kVersion) {
    in.Fail("version", absl::StrCat("unknown version ", version));
  }
  UpdateRecord r;
  r.start_time = in.Double("start time");
  r.duration_seconds = in.Double("duration");
  r.states_updated = in.Varint("states updated");
  r.prediction_error_before = in.Double("prediction error before");
  r.prediction_error_after = in.Double("prediction error after");
  const uint64_t orders = in.Varint("histogram length");
  if (orders > kMaxHistogram) in.Fail("histogram length", absl::StrCat(orders, " orders exceed ", kMaxHistogram));
  for (uint64_t l = 0; l < orders && in.ok(); ++l) r.order_histogram.push_back(in.Varint("histogram"));
  if (absl::Status s = in.Finish(); !s.ok()) return s;
  return r;
}

absl::Status WriteUpdateRecord(Env* env, const std::string& path, const UpdateRecord& record) {
  return WriteFileAtomically(env, path, EncodeUpdateRecord(record));
}

absl::StatusOr<std::optional<UpdateRecord>> ReadUpdateRecord(Env* env, const std::string& path) {
  auto bytes = env->ReadFile(path);
  if (absl::IsNotFound(bytes.status())) return std::optional<UpdateRecord>();
  if (!bytes.ok()) return bytes.status();
  auto record = DecodeUpdateRecord(*bytes);
  if (!record.ok()) return absl::DataLossError(absl::StrCat(path, ": ", record.status().message()));
  return std::optional<UpdateRecord>(*std::move(record));
}

}  // namespace fremen::storage
