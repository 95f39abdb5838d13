// RecordBuffer: the storage under the batch kernels' flat tables (RecordArena, CompactModels,
// OrderErrorTable): `size` records of a fixed `stride` bytes in one 64-byte-aligned allocation.
//
// Why one block and not a vector of objects: the kernels stream over, or prefetch into, millions of
// records; a fixed stride makes record i's address a multiply, and cache-line alignment keeps a
// record from touching one more line than its size needs. Blocks of 32 MiB and more are 2 MiB-aligned
// and advised for transparent huge pages, so that random access to a multi-GB arena is not one TLB
// miss per record. New records are zero bytes. Growth reallocates and copies (amortised: capacity
// grows by half), so pointers into the buffer are invalidated by Resize/Reserve.
// Thread-safety: none; concurrent readers of an unchanging buffer are fine.
#pragma once

#include <cstddef>
#include <cstdint>

namespace fremen::model {

class RecordBuffer {
 public:
  // REQUIRES: stride > 0 and a multiple of 4.
  explicit RecordBuffer(size_t stride) : stride_(stride) {}
  ~RecordBuffer();
  RecordBuffer(RecordBuffer&& other) noexcept;
  RecordBuffer& operator=(RecordBuffer&& other) noexcept;
  RecordBuffer(const RecordBuffer&) = delete;
  RecordBuffer& operator=(const RecordBuffer&) = delete;

  size_t stride() const { return stride_; }
  size_t size() const { return size_; }
  size_t capacity() const { return capacity_; }
  size_t bytes() const { return capacity_ * stride_; }

  std::byte* record(size_t i) { return data_ + i * stride_; }
  const std::byte* record(size_t i) const { return data_ + i * stride_; }

  // Grows (new records zeroed) or shrinks to n records.
  void Resize(size_t n);
  // Makes room for n records without changing size().
  void Reserve(size_t n);

 private:
  size_t stride_;
  size_t size_ = 0;
  size_t capacity_ = 0;
  size_t alignment_ = 0;  // of the current allocation (needed to free it)
  std::byte* data_ = nullptr;
};

// Hints the CPU to fetch every cache line of [p, p + bytes), for reading or for writing (a
// read-modify-write is next). Records need not be line-aligned. Always inlined: GCC deems a function
// that only prefetches free of side effects and deletes calls to it (seen with GCC 12), so the
// prefetches must land in the caller's own loop.
template <bool kForWrite>
[[gnu::always_inline]] inline void PrefetchLines(const void* p, size_t bytes) {
  const uintptr_t begin = reinterpret_cast<uintptr_t>(p);
  for (uintptr_t line = begin & ~uintptr_t{63}; line < begin + bytes; line += 64) {
    __builtin_prefetch(reinterpret_cast<const void*>(line), kForWrite ? 1 : 0, 3);
  }
}
[[gnu::always_inline]] inline void PrefetchForRead(const void* p, size_t bytes) { PrefetchLines<false>(p, bytes); }
[[gnu::always_inline]] inline void PrefetchForWrite(const void* p, size_t bytes) { PrefetchLines<true>(p, bytes); }

}  // namespace fremen::model
