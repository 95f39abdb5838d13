// A set of slot indices (non-negative integers) stored as its toggle points, Δ-encoded as varints
// (the FreMEn paper, Krajník et al., IEEE T-RO 2017, eq. 8: "a sequence of values indicating the
// starts and ends of time intervals"; docs/model.md, "Lossless history").
//
// Toggle points p_0 < p_1 < ... : slot x is a member iff an odd number of points are ≤ x, so the
// members are [p_0, p_1) ∪ [p_2, p_3) ∪ ... and, with an odd number of points, [p_last, ∞). The open
// end is what makes eq. 8 cheap for the outlier set O: a run of consecutive outliers, or a gap of
// unobserved slots, costs nothing until the state starts matching again. The same type stores the
// coverage (which sampling slots were observed), which is always closed.
//
// Memory is the encoding itself: one varint per toggle point (the distance to the previous one; the
// first from 0), typically a byte or two. Toggling at or after the last point is O(1) (the common
// append); anything else is a scan of the bytes, O(toggle points).
// Thread-safety: a value type; const methods may be called concurrently.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "storage/model/varint.h"

namespace fremen::model {

class SlotSet {
 public:
  // The end of an open interval.
  static constexpr uint64_t kOpenEnd = UINT64_MAX;
  // Toggle points are below this (leaves room for x + 1 and kOpenEnd).
  static constexpr uint64_t kMaxPoint = uint64_t{1} << 62;

  struct Interval {
    uint64_t begin;
    uint64_t end;  // exclusive; kOpenEnd for the open last interval
    bool operator==(const Interval&) const = default;
  };

  // Walks the set in increasing slot order. Seek(x) with non-decreasing x is amortised O(1) per
  // toggle point passed, so merging several sets over a range is linear.
  class Cursor {
   public:
    explicit Cursor(const SlotSet& set);
    // Whether slot x is a member. REQUIRES: x ≥ every earlier argument.
    bool Seek(uint64_t x);
    // The first slot after the last sought one where membership changes (kOpenEnd: never); before
    // any Seek, the first toggle point.
    uint64_t next_change() const { return has_next_ ? next_ : kOpenEnd; }

   private:
    void Advance();
    const char* p_;
    const char* end_;
    uint64_t next_ = 0;
    bool has_next_ = false;
    bool member_ = false;
  };

  SlotSet() = default;

  bool empty() const { return toggles_ == 0; }
  size_t toggle_count() const { return toggles_; }
  // Whether the last interval is open (an odd number of toggle points).
  bool open() const { return (toggles_ & 1) != 0; }
  // The first and last toggle points. REQUIRES: !empty().
  uint64_t first_point() const;
  uint64_t last_point() const { return last_; }

  bool contains(uint64_t slot) const;
  // Flips the membership of every slot ≥ `slot` (adds or removes the toggle point `slot`).
  // REQUIRES: slot < kMaxPoint.
  void Toggle(uint64_t slot);
  // Flips the membership of `slot` alone. REQUIRES: slot + 1 < kMaxPoint.
  void Flip(uint64_t slot);
  void Insert(uint64_t slot) {
    if (!contains(slot)) Flip(slot);
  }
  void Erase(uint64_t slot) {
    if (contains(slot)) Flip(slot);
  }
  void Clear() { *this = SlotSet(); }

  // Members in [begin, end) (eq. 15's |(t_a, t_b) ∩ O|).
  uint64_t Count(uint64_t begin, uint64_t end) const;

  // Calls f(Interval) for every interval, in order.
  template <typename F>
  void ForEachInterval(F&& f) const {
    Cursor c(*this);
    uint64_t x = c.next_change();
    while (x != kOpenEnd) {
      c.Seek(x);  // x is a toggle point: membership starts here
      const uint64_t end = c.next_change();
      f(Interval{x, end});
      if (end == kOpenEnd) break;
      c.Seek(end);
      x = c.next_change();
    }
  }
  std::vector<Interval> Intervals() const;

  // The varint Δs alone, and the whole encoding (a varint byte length, then the Δs).
  size_t byte_size() const { return bytes_.size(); }
  size_t encoded_size() const { return Varint64Length(bytes_.size()) + bytes_.size(); }
  void EncodeTo(std::string* out) const;
  // Reads what EncodeTo wrote; errors (sticky in `reader`) name `field`. Rejects truncated bytes,
  // bad varints and points that are not strictly increasing or not below kMaxPoint.
  static SlotSet Decode(ByteReader& reader, std::string_view field);

  bool operator==(const SlotSet& other) const { return bytes_ == other.bytes_; }

 private:
  // Removes the last toggle point. REQUIRES: !empty().
  void RemoveLast();
  // Adds or removes the point x < last_.
  void ToggleBefore(uint64_t x);
  // Recomputes last_offset_ by scanning back over the varint that ends the bytes.
  void FindLastOffset();

  std::string bytes_;     // varint Δs: p_0, p_1 − p_0, p_2 − p_1, ...
  size_t toggles_ = 0;    // number of toggle points
  uint64_t last_ = 0;     // the last toggle point (0 when empty)
  size_t last_offset_ = 0;  // where the last varint starts in bytes_
};

// |a ∩ b ∩ [begin, end)|: e.g. outlier slots that were observed (eq. 15 restricted to observations).
uint64_t CountCommon(const SlotSet& a, const SlotSet& b, uint64_t begin, uint64_t end);

}  // namespace fremen::model
