// Recovery's log reader (storage/wal/wal.h ReplayWal) over segment files made from the input, and
// each replayed payload decoded as recovery does (storage/batch.h DecodeBatch). Replay must deliver
// consecutive LSNs above the checkpoint's, and never more than the log holds.
//
// Input: a flags byte, a split byte, then the log's bytes (records as wal.h lays them out). Random
// bytes almost never carry a valid CRC-32, so flag bit 0 recomputes each record's CRC (and bit 1
// renumbers the LSNs from 1) before the files are written: the fuzzer then explores the framing and
// the payloads behind it. Bit 4 splits the log into two segments after record (split % 8). Bits 2-3
// choose the checkpoint LSN replay starts after (0, 1, 3 or the last LSN).
#include <zlib.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "absl/strings/str_format.h"
#include "fuzz/fuzz_util.h"
#include "storage/batch.h"
#include "storage/wal/wal.h"

namespace {

constexpr size_t kHeader = 16;  // u32 length | u32 CRC-32 of (LSN, payload) | u64 LSN

uint32_t Get32(const uint8_t* p) { return p[0] | p[1] << 8 | p[2] << 16 | static_cast<uint32_t>(p[3]) << 24; }
void Put32(uint8_t* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}
void Put64(uint8_t* p, uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<uint8_t>(v >> (8 * i));
}
uint64_t Get64(const uint8_t* p) {
  uint64_t v = 0;
  for (int i = 7; i >= 0; --i) v = v << 8 | p[i];
  return v;
}

void WriteFile(const std::string& path, const uint8_t* data, size_t size) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  FUZZ_CHECK(f != nullptr, path);
  FUZZ_CHECK(std::fwrite(data, 1, size, f) == size || size == 0, path);
  std::fclose(f);
}

std::string SegmentPath(const std::string& dir, uint64_t first_lsn) {
  return absl::StrFormat("%s/wal-%020d.log", dir, first_lsn);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace fremen;
  if (size < 2) return 0;
  const uint8_t flags = data[0], split = data[1];
  std::vector<uint8_t> log(data + 2, data + size);
  // The record boundaries the framing gives (the lengths as written), fixing CRCs and LSNs.
  std::vector<size_t> ends;
  uint64_t lsn = 1;
  for (size_t pos = 0; log.size() - pos >= kHeader;) {
    const uint32_t length = Get32(&log[pos]);
    if (log.size() - pos - kHeader < length) break;
    if (flags & 2) Put64(&log[pos + 8], lsn);
    if (flags & 1) {
      uLong crc = crc32(0L, Z_NULL, 0);
      crc = crc32(crc, &log[pos + 8], 8);
      crc = crc32(crc, &log[pos + kHeader], length);
      Put32(&log[pos + 4], static_cast<uint32_t>(crc));
    }
    ++lsn;
    pos += kHeader + length;
    ends.push_back(pos);
  }
  // One directory for the whole run (in memory when /dev/shm exists), emptied after each input.
  // Never destroyed: the exit handler that removes it may run after the static destructors.
  static const std::string& dir = *[] {
    std::string pattern = (std::filesystem::exists("/dev/shm") ? std::filesystem::path("/dev/shm")
                                                               : std::filesystem::temp_directory_path()) /
                          "fremen-fuzz-wal-XXXXXX";
    FUZZ_CHECK(mkdtemp(pattern.data()) != nullptr, "a temporary directory");
    auto* path = new std::string(pattern);
    std::atexit([] { std::filesystem::remove_all(dir); });
    return path;
  }();
  const size_t records_before_cut = (flags & 16) && !ends.empty() ? std::min<size_t>(split % 8, ends.size() - 1) + 1 : 0;
  const size_t cut = records_before_cut > 0 ? ends[records_before_cut - 1] : log.size();
  std::vector<std::string> written = {SegmentPath(dir, 1)};
  WriteFile(written[0], log.data(), cut);
  if (cut < log.size()) {
    // Named after the LSN its first record carries (as the writer names a segment), else the next.
    const uint64_t second_first = log.size() - cut >= kHeader ? Get64(&log[cut + 8]) : records_before_cut + 1;
    written.push_back(SegmentPath(dir, second_first));
    WriteFile(written.back(), log.data() + cut, log.size() - cut);
  }
  const uint64_t afters[4] = {0, 1, 3, lsn - 1};
  const uint64_t after = afters[(flags >> 2) & 3];
  uint64_t expected = after + 1, delivered = 0;
  auto replay = storage::ReplayWal(dir, after, [&](uint64_t record_lsn, std::span<const uint8_t> payload) {
    FUZZ_CHECK(record_lsn >= expected, "LSNs increase and are above the checkpoint");
    expected = record_lsn + 1;
    ++delivered;
    auto batch = storage::DecodeBatch(fuzz::AsView(payload.data(), payload.size()));
    if (batch.ok()) {
      auto again = storage::DecodeBatch(storage::EncodeBatch(*batch));
      FUZZ_CHECK(again.ok(), again.status().ToString());
    }
    return absl::OkStatus();
  });
  for (const std::string& path : written) std::remove(path.c_str());
  if (!replay.ok()) return 0;
  FUZZ_CHECK(replay->records == delivered, "records counts the callback's calls");
  FUZZ_CHECK(delivered <= ends.size(), "no more records than the log holds");
  return 0;
}
