// Damage done to files as a bad disk or a stray write would, for the integrity tests: single bit flips and zeroed
// pages, at places found by content (a record's bytes) or by offset.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <iterator>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace fremen::storage::testing {

inline std::string ReadWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

inline void WriteWholeFile(const std::string& path, std::string_view bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  ASSERT_TRUE(out.good()) << "cannot write " << path;
}

// Writes `bytes` over the file's bytes from `offset` on (a stray write, a flipped run).
inline void OverwriteBytes(const std::string& path, uint64_t offset, std::string_view bytes) {
  std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
  f.seekp(static_cast<std::streamoff>(offset));
  f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  ASSERT_TRUE(f.good()) << "cannot write " << path;
}

// Offset of the only occurrence of `needle` in `bytes`; npos when absent or not unique (a test that damages "the
// record" must know it hit that record and nothing else).
inline size_t FindUnique(std::string_view bytes, std::span<const uint8_t> needle) {
  const std::string_view n(reinterpret_cast<const char*>(needle.data()), needle.size());
  const size_t at = bytes.find(n);
  if (at == std::string_view::npos || bytes.find(n, at + 1) != std::string_view::npos) return std::string_view::npos;
  return at;
}

// Offsets of every occurrence of `needle` in `bytes`. LMDB copies a page on write, so a file holds the live copy of a
// record and may hold stale ones on free pages: damaging "the record" means damaging them all (the stale ones are never
// read).
inline std::vector<size_t> FindAll(std::string_view bytes, std::span<const uint8_t> needle) {
  const std::string_view n(reinterpret_cast<const char*>(needle.data()), needle.size());
  std::vector<size_t> found;
  for (size_t at = bytes.find(n); at != std::string_view::npos; at = bytes.find(n, at + 1)) found.push_back(at);
  return found;
}

// Flips bit `bit` (0 = the lowest) of byte `offset` of the file.
inline void FlipBit(const std::string& path, size_t offset, int bit) {
  std::fstream f(path, std::ios::binary | std::ios::in | std::ios::out);
  ASSERT_TRUE(f.good()) << "cannot open " << path;
  f.seekg(static_cast<std::streamoff>(offset));
  char c = 0;
  f.read(&c, 1);
  ASSERT_TRUE(f.good()) << path << " has no byte " << offset;
  c = static_cast<char>(c ^ (1 << bit));
  f.seekp(static_cast<std::streamoff>(offset));
  f.write(&c, 1);
  ASSERT_TRUE(f.good());
}

// Overwrites page `page` (of `page_size` bytes) of the file with zeros.
inline void ZeroPage(const std::string& path, size_t page, size_t page_size = 4096) {
  std::fstream f(path, std::ios::binary | std::ios::in | std::ios::out);
  ASSERT_TRUE(f.good()) << "cannot open " << path;
  f.seekp(static_cast<std::streamoff>(page * page_size));
  const std::string zeros(page_size, '\0');
  f.write(zeros.data(), static_cast<std::streamsize>(zeros.size()));
  ASSERT_TRUE(f.good());
}

}  // namespace fremen::storage::testing
