#include "tests/query_fixture.h"

#include "storage/state_names.h"
#include "tests/map_specs.h"

namespace fremen::testing {

float CellValue(uint32_t x, uint32_t y, int h) {
  const int hour = h % 24, day = h / 24;
  switch (x % 4) {
    case 0:
      return ((hour >= 8 && hour < 20) != ((x * 7 + y * 3 + h) % 37 == 0)) ? 1.0f : 0.0f;
    case 1:
      return (day % 7 < 5 && hour >= 9 && hour < 17) ? 1.0f : 0.0f;
    case 2:
      return 0.0f;
    default:
      return y % 2 == 1 ? 1.0f : 0.0f;
  }
}

v1::Map GridMap(const std::string& name, uint32_t nx, uint32_t ny, bool persistence) {
  v1::Map map = GridMapSpec(name, nx, ny, 0.1);
  map.mutable_grid()->mutable_origin()->set_x(-1.0);
  map.set_persistence(persistence);
  return map;
}

v1::Map GenericMap(const std::string& name, double lossless_sampling) {
  v1::Map map = GenericMapSpec(name);
  map.set_lossless_sampling_seconds(lossless_sampling);
  map.set_lossless_origin(kT0);
  return map;
}

v1::CellIndex Cell(uint32_t x, uint32_t y, uint32_t z) {
  v1::CellIndex c;
  c.set_x(x);
  c.set_y(y);
  c.set_z(z);
  return c;
}

std::string DoorName(int i) { return "door-" + std::to_string(i); }

void QueryServiceTest::Fill(storage::Store& store) {
  auto lab = store.Map("lab");
  ASSERT_TRUE(lab.ok());
  storage::MapStore& map = **lab;
  const storage::GridKeys keys = map.info().grid.keys();
  for (int h = 0; h < kHours; ++h) {
    storage::ObservationBatch batch;
    batch.writer_id = 1;
    batch.sequence = h + 1;
    batch.time = kT0 + 3600.0 * h;
    for (uint32_t y = 0; y < kNy; ++y) {
      for (uint32_t x = 0; x < kObservedNx; ++x) {
        batch.keys.push_back(keys.Key(x, y, 0));
        batch.values.push_back(CellValue(x, y, h));
      }
    }
    ASSERT_TRUE(map.Write(std::move(batch)).ok());
    // The nightly update, so that orders are chosen on prequential evidence.
    if (h % 24 == 23) {
      ASSERT_TRUE(map.PublishModels().ok());
    }
  }

  Expected& e = expected_;
  e.probe_cells = {{0, 0}, {4, 7}, {1, 2}, {2, 3}, {3, 5}, {3, 4}, {40, 10}, {63, 47}};
  for (auto [x, y] : e.probe_cells) e.probe_keys.push_back(keys.Key(x, y, 0));
  e.times = {kT0 + kHours * 3600.0, kQueryTime, kT0 + kHours * 3600.0 + 86400 * 2.5};
  e.predict = map.Predict(e.probe_keys, e.times, {});
  e.predict_persistence = map.Predict(e.probe_keys, e.times, {.persistence = true});
  e.predict_order0 = map.Predict(e.probe_keys, e.times, {.order = 0});
  storage::CellBox box;
  box.hi = {kNx, kNy, 1};
  ASSERT_TRUE(map.PredictBox(box, kQueryTime, {}, e.region).ok());
  e.dynamic_cell = *map.Snapshot(keys.Key(4, 7, 0));
  e.static_cell = *map.Snapshot(keys.Key(2, 3, 0));
  e.lab_stats = map.Stats();

  auto doors = store.Map("doors");
  ASSERT_TRUE(doors.ok());
  std::vector<uint64_t> door_keys;
  for (int i = 0; i < kDoors; ++i) door_keys.push_back(storage::StateIdOfName(DoorName(i)));
  for (int step = 0; step < 14 * 48; ++step) {
    storage::ObservationBatch batch;
    batch.writer_id = 2;
    batch.sequence = step + 1;
    batch.time = kT0 + 1800.0 * step;
    const int hour = (step / 2) % 24;
    for (int i = 0; i < kDoors; ++i) {
      batch.keys.push_back(door_keys[i]);
      batch.values.push_back((hour + i) % 24 < 12 ? 1.0f : 0.0f);
      if (step == 0) batch.labels.push_back({door_keys[i], DoorName(i), i < 5 ? "kitchen" : "hall"});
    }
    ASSERT_TRUE((*doors)->Write(std::move(batch)).ok());
    if (step % 48 == 47) {
      ASSERT_TRUE((*doors)->PublishModels().ok());
    }
  }
  auto top = (*doors)->TopN("kitchen", kQueryTime, 3, {});
  ASSERT_TRUE(top.ok());
  e.top_kitchen = *top;
  e.door_p = (*doors)->Predict(door_keys, std::vector<double>{kQueryTime}, {});

  // "history": ids 1..3 every 10 minutes for three days, id 3 with a gap on day two.
  auto history = store.Map("history");
  ASSERT_TRUE(history.ok());
  for (uint64_t slot = 0; slot < kLosslessSlots; ++slot) {
    storage::ObservationBatch batch;
    batch.writer_id = 3;
    batch.sequence = slot + 1;
    batch.time = kT0 + 600.0 * slot + 1;
    const int hour = static_cast<int>(slot / 6) % 24;
    for (uint64_t id = 1; id <= 3; ++id) {
      if (id == 3 && slot >= 160 && slot < 200) continue;
      batch.keys.push_back(id);
      batch.values.push_back(((hour >= 7 && hour < 19) != (slot % 23 == id)) ? 1.0f : 0.0f);
    }
    ASSERT_TRUE((*history)->Write(std::move(batch)).ok());
    if (slot % 144 == 143) {
      ASSERT_TRUE((*history)->PublishModels().ok());
    }
  }
  for (uint64_t id = 1; id <= 3; ++id) {
    auto slots = (*history)->Snapshot(id)->lossless->Reconstruct(0, kLosslessSlots);
    ASSERT_TRUE(slots.ok());
    e.lossless_slots.push_back(*slots);
  }
  e.lossless_state = *(*history)->Snapshot(3);
  e.lossless_stats = (*history)->Stats();
}

}  // namespace fremen::testing
