#include "storage/dedup_table.h"

#include <algorithm>
#include <vector>

#include "absl/strings/str_cat.h"
#include "storage/model/varint.h"

namespace fremen::storage {

namespace {

// The first byte of an encoded table. Version 1 (writer, highest sequence) pairs without a version
// byte is not read: it knew no fingerprints.
constexpr uint8_t kFormat = 2;

}  // namespace

absl::StatusOr<bool> DedupTable::Seen(uint64_t writer, uint64_t sequence, uint64_t fingerprint) const {
  auto it = writers_.find(writer);
  if (it == writers_.end()) return false;
  const Writer& w = it->second;
  const uint64_t last = w.recent.rbegin()->first;
  if (auto entry = w.recent.find(sequence); entry != w.recent.end()) {
    if (entry->second == fingerprint) return true;
    return absl::AlreadyExistsError(absl::StrCat("writer ", writer, " sequence ", sequence,
                                                 " was already used for a different batch; continue after sequence ",
                                                 last));
  }
  if (sequence < w.floor) {
    return absl::AlreadyExistsError(absl::StrCat(
        "writer ", writer, " sequence ", sequence, " is older than the last ", kWindow,
        " sequences the map remembers of this writer, so a retry cannot be told from new data; continue after "
        "sequence ",
        last));
  }
  return false;
}

void DedupTable::Record(uint64_t writer, uint64_t sequence, uint64_t fingerprint) {
  Writer& w = writers_[writer];  // a new writer's floor is 0: the sequence is kept
  if (sequence < w.floor) return;
  w.recent.insert_or_assign(sequence, fingerprint);
  while (w.recent.size() > kWindow) {
    // Not UINT64_MAX: kWindow sequences are above it.
    w.floor = w.recent.begin()->first + 1;
    w.recent.erase(w.recent.begin());
  }
}

uint64_t DedupTable::LastSequence(uint64_t writer) const {
  auto it = writers_.find(writer);
  return it == writers_.end() ? 0 : it->second.recent.rbegin()->first;
}

void DedupTable::MergeFrom(const DedupTable& other) {
  for (const auto& [writer, theirs] : other.writers_) {
    Writer& mine = writers_[writer];
    if (theirs.floor > mine.floor) {
      mine.floor = theirs.floor;
      mine.recent.erase(mine.recent.begin(), mine.recent.lower_bound(mine.floor));
    }
    for (const auto& [sequence, fingerprint] : theirs.recent) Record(writer, sequence, fingerprint);
    if (mine.recent.empty()) writers_.erase(writer);  // only when `other` was malformed
  }
}

// Layout: format byte; writer count varint; per writer, by ascending id: writer varint, floor
// varint, sequence count varint (1..kWindow), then per sequence, ascending: the step from the
// previous one varint (for the first: from the floor, ≥ 0; then ≥ 1) and the fingerprint fixed64.
std::string DedupTable::Encode() const {
  std::vector<uint64_t> ids;
  ids.reserve(writers_.size());
  for (const auto& [writer, w] : writers_) ids.push_back(writer);
  std::sort(ids.begin(), ids.end());
  std::string out(1, static_cast<char>(kFormat));
  model::PutVarint64(&out, ids.size());
  for (uint64_t writer : ids) {
    const Writer& w = writers_.at(writer);
    model::PutVarint64(&out, writer);
    model::PutVarint64(&out, w.floor);
    model::PutVarint64(&out, w.recent.size());
    uint64_t previous = w.floor;  // the first sequence is ≥ floor, the others above the previous
    for (const auto& [sequence, fingerprint] : w.recent) {
      model::PutVarint64(&out, sequence - previous);
      model::PutFixed64(&out, fingerprint);
      previous = sequence;
    }
  }
  return out;
}

absl::StatusOr<DedupTable> DedupTable::Decode(std::string_view bytes) {
  model::ByteReader r(bytes, "dedup table");
  DedupTable table;
  if (const uint8_t format = r.Byte("format"); r.ok() && format != kFormat) {
    r.Fail("format", absl::StrCat("is ", format, ", expected ", kFormat));
  }
  const uint64_t count = r.Varint("writer count");
  // Each writer takes at least 12 bytes: a bound that keeps a damaged count from allocating.
  if (r.ok() && count > r.remaining() / 12) r.Fail("writer count", "more than the bytes left");
  uint64_t previous_writer = 0;
  for (uint64_t i = 0; r.ok() && i < count; ++i) {
    const uint64_t writer = r.Varint("writer");
    if (r.ok() && i > 0 && writer <= previous_writer) r.Fail("writer", "not above the previous writer");
    previous_writer = writer;
    Writer w;
    w.floor = r.Varint("floor");
    const uint64_t sequences = r.Varint("sequence count");
    if (r.ok() && (sequences == 0 || sequences > kWindow)) {
      r.Fail("sequence count", absl::StrCat("must be in [1, ", kWindow, "]"));
    }
    uint64_t sequence = w.floor;
    for (uint64_t j = 0; r.ok() && j < sequences; ++j) {
      const uint64_t step = r.Varint("sequence step");
      const uint64_t fingerprint = r.Fixed64("fingerprint");
      if (r.ok() && ((j > 0 && step == 0) || sequence + step < sequence)) r.Fail("sequence step", "not ascending");
      sequence += step;
      w.recent.emplace_hint(w.recent.end(), sequence, fingerprint);
    }
    if (r.ok()) table.writers_.emplace(writer, std::move(w));
  }
  if (absl::Status s = r.Finish(); !s.ok()) return s;
  return table;
}

}  // namespace fremen::storage
