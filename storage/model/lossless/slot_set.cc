#include "storage/model/lossless/slot_set.h"

#include <algorithm>

#include "absl/strings/str_cat.h"

namespace fremen::model {

namespace {

// Reads a varint from bytes this set wrote or Decode validated; stops at `end` regardless.
inline uint64_t ReadTrustedVarint(const char*& p, const char* end) {
  uint64_t v = 0;
  for (int shift = 0; p < end && shift < 64; shift += 7) {
    const auto b = static_cast<unsigned char>(*p++);
    v |= static_cast<uint64_t>(b & 0x7f) << shift;
    if ((b & 0x80) == 0) break;
  }
  return v;
}

std::string VarintBytes(uint64_t v) {
  std::string s;
  PutVarint64(&s, v);
  return s;
}

}  // namespace

SlotSet::Cursor::Cursor(const SlotSet& set) : p_(set.bytes_.data()), end_(set.bytes_.data() + set.bytes_.size()) {
  Advance();
}

void SlotSet::Cursor::Advance() {
  if (p_ == end_) {
    has_next_ = false;
    return;
  }
  // Δs are from the previous point; the first from 0, which next_ starts at.
  next_ += ReadTrustedVarint(p_, end_);
  has_next_ = true;
}

bool SlotSet::Cursor::Seek(uint64_t x) {
  while (has_next_ && next_ <= x) {
    member_ = !member_;
    Advance();
  }
  return member_;
}

uint64_t SlotSet::first_point() const {
  const char* p = bytes_.data();
  return ReadTrustedVarint(p, bytes_.data() + bytes_.size());
}

bool SlotSet::contains(uint64_t slot) const {
  if (toggles_ == 0) return false;
  if (slot >= last_) return open();
  // Just before the last point (the newest slot of a closed coverage set): all points but one are ≤ it.
  if (slot + 1 == last_) return !open();
  Cursor c(*this);
  return c.Seek(slot);
}

void SlotSet::Toggle(uint64_t slot) {
  if (toggles_ > 0 && slot < last_) {
    ToggleBefore(slot);
  } else if (toggles_ > 0 && slot == last_) {
    RemoveLast();
  } else {
    last_offset_ = bytes_.size();
    PutVarint64(&bytes_, slot - last_);  // last_ is 0 when empty: the first Δ is from 0
    last_ = slot;
    ++toggles_;
  }
}

void SlotSet::Flip(uint64_t slot) {
  // slot first: when slot is at or after the last point both toggles are O(1) appends/removals.
  Toggle(slot);
  Toggle(slot + 1);
}

void SlotSet::RemoveLast() {
  const char* p = bytes_.data() + last_offset_;
  const uint64_t delta = ReadTrustedVarint(p, bytes_.data() + bytes_.size());
  bytes_.resize(last_offset_);
  --toggles_;
  last_ -= delta;  // becomes 0 when the set empties
  FindLastOffset();
}

void SlotSet::FindLastOffset() {
  if (bytes_.empty()) {
    last_offset_ = 0;
    return;
  }
  // The last byte ends the last varint (high bit clear); the varint starts after the previous byte
  // with a clear high bit, i.e. after the end of the varint before it.
  size_t i = bytes_.size() - 1;
  while (i > 0 && (static_cast<unsigned char>(bytes_[i - 1]) & 0x80) != 0) --i;
  last_offset_ = i;
}

void SlotSet::ToggleBefore(uint64_t x) {
  // Find the first point p_i ≥ x, with p_{i-1} (0 before the first) and the byte range of Δ_i.
  const char* const begin = bytes_.data();
  const char* const end = begin + bytes_.size();
  const char* p = begin;
  uint64_t prev = 0;
  uint64_t point = 0;
  const char* at = p;
  for (;;) {
    at = p;
    point = prev + ReadTrustedVarint(p, end);
    if (point >= x) break;  // always reached: x < last_
    prev = point;
  }
  const size_t from = at - begin;
  size_t to = p - begin;
  std::string replacement;
  if (point == x) {
    // Remove p_i: Δ_i and Δ_{i+1} merge into p_{i+1} − p_{i−1}. p_i < last_, so p_{i+1} exists.
    const uint64_t next = point + ReadTrustedVarint(p, end);
    to = p - begin;
    replacement = VarintBytes(next - prev);
    --toggles_;
  } else {
    // Insert x between p_{i−1} and p_i.
    replacement = VarintBytes(x - prev) + VarintBytes(point - x);
    ++toggles_;
  }
  const bool touches_last = to == bytes_.size();
  bytes_.replace(from, to - from, replacement);
  if (touches_last) {
    FindLastOffset();
  } else {
    last_offset_ = last_offset_ + replacement.size() - (to - from);
  }
}

uint64_t SlotSet::Count(uint64_t begin, uint64_t end) const {
  uint64_t count = 0;
  Cursor c(*this);
  uint64_t x = begin;
  while (x < end) {
    const bool member = c.Seek(x);
    const uint64_t run_end = std::min(c.next_change(), end);
    if (member) count += run_end - x;
    x = run_end;
  }
  return count;
}

std::vector<SlotSet::Interval> SlotSet::Intervals() const {
  std::vector<Interval> out;
  ForEachInterval([&out](Interval i) { out.push_back(i); });
  return out;
}

void SlotSet::EncodeTo(std::string* out) const {
  PutVarint64(out, bytes_.size());
  out->append(bytes_);
}

SlotSet SlotSet::Decode(ByteReader& reader, std::string_view field) {
  SlotSet set;
  const uint64_t length = reader.Varint(std::string(field) + " byte length");
  if (!reader.ok()) return set;
  if (length > reader.remaining()) {
    reader.Fail(field, absl::StrCat("byte length ", length, " exceeds the ", reader.remaining(), " bytes left"));
    return set;
  }
  const size_t start = reader.offset();
  const size_t stop = start + length;
  const std::string point_field = std::string(field) + " toggle point";
  uint64_t point = 0;
  size_t toggles = 0;
  size_t last_offset = 0;
  while (reader.ok() && reader.offset() < stop) {
    last_offset = reader.offset() - start;
    const uint64_t delta = reader.Varint(point_field);
    if (!reader.ok()) break;
    if (reader.offset() > stop) {
      reader.Fail(point_field, "varint runs past the end of the set");
    } else if (toggles > 0 && delta == 0) {
      reader.Fail(point_field, absl::StrCat("repeats point ", point, " (points must increase)"));
    } else if (delta >= kMaxPoint - point) {
      reader.Fail(point_field, absl::StrCat("exceeds the largest slot ", kMaxPoint - 1));
    }
    point += delta;
    ++toggles;
  }
  if (!reader.ok()) return SlotSet();
  // The bytes are canonical varints, so they are kept as they are: re-encoding is a copy.
  set.bytes_ = std::string(reader.Since(start));
  set.toggles_ = toggles;
  set.last_ = point;
  set.last_offset_ = last_offset;
  return set;
}

uint64_t CountCommon(const SlotSet& a, const SlotSet& b, uint64_t begin, uint64_t end) {
  uint64_t count = 0;
  SlotSet::Cursor ca(a), cb(b);
  uint64_t x = begin;
  while (x < end) {
    // Both cursors move to x, whatever the first answers.
    const bool in_a = ca.Seek(x);
    const bool in_b = cb.Seek(x);
    const bool both = in_a && in_b;
    const uint64_t run_end = std::min({ca.next_change(), cb.next_change(), end});
    if (both) count += run_end - x;
    x = run_end;
  }
  return count;
}

}  // namespace fremen::model
