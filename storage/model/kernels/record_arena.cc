#include "storage/model/kernels/record_arena.h"

#include <cstring>

namespace fremen::model {

RecordArena::RecordArena(size_t periods, size_t size)
    : periods_(periods), body_bytes_(BodyBytes(periods)), buffer_(StrideFor(periods)) {
  buffer_.Resize(size);
}

size_t RecordArena::Append() {
  const size_t i = size();
  buffer_.Resize(i + 1);
  return i;
}

void RecordArena::Store(size_t i, const CompactSpectrum& spectrum) {
  header(i) = spectrum.header();
  std::memcpy(body(i), spectrum.body(), body_bytes_);
}

void RecordArena::Load(size_t i, CompactSpectrum& spectrum) const {
  spectrum.mutable_header() = header(i);
  std::memcpy(spectrum.body(), body(i), body_bytes_);
}

}  // namespace fremen::model
