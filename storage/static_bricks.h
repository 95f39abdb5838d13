// The on-disk record of a brick's never-changed states: one LMDB value for up to 512 states, so
// that a never-changed cell costs its 16-byte StaticState plus 1/8 byte of bitmap, not an LMDB node
// (~18 bytes of overhead) of its own. Value type.
//
// Layout (version 1): version u8 | presence bitmap, 512 bits (64 bytes, bit i of byte i/8 = key
// brick·512 + i) | per present state in key order: t_first f64, span f32, count_value u32.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"
#include "storage/model/static_state.h"

namespace fremen::storage {

class StaticBrick {
 public:
  // REQUIRES: indices added in increasing order, each < 512.
  void Add(uint32_t index, const model::StaticState& state) { entries_.push_back({index, state}); }
  bool empty() const { return entries_.empty(); }
  size_t size() const { return entries_.size(); }
  void ForEach(const std::function<void(uint32_t, const model::StaticState&)>& f) const {
    for (const Entry& e : entries_) f(e.index, e.state);
  }

  std::string Encode() const;
  static absl::StatusOr<StaticBrick> Decode(std::string_view bytes);

 private:
  struct Entry {
    uint32_t index;
    model::StaticState state;
  };
  std::vector<Entry> entries_;
};

}  // namespace fremen::storage
