// The highest sequence number applied per writer of a map: a batch at or below it is a retry,
// acknowledged again and not applied again. Persisted with every checkpoint and rebuilt from the
// write-ahead log after it. Thread-safety: none (the map's committer owns it).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "absl/container/flat_hash_map.h"
#include "absl/status/statusor.h"

namespace fremen::storage {

class DedupTable {
 public:
  // Whether (writer, sequence) was applied already.
  bool Seen(uint64_t writer, uint64_t sequence) const {
    auto it = last_.find(writer);
    return it != last_.end() && sequence <= it->second;
  }
  void Record(uint64_t writer, uint64_t sequence) {
    uint64_t& last = last_[writer];
    if (sequence > last) last = sequence;
  }
  // Keeps, per writer, the higher of both tables' sequences.
  void MergeFrom(const DedupTable& other) {
    for (const auto& [writer, sequence] : other.last_) Record(writer, sequence);
  }
  size_t writers() const { return last_.size(); }

  std::string Encode() const;
  static absl::StatusOr<DedupTable> Decode(std::string_view bytes);
  bool operator==(const DedupTable&) const = default;

 private:
  absl::flat_hash_map<uint64_t, uint64_t> last_;
};

}  // namespace fremen::storage
