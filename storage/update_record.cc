#include "storage/update_record.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>

#include "absl/strings/str_cat.h"
#include "storage/model/varint.h"

namespace fremen::storage {

namespace {

constexpr uint8_t kVersion = 1;
// Orders 0..L with L ≤ 64: a longer histogram is corruption.
constexpr uint64_t kMaxHistogram = 65;

void PutDouble(std::string* out, double v) {
  uint64_t bits;
  std::memcpy(&bits, &v, 8);
  for (int i = 0; i < 8; ++i) out->push_back(static_cast<char>(bits >> (8 * i)));
}

absl::Status Errno(const char* what, const std::string& path) {
  return absl::InternalError(absl::StrCat("cannot ", what, " ", path, ": ", std::strerror(errno)));
}

}  // namespace

std::string EncodeUpdateRecord(const UpdateRecord& r) {
  std::string out(1, static_cast<char>(kVersion));
  PutDouble(&out, r.start_time);
  PutDouble(&out, r.duration_seconds);
  model::PutVarint64(&out, r.states_updated);
  PutDouble(&out, r.prediction_error_before);
  PutDouble(&out, r.prediction_error_after);
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

absl::Status WriteUpdateRecord(const std::string& path, const UpdateRecord& record) {
  const std::string bytes = EncodeUpdateRecord(record);
  const std::string temporary = path + ".tmp";
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0640);
  if (fd < 0) return Errno("create", temporary);
  const bool written = ::write(fd, bytes.data(), bytes.size()) == static_cast<ssize_t>(bytes.size()) && ::fsync(fd) == 0;
  const absl::Status failed = written ? absl::OkStatus() : Errno("write", temporary);
  ::close(fd);
  if (!failed.ok()) return failed;
  if (std::rename(temporary.c_str(), path.c_str()) != 0) return Errno("rename to", path);
  return absl::OkStatus();
}

absl::StatusOr<std::optional<UpdateRecord>> ReadUpdateRecord(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) {
    if (errno == ENOENT) return std::optional<UpdateRecord>();
    return Errno("read", path);
  }
  std::ostringstream bytes;
  bytes << in.rdbuf();
  auto record = DecodeUpdateRecord(bytes.str());
  if (!record.ok()) return absl::DataLossError(absl::StrCat(path, ": ", record.status().message()));
  return std::optional<UpdateRecord>(*std::move(record));
}

}  // namespace fremen::storage
