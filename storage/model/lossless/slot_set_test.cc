#include "storage/model/lossless/slot_set.h"

#include <cstdint>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "gtest/gtest.h"

namespace fremen::model {
namespace {

using Interval = SlotSet::Interval;

// `bytes` decoded as the lossless history decodes its sets (SlotSet::Decode on its ByteReader), the
// reader then finished, so that bytes left after the set are an error too.
absl::StatusOr<SlotSet> DecodeWhole(std::string_view bytes) {
  ByteReader reader(bytes, "slot set");
  SlotSet set = SlotSet::Decode(reader, "set");
  if (absl::Status s = reader.Finish(); !s.ok()) return s;
  return set;
}

// Membership of slots [0, size) as a plain vector; slots ≥ size take the value of `tail`.
struct Reference {
  std::vector<bool> member;
  bool tail = false;
  bool contains(uint64_t x) const { return x < member.size() ? member[x] : tail; }
  void Toggle(uint64_t x) {
    for (uint64_t i = x; i < member.size(); ++i) member[i] = !member[i];
    tail = !tail;
  }
  void Flip(uint64_t x) { member[x] = !member[x]; }
  uint64_t Count(uint64_t a, uint64_t b) const {
    uint64_t n = 0;
    for (uint64_t i = a; i < b; ++i) n += contains(i);
    return n;
  }
};

void ExpectSame(const SlotSet& set, const Reference& ref) {
  for (uint64_t x = 0; x < ref.member.size() + 3; ++x) ASSERT_EQ(set.contains(x), ref.contains(x)) << "slot " << x;
  EXPECT_EQ(set.open(), ref.tail);
  // Intervals: consistent with membership and strictly increasing.
  uint64_t previous_end = 0;
  bool first = true;
  set.ForEachInterval([&](Interval i) {
    EXPECT_LT(i.begin, i.end);
    if (!first) {
      EXPECT_LT(previous_end, i.begin);
    }
    first = false;
    previous_end = i.end;
    EXPECT_TRUE(ref.contains(i.begin));
    if (i.begin > 0) {
      EXPECT_FALSE(ref.contains(i.begin - 1));
    }
    if (i.end != SlotSet::kOpenEnd) {
      EXPECT_FALSE(ref.contains(i.end));
    }
  });
}

TEST(SlotSet, EmptySet) {
  SlotSet set;
  EXPECT_TRUE(set.empty());
  EXPECT_FALSE(set.contains(0));
  EXPECT_FALSE(set.contains(SlotSet::kMaxPoint));
  EXPECT_EQ(set.Count(0, 1000), 0u);
  EXPECT_TRUE(set.Intervals().empty());
  std::string bytes;
  set.EncodeTo(&bytes);
  EXPECT_EQ(bytes, std::string(1, '\0'));
  EXPECT_EQ(set.encoded_size(), 1u);
  EXPECT_EQ(*DecodeWhole(bytes), set);
}

TEST(SlotSet, TogglePointsDelimitIntervalsAndTheLastMayBeOpen) {
  SlotSet set;
  set.Toggle(3);
  EXPECT_TRUE(set.open());
  EXPECT_FALSE(set.contains(2));
  EXPECT_TRUE(set.contains(3));
  EXPECT_TRUE(set.contains(1'000'000));
  EXPECT_EQ(set.Intervals(), (std::vector<Interval>{{3, SlotSet::kOpenEnd}}));
  set.Toggle(7);
  set.Toggle(10);
  EXPECT_EQ(set.Intervals(), (std::vector<Interval>{{3, 7}, {10, SlotSet::kOpenEnd}}));
  EXPECT_EQ(set.Count(0, 20), 4u + 10u);
  EXPECT_EQ(set.Count(5, 11), 2u + 1u);
  EXPECT_EQ(set.first_point(), 3u);
  EXPECT_EQ(set.last_point(), 10u);
  EXPECT_EQ(set.toggle_count(), 3u);
  // Toggling the last point again removes it.
  set.Toggle(10);
  EXPECT_EQ(set.Intervals(), (std::vector<Interval>{{3, 7}}));
  EXPECT_FALSE(set.open());
}

TEST(SlotSet, AppendingContiguousSlotsGrowsOneInterval) {
  SlotSet set;
  for (uint64_t x = 100; x < 1'000'100; ++x) set.Insert(x);
  EXPECT_EQ(set.Intervals(), (std::vector<Interval>{{100, 1'000'100}}));
  EXPECT_EQ(set.toggle_count(), 2u);
  EXPECT_LE(set.byte_size(), 4u);
  set.Insert(2'000'000);
  EXPECT_EQ(set.Count(0, SlotSet::kOpenEnd), 1'000'001u);
}

TEST(SlotSet, PointZeroAndFlipsAtTheEdges) {
  SlotSet set;
  set.Flip(0);
  EXPECT_EQ(set.Intervals(), (std::vector<Interval>{{0, 1}}));
  set.Flip(1);
  EXPECT_EQ(set.Intervals(), (std::vector<Interval>{{0, 2}}));
  set.Flip(0);
  EXPECT_EQ(set.Intervals(), (std::vector<Interval>{{1, 2}}));
  set.Flip(1);
  EXPECT_TRUE(set.empty());
  EXPECT_EQ(set.byte_size(), 0u);
  set.Flip(SlotSet::kMaxPoint - 2);
  EXPECT_TRUE(set.contains(SlotSet::kMaxPoint - 2));
  EXPECT_EQ(*DecodeWhole([&] {
    std::string b;
    set.EncodeTo(&b);
    return b;
  }()),
            set);
}

// Random toggles, flips, inserts and erases anywhere, checked against a plain vector.
TEST(SlotSet, RandomOperationsMatchAReference) {
  std::mt19937_64 rng(42);
  for (int trial = 0; trial < 40; ++trial) {
    const uint64_t size = 1 + rng() % 400;
    SlotSet set;
    Reference ref{std::vector<bool>(size, false)};
    for (int op = 0; op < 300; ++op) {
      // Bias towards the end, the common case, but hit the middle and the start too.
      uint64_t x = rng() % 3 == 0 ? rng() % size : (size > 8 ? size - 1 - rng() % 8 : rng() % size);
      switch (rng() % 4) {
        case 0:
          set.Toggle(x);
          ref.Toggle(x);
          break;
        case 1:
          if (x + 1 < size) {
            set.Flip(x);
            ref.Flip(x);
          }
          break;
        case 2:
          if (x + 1 < size) {
            set.Insert(x);
            ref.member[x] = true;
          }
          break;
        default:
          if (x + 1 < size) {
            set.Erase(x);
            ref.member[x] = false;
          }
      }
      if (op % 50 == 0) ExpectSame(set, ref);
    }
    ExpectSame(set, ref);
    for (int q = 0; q < 50; ++q) {
      uint64_t a = rng() % (size + 5), b = rng() % (size + 5);
      if (a > b) std::swap(a, b);
      EXPECT_EQ(set.Count(a, b), ref.Count(a, b)) << a << ".." << b;
    }
    std::string bytes;
    set.EncodeTo(&bytes);
    EXPECT_EQ(bytes.size(), set.encoded_size());
    absl::StatusOr<SlotSet> decoded = DecodeWhole(bytes);
    ASSERT_TRUE(decoded.ok()) << decoded.status();
    EXPECT_EQ(*decoded, set);
    EXPECT_EQ(decoded->toggle_count(), set.toggle_count());
    EXPECT_EQ(decoded->last_point(), set.last_point());
    // A decoded set keeps working: appends after decode use its recovered end.
    decoded->Toggle(size + 10);
    set.Toggle(size + 10);
    EXPECT_EQ(*decoded, set);
  }
}

TEST(SlotSet, CountCommonMatchesBruteForce) {
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 30; ++trial) {
    SlotSet a, b;
    Reference ra{std::vector<bool>(300, false)}, rb{std::vector<bool>(300, false)};
    for (uint64_t x = 0; x < 300; ++x) {
      if (rng() % 7 == 0) {
        a.Toggle(x);
        ra.Toggle(x);
      }
      if (rng() % 5 == 0) {
        b.Toggle(x);
        rb.Toggle(x);
      }
    }
    for (int q = 0; q < 30; ++q) {
      uint64_t lo = rng() % 320, hi = rng() % 320;
      if (lo > hi) std::swap(lo, hi);
      uint64_t expected = 0;
      for (uint64_t x = lo; x < hi; ++x) expected += ra.contains(x) && rb.contains(x);
      EXPECT_EQ(CountCommon(a, b, lo, hi), expected);
    }
  }
}

TEST(SlotSet, DecodeRejectsCorruptedBytes) {
  // Points must increase: Δ = 0 after the first point repeats it.
  std::string repeated;
  PutVarint64(&repeated, 2);
  repeated += std::string("\x05\x00", 2);
  absl::StatusOr<SlotSet> s = DecodeWhole(repeated);
  EXPECT_EQ(s.status().code(), absl::StatusCode::kDataLoss);
  EXPECT_NE(s.status().message().find("repeats point 5"), std::string::npos) << s.status();

  // A length longer than the bytes left.
  std::string long_length;
  PutVarint64(&long_length, 1000);
  long_length += "\x01";
  s = DecodeWhole(long_length);
  EXPECT_NE(s.status().message().find("exceeds"), std::string::npos) << s.status();

  // A varint that runs past the set's own length.
  s = DecodeWhole(std::string("\x01\x81\x01", 3));
  EXPECT_EQ(s.status().code(), absl::StatusCode::kDataLoss);

  // Points beyond kMaxPoint.
  std::string huge;
  std::string body;
  PutVarint64(&body, SlotSet::kMaxPoint);
  PutVarint64(&huge, body.size());
  huge += body;
  EXPECT_FALSE(DecodeWhole(huge).ok());

  // Trailing bytes.
  EXPECT_FALSE(DecodeWhole(std::string("\x01\x05\x00", 3)).ok());
}

TEST(SlotSet, FuzzedEncodingsNeverCrashAndValidOnesAreCanonical) {
  std::mt19937_64 rng(11);
  SlotSet set;
  uint64_t x = 0;
  for (int i = 0; i < 200; ++i) {
    x += 1 + rng() % (i % 3 == 0 ? 100000 : 50);
    set.Toggle(x);
  }
  std::string good;
  set.EncodeTo(&good);
  for (int trial = 0; trial < 5000; ++trial) {
    std::string bytes = good;
    if (trial % 2 == 0) {
      bytes.resize(rng() % bytes.size());
    } else {
      for (int flips = 1 + rng() % 3; flips > 0; --flips) bytes[rng() % bytes.size()] ^= static_cast<char>(1 << (rng() % 8));
    }
    absl::StatusOr<SlotSet> decoded = DecodeWhole(bytes);
    if (!decoded.ok()) {
      EXPECT_EQ(decoded.status().code(), absl::StatusCode::kDataLoss);
      continue;
    }
    std::string again;
    decoded->EncodeTo(&again);
    EXPECT_EQ(again, bytes);
    (void)decoded->Count(0, SlotSet::kOpenEnd);
  }
}

}  // namespace
}  // namespace fremen::model
