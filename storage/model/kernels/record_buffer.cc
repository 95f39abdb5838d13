#include "storage/model/kernels/record_buffer.h"

#include <algorithm>
#include <cstring>
#include <new>
#include <utility>

#ifdef __linux__
#include <sys/mman.h>
#endif

namespace fremen::model {
namespace {

constexpr size_t kLineAlignment = 64;
constexpr size_t kHugePage = size_t{2} << 20;
// Below this a block is not worth a huge page (and would waste up to 2 MiB of one).
constexpr size_t kHugeBlock = size_t{32} << 20;

size_t RoundUp(size_t x, size_t to) { return (x + to - 1) / to * to; }

}  // namespace

RecordBuffer::~RecordBuffer() {
  if (data_ != nullptr) ::operator delete (data_, std::align_val_t{alignment_});
}

RecordBuffer::RecordBuffer(RecordBuffer&& other) noexcept
    : stride_(other.stride_),
      size_(std::exchange(other.size_, 0)),
      capacity_(std::exchange(other.capacity_, 0)),
      alignment_(other.alignment_),
      data_(std::exchange(other.data_, nullptr)) {}

RecordBuffer& RecordBuffer::operator=(RecordBuffer&& other) noexcept {
  if (this != &other) {
    RecordBuffer old(std::move(*this));
    stride_ = other.stride_;
    size_ = std::exchange(other.size_, 0);
    capacity_ = std::exchange(other.capacity_, 0);
    alignment_ = other.alignment_;
    data_ = std::exchange(other.data_, nullptr);
  }
  return *this;
}

void RecordBuffer::Reserve(size_t n) {
  if (n <= capacity_) return;
  const size_t wanted = n * stride_;
  const size_t alignment = wanted >= kHugeBlock ? kHugePage : kLineAlignment;
  const size_t bytes = RoundUp(wanted, alignment);
  auto* fresh = static_cast<std::byte*>(::operator new (bytes, std::align_val_t{alignment}));
#if defined(__linux__) && defined(MADV_HUGEPAGE)
  // Only a hint: THP may be disabled, and then this fails harmlessly.
  if (alignment == kHugePage) madvise(fresh, bytes, MADV_HUGEPAGE);
#endif
  if (data_ != nullptr) {
    std::memcpy(fresh, data_, size_ * stride_);
    ::operator delete (data_, std::align_val_t{alignment_});
  }
  data_ = fresh;
  alignment_ = alignment;
  capacity_ = bytes / stride_;
}

void RecordBuffer::Resize(size_t n) {
  if (n > capacity_) Reserve(std::max(n, capacity_ + capacity_ / 2));
  if (n > size_) std::memset(record(size_), 0, (n - size_) * stride_);
  size_ = n;
}

}  // namespace fremen::model
