// MapStore and histories (a time per observation): a store fed a history and a store fed the same
// observations one scan per time predict bit-identically, with and without persistence, before
// and after publication and after reopening — the history's runs split across the
// shards as the scans' keys are.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "storage/map_store.h"
#include "storage/testing/open_map_store.h"
#include "testing/temp_dir.h"

namespace fremen::storage {
namespace {

using fremen::testing::TempDir;
using testing::OpenOrDie;

MapInfo Doors(const std::string& name) {
  MapInfo map;
  map.name = name;
  map.kind = MapKind::kGeneric;
  map.shards = 3;
  return map;
}

// Five states over two days, one to five of them seen each minute, a late stretch (times going
// back), a value outside [0, 1]: as one history.
ObservationBatch Log() {
  ObservationBatch history;
  history.writer_id = 1;
  history.sequence = 1;
  std::mt19937 rng(4);
  for (int minute = 0; minute < 2880; ++minute) {
    const double t = 1.7e9 + 60.0 * (minute >= 1000 && minute < 1100 ? minute - 700 : minute);
    for (uint64_t id = 1; id <= 5; ++id) {
      if (rng() % 2) continue;
      history.keys.push_back(id * 0x9E3779B97F4A7C15ull);  // spread over the shards
      history.times.push_back(t);
      history.values.push_back(rng() % 3 == 0 ? 1.0f : (rng() % 5 == 0 ? 0.5f : 0.0f));
    }
  }
  history.values[77] = 2.0f;
  return history;
}

// The same observations, one scan per run of equal times.
std::vector<ObservationBatch> Scans(const ObservationBatch& history) {
  std::vector<ObservationBatch> scans;
  for (size_t i = 0; i < history.keys.size(); ++i) {
    if (i == 0 || history.times[i] != history.times[i - 1]) {
      scans.emplace_back();
      scans.back().writer_id = 1;
      scans.back().sequence = scans.size();
      scans.back().time = history.times[i];
    }
    scans.back().keys.push_back(history.keys[i]);
    scans.back().values.push_back(history.values[i]);
  }
  return scans;
}

// Every state's prediction across a week, with and without persistence, as bytes.
std::string Predictions(const MapStore& store) {
  std::vector<uint64_t> keys;
  for (uint64_t id = 1; id <= 5; ++id) keys.push_back(id * 0x9E3779B97F4A7C15ull);
  std::vector<double> times;
  for (int h = 0; h < 168; h += 3) times.push_back(1.7e9 + 3600.0 * h + 11);
  std::string out;
  for (bool persistence : {false, true}) {
    const std::vector<float> p = store.Predict(keys, times, {persistence, -1});
    out.append(reinterpret_cast<const char*>(p.data()), p.size() * sizeof(float));
  }
  const MapStats stats = store.Stats();
  out += std::to_string(stats.totals.observations) + " " + std::to_string(stats.totals.states);
  return out;
}

TEST(MapStoreHistoryTest, AHistoryPredictsAsItsScansBitForBitAcrossPublicationAndReopening) {
  TempDir dir;
  const ObservationBatch history = Log();
  std::string by_history, by_scans;
  {
    auto h = OpenOrDie(Doors("h"), dir.Path("h"));
    auto s = OpenOrDie(Doors("s"), dir.Path("s"));
    auto ack = h->Write(history);
    ASSERT_TRUE(ack.ok()) << ack.status();
    EXPECT_EQ(ack->rejected, 1u);
    uint64_t accepted = 0;
    for (ObservationBatch& scan : Scans(history)) {
      auto scan_ack = s->Write(std::move(scan));
      ASSERT_TRUE(scan_ack.ok()) << scan_ack.status();
      accepted += scan_ack->accepted;
    }
    EXPECT_EQ(accepted, ack->accepted);
    EXPECT_EQ(Predictions(*h), Predictions(*s));
    ASSERT_TRUE(h->PublishModels().ok());
    ASSERT_TRUE(s->PublishModels().ok());
    by_history = Predictions(*h);
    by_scans = Predictions(*s);
    EXPECT_EQ(by_history, by_scans);
  }  // closed: from the checkpoint now (tests/ingest_history_test.cc replays the log after kill -9)
  auto h = OpenOrDie(Doors("h"), dir.Path("h"));
  EXPECT_EQ(Predictions(*h), by_history);
  // A retry after the reopening is a duplicate.
  auto again = h->Write(history);
  ASSERT_TRUE(again.ok()) << again.status();
  EXPECT_TRUE(again->duplicate);
}

}  // namespace
}  // namespace fremen::storage
