#include "storage/shard_record_checks.h"

#include "absl/strings/str_cat.h"
#include "storage/model/lossless/lossless_history.h"
#include "storage/model/record_codec.h"
#include "storage/model/kernels/wide_bodies.h"
#include "storage/shard_records.h"

namespace fremen::storage {

absl::Status ShardRecordChecks::Place(uint64_t key) const {
  if (const uint32_t owner = ShardOf(key, info_.shards); owner != shard_) {
    return absl::DataLossError(absl::StrCat("belongs to shard ", owner, ", not this one"));
  }
  if (info_.kind == MapKind::kGrid) {
    if (!keys_.IsCellKey(key)) return absl::DataLossError("not the key of a grid cell");
    const auto cell = keys_.Cell(key);
    if (!info_.grid.Contains(cell[0], cell[1], cell[2])) {
      return absl::DataLossError(absl::StrCat("cell (", cell[0], ", ", cell[1], ", ", cell[2], ") is outside the ",
                                              info_.grid.size[0], "×", info_.grid.size[1], "×", info_.grid.size[2],
                                              " grid"));
    }
  }
  return absl::OkStatus();
}

absl::Status ShardRecordChecks::Static(uint64_t brick_key, std::string_view value, StaticBrick* brick) const {
  if (brick_key > (UINT64_MAX >> kBrickBits)) return absl::DataLossError("not a brick key");
  if (const uint32_t owner = ShardOf(brick_key << kBrickBits, info_.shards); owner != shard_) {
    return absl::DataLossError(absl::StrCat("brick belongs to shard ", owner, ", not this one"));
  }
  auto decoded = StaticBrick::Decode(value);
  if (!decoded.ok()) return decoded.status();
  absl::Status first;
  decoded->ForEach([&](uint32_t i, const model::StaticState&) {
    const uint64_t key = brick_key << kBrickBits | i;
    if (absl::Status s = Place(key); !s.ok() && first.ok()) {
      first = absl::DataLossError(absl::StrCat("state ", key, ": ", s.message()));
    }
  });
  if (brick != nullptr) *brick = *std::move(decoded);
  return first;
}

absl::Status ShardRecordChecks::Dynamic(uint64_t key, std::string_view value) const {
  if (absl::Status s = Place(key); !s.ok()) return s;
  return model::DecodeStateModel<float>(value, settings_).status();
}

absl::Status ShardRecordChecks::Lossless(std::string_view value) const {
  if (info_.lossless_sampling_period <= 0) return absl::DataLossError("a lossless history in a map without them");
  return model::LosslessHistory::Decode(value).status();
}

absl::Status ShardRecordChecks::Published(std::string_view value) const {
  return model::DecodePublishedModel(value, settings_.periods.size(), settings_.max_order).status();
}

absl::Status ShardRecordChecks::Wide(std::string_view value) const {
  model::WideBodies bodies(settings_.periods.size());
  return bodies.Decode(0, value);
}

absl::Status ShardRecordChecks::Label(uint64_t key, std::string_view value) const {
  if (absl::Status s = Place(key); !s.ok()) return s;
  return shard_records::DecodeLabel(value).status();
}

}  // namespace fremen::storage
