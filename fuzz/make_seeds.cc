// Writes the seed corpora of the fuzz targets into <dir>/<target>/ (fuzz/corpus/ in the tree): a
// few valid inputs each, made with the project's own encoders so that they stay valid when a format
// changes (then rerun:
// build-fuzz/bin/fremen_fuzz_seeds fuzz/corpus).
#include <zlib.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "client/formats/gray_image.h"
#include "client/formats/png.h"
#include "fremen/v1/ingest.pb.h"
#include "fremen/v1/maps.pb.h"
#include "fremen/v1/query.pb.h"
#include "fuzz/fuzz_map.h"
#include "fuzz/fuzz_util.h"
#include "storage/batch.h"
#include "storage/dedup_table.h"
#include "storage/map_info.h"
#include "storage/model/lossless/lossless_history.h"
#include "storage/model/record_codec.h"
#include "storage/model/state_model.h"
#include "storage/model/kernels/wide_bodies.h"
#include "storage/static_bricks.h"
#include "storage/update_record.h"

namespace {

using namespace fremen;

std::string root;

void Seed(const std::string& target, const std::string& name, const std::string& bytes) {
  const std::filesystem::path dir = std::filesystem::path(root) / target;
  std::filesystem::create_directories(dir);
  std::ofstream(dir / name, std::ios::binary) << bytes;
}

std::string Byte(int b) { return std::string(1, static_cast<char>(b)); }

void IngestSeeds() {
  v1::IngestRequest cells;
  cells.set_map("fuzz");
  cells.set_writer_id(3);
  cells.set_sequence(17);
  cells.set_time(1.7e9);
  auto* c = cells.mutable_cells();
  for (uint32_t i = 0; i < 4; ++i) {
    c->mutable_cells()->add_x(i * 7);
    c->mutable_cells()->add_y(i * 5);
    c->add_values(i % 2);
  }
  c->add_values(0.5f);  // one too many: an error
  Seed("ingest_convert", "cells_mismatch", Byte(0) + cells.SerializeAsString());
  c->mutable_values()->RemoveLast();
  Seed("ingest_convert", "cells_2d", Byte(0) + cells.SerializeAsString());
  for (uint32_t i = 0; i < 4; ++i) c->mutable_cells()->add_z(i);
  Seed("ingest_convert", "cells_3d", Byte(1) + cells.SerializeAsString());

  v1::IngestRequest points = cells;
  auto* p = points.mutable_points();
  for (double x : {-1.0, 0.3, 1.2}) {
    p->mutable_points()->add_x(x);
    p->mutable_points()->add_y(x + 2.5);
    p->add_values(0.25f);
  }
  Seed("ingest_convert", "points", Byte(0) + points.SerializeAsString());

  v1::IngestRequest patch = cells;
  auto* d = patch.mutable_patch();
  d->mutable_origin()->set_x(2);
  d->mutable_origin()->set_y(3);
  d->mutable_size()->set_x(3);
  d->mutable_size()->set_y(2);
  d->mutable_size()->set_z(1);
  d->set_probabilities(std::string("\x00\x40\x80\xc0\xff\x10", 6));
  Seed("ingest_convert", "patch_bytes", Byte(0) + patch.SerializeAsString());
  d->clear_probabilities();
  for (int i = 0; i < 6; ++i) d->add_values(i / 5.0f);
  Seed("ingest_convert", "patch_floats", Byte(3) + patch.SerializeAsString());

  v1::IngestRequest states = cells;
  auto* s = states.mutable_states();
  for (uint64_t id : {1ull, 99ull, 1ull << 40}) {
    s->add_ids(id);
    s->add_values(1);
    s->add_names("door" + std::to_string(id));
    s->add_groups("doors");
  }
  Seed("ingest_convert", "states", Byte(2) + states.SerializeAsString());
  v1::IngestRequest named = cells;
  auto* n = named.mutable_named_states();
  for (const char* name : {"kitchen.light", "hall.door"}) {
    n->add_names(name);
    n->add_values(0);
  }
  n->add_groups("lights");
  n->add_groups("");
  Seed("ingest_convert", "named_states", Byte(2) + named.SerializeAsString());
}

v1::Map GridProto() {
  v1::Map map;
  map.set_name("office");
  map.set_kind(v1::MAP_KIND_GRID);
  map.mutable_grid()->set_resolution(0.05);
  map.mutable_grid()->mutable_origin()->set_x(-10);
  map.mutable_grid()->mutable_size()->set_x(400);
  map.mutable_grid()->mutable_size()->set_y(200);
  return map;
}

void MapSeeds() {
  v1::Map grid = GridProto();
  Seed("map_convert", "grid_defaults", grid.SerializeAsString());
  grid.mutable_grid()->mutable_size()->set_z(8);
  grid.mutable_periods()->set_longest_seconds(86400);
  grid.mutable_periods()->set_count(6);
  grid.mutable_periods()->set_floor_periods(true);
  grid.set_max_order(3);
  grid.set_persistence(false);
  grid.set_error_half_life_seconds(0);
  grid.set_criterion(v1::ERROR_CRITERION_SQUARED);
  grid.set_order_selection(v1::ORDER_SELECTION_MARGIN);
  grid.set_order_margin(0.002);
  grid.set_shards(4);
  Seed("map_convert", "grid_3d", grid.SerializeAsString());
  v1::Map generic;
  generic.set_name("rooms");
  generic.set_kind(v1::MAP_KIND_GENERIC);
  for (double p : {604800.0, 86400.0, 43200.0, 3600.0}) generic.mutable_periods()->add_explicit_seconds(p);
  generic.set_lossless_sampling_seconds(60);
  generic.set_lossless_origin(1.7e9);
  Seed("map_convert", "generic_lossless", generic.SerializeAsString());

  for (int i = 0; i < 3; ++i)
    Seed("catalog_record", "map" + std::to_string(i), storage::EncodeMapInfo(fuzz::FuzzMap(i)));
  storage::MapInfo explicit_periods = fuzz::FuzzMap(2);
  explicit_periods.periods.explicit_periods = {86400, 3600, 600};
  explicit_periods.created_unix = 1764547200;
  Seed("catalog_record", "explicit_periods", storage::EncodeMapInfo(explicit_periods));
}

void RecordSeeds() {
  for (int map = 0; map < 3; ++map) {
    const storage::MapInfo info = fuzz::FuzzMap(map);
    const model::ModelSettings settings = *storage::ModelSettingsOf(info);
    model::BasicStateModel<float> m(settings);
    model::BasicStateModel<double> wide(settings);
    for (int i = 0; i < 200; ++i) {
      const double t = 1.7e9 + 900.0 * i;
      const float s = (i / 48) % 2 ? 1.0f : 0.0f;
      m.Observe(t, s);
      wide.Observe(t, s);
    }
    const std::string k = "_map" + std::to_string(map);
    const auto selector = [&](int type) { return Byte(map * 16 + type); };
    Seed("record_codec", "spectrum_float" + k, selector(1) + model::EncodeSpectrum(m.spectrum()));
    Seed("record_codec", "spectrum_double" + k, selector(2) + model::EncodeSpectrum(wide.spectrum()));
    Seed("record_codec", "state_model_float_unpublished" + k, selector(7) + model::EncodeStateModel(m));
    m.Update();
    wide.Update();
    Seed("record_codec", "published" + k, selector(3) + model::EncodePublishedModel(m.published()));
    Seed("record_codec", "persistence" + k, selector(4) + model::EncodePersistence(m.persistence()));
    Seed("record_codec", "order_errors" + k, selector(5) + model::EncodeOrderErrors(m.order_errors()));
    Seed("record_codec", "state_model_float" + k, selector(7) + model::EncodeStateModel(m));
    Seed("record_codec", "state_model_double" + k, selector(8) + model::EncodeStateModel(wide));
    Seed("record_codec", "tag" + k, selector(0) + model::EncodeStateModel(m));
    model::WideBodies bodies(settings.periods.size());
    bodies.Widen(0, m.spectrum().body());
    Seed("record_codec", "wide_body" + k, selector(11) + bodies.Encode(0));
    if (map == 2) {
      auto h = model::LosslessHistory::Create(info.lossless_origin, info.lossless_sampling_period);
      for (int i = 0; i < 300; ++i) (void)h->Add(info.lossless_origin + 60.0 * i + 7, (i / 20) % 3 == 0 ? 1.0f : 0.0f);
      (void)h->Update(settings.max_order);
      Seed("record_codec", "lossless" + k, selector(10) + h->Encode());
      const std::string record = model::EncodeStateModel(m);
      Seed("query", "state_model_lossless",
           Byte(2 * 4 + 2) + Byte(record.size() & 255) + Byte(record.size() >> 8) + record + h->Encode());
    } else {
      const std::string record = model::EncodeStateModel(m);
      Seed("query", "state_model" + k,
           Byte(map * 4 + 2) + Byte(record.size() & 255) + Byte(record.size() >> 8) + record);
    }
  }
  model::StaticState state;
  for (int i = 0; i < 5; ++i) state.Observe(1.7e9 + i, 1.0f);
  Seed("record_codec", "static_state", Byte(6) + model::EncodeStaticState(state));
  Seed("query", "static_state", Byte(2) + Byte(18) + Byte(0) + model::EncodeStaticState(state));
  storage::StaticBrick brick;
  brick.Add(0, state);
  brick.Add(17, state);
  brick.Add(511, state);
  Seed("record_codec", "static_brick", Byte(9) + brick.Encode());
}

storage::ObservationBatch Batch(int i) {
  storage::ObservationBatch b;
  b.writer_id = 5;
  b.sequence = 10 + i;
  b.time = 1.7e9 + 60.0 * i;
  b.keys = {0, 3, 17, 1000};
  b.values = {0, 1, 0.5f, 1};
  if (i == 1) {
    b.patch.origin = {1, 2, 0};
    b.patch.size = {2, 2, 1};
    b.patch.values = {0, 0.25f, 0.75f, 1};
  }
  if (i == 2) b.labels = {{3, "door", "doors"}, {17, "light", ""}};
  return b;
}

void PutU32(std::string& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>(v >> (8 * i)));
}
void PutU64(std::string& out, uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>(v >> (8 * i)));
}

// A log record as storage/wal/wal.h lays it out.
std::string WalRecord(uint64_t lsn, const std::string& payload) {
  std::string lsn_bytes;
  PutU64(lsn_bytes, lsn);
  uLong crc = crc32(0L, Z_NULL, 0);
  crc = crc32(crc, reinterpret_cast<const Bytef*>(lsn_bytes.data()), 8);
  crc = crc32(crc, reinterpret_cast<const Bytef*>(payload.data()), static_cast<uInt>(payload.size()));
  std::string out;
  PutU32(out, static_cast<uint32_t>(payload.size()));
  PutU32(out, static_cast<uint32_t>(crc));
  return out + lsn_bytes + payload;
}

void LogSeeds() {
  std::string log;
  for (int i = 0; i < 3; ++i) {
    const std::string payload = storage::EncodeBatch(Batch(i));
    Seed("batch", "batch" + std::to_string(i), Byte(i == 2 ? 2 : 0) + payload);
    log += WalRecord(i + 1, payload);
  }
  // A compact batch (version 2 record): cells 3, 4, 5 and 9 by linear index, occupied bits.
  storage::ObservationBatch compact = Batch(0);
  compact.keys.clear();
  compact.values.clear();
  compact.compact = {std::string("\x03\x01\x01\x04", 4), std::string("\x0b", 1), ""};
  Seed("batch", "batch_compact", Byte(0) + storage::EncodeBatch(compact));
  Seed("wal_replay", "three_records", Byte(0) + Byte(0) + log);
  Seed("wal_replay", "three_records_fix_crc", Byte(3) + Byte(0) + log);
  Seed("wal_replay", "two_segments_after_1", Byte(16 | 4) + Byte(1) + log);
  Seed("wal_replay", "torn_tail", Byte(0) + Byte(0) + log.substr(0, log.size() - 5));
  std::string corrupt = log;
  corrupt[20] ^= 0x40;
  Seed("wal_replay", "corrupt_first", Byte(0) + Byte(0) + corrupt);

  storage::UpdateRecord update;
  update.start_time = 1.7e9;
  update.duration_seconds = 12.5;
  update.states_updated = 1234;
  update.prediction_error_before = 0.2;
  update.prediction_error_after = 0.1;
  update.order_histogram = {10, 0, 400, 3, 0, 821};
  Seed("update_record", "record", storage::EncodeUpdateRecord(update));
  Seed("update_record", "empty_histogram", storage::EncodeUpdateRecord({}));

  storage::DedupTable dedup;
  dedup.Record(1, 10);
  dedup.Record(77, 1ull << 40);
  dedup.Record(1ull << 63, 1);
  Seed("dedup_table", "three_writers", dedup.Encode());
  Seed("dedup_table", "empty", storage::DedupTable().Encode());
}

void QuerySeeds() {
  v1::PredictRequest predict;
  predict.set_map("fuzz");
  for (uint32_t i = 0; i < 3; ++i) {
    predict.mutable_states()->mutable_cells()->add_x(i);
    predict.mutable_states()->mutable_cells()->add_y(2 * i);
  }
  predict.add_times(1.7e9);
  predict.add_times(1.7e9 + 3600);
  predict.set_confidence(0.8f);
  predict.mutable_options()->set_order(2);
  Seed("query", "predict_cells", Byte(0) + predict.SerializeAsString());
  predict.mutable_states()->Clear();
  for (double x : {0.0, 1.0, -1.0}) {
    predict.mutable_states()->mutable_points()->add_x(x);
    predict.mutable_states()->mutable_points()->add_y(x + 3);
  }
  Seed("query", "predict_points", Byte(0) + predict.SerializeAsString());
  predict.mutable_states()->Clear();
  predict.mutable_states()->add_names("door");
  predict.mutable_states()->add_names("light");
  Seed("query", "predict_names", Byte(2 * 4) + predict.SerializeAsString());
  predict.mutable_states()->Clear();
  predict.mutable_states()->add_ids(7);
  predict.mutable_options()->set_persistence(true);
  Seed("query", "predict_ids", Byte(2 * 4) + predict.SerializeAsString());

  v1::PredictRegionRequest region;
  region.set_map("fuzz");
  region.mutable_lo()->set_x(3);
  region.mutable_hi()->set_x(40);
  region.mutable_hi()->set_y(30);
  region.set_time(1.7e9);
  region.set_output(v1::REGION_OUTPUT_STATES);
  region.set_confidence(0.6f);
  region.set_chunk_cells(100);
  Seed("query", "region_small", Byte(1) + region.SerializeAsString());
  region.mutable_hi()->set_x(1u << 21);
  region.mutable_hi()->set_y(1u << 21);
  region.mutable_hi()->set_z(3);
  region.set_output(v1::REGION_OUTPUT_UINT8);
  region.set_chunk_cells(0);
  Seed("query", "region_huge", Byte(3 * 4 + 1) + region.SerializeAsString());
  region.mutable_hi()->set_x(16);
  region.mutable_hi()->set_y(12);
  region.mutable_hi()->set_z(8);
  region.set_output(v1::REGION_OUTPUT_ENTROPY);
  region.set_chunk_cells(50);
  Seed("query", "region_3d", Byte(1 * 4 + 1) + region.SerializeAsString());
}

void TextSeeds() {
  Seed("config", "full",
       "# fremend.conf\n"
       "listen = 127.0.0.1:6000\n"
       "data_dir = \"/var/lib/fremen\"\n"
       "shards = 4\n"
       "checkpoint_log_mb = 64\n"
       "max_message_mb = 32\n"
       "keepalive_time = 30s\n"
       "keepalive_timeout = 5s\n"
       "keepalive_permit_without_calls = false\n"
       "shutdown_grace = 2m\n"
       "blocking_threads = 3\n"
       "tokens = read:abc, write:def\n"
       "update_schedule = 30 2 * * 1-5\n"
       "update_time_zone = UTC\n"
       "update_map_schedules = office=0 3 * * *; rooms=never\n"
       "log_level = debug\n");
  Seed("config", "ipv6", "listen = [::1]:0\nupdate_schedule = \"\"\n");
  Seed("config", "tls_only_cert", "tls_cert_file = /nonexistent/cert.pem\n");

  Seed("map_yaml", "trinary",
       "image: office.pgm\nresolution: 0.050000\norigin: [-10.000000, "
       "-10.000000, 0.000000]\nnegate: 0\n"
       "occupied_thresh: 0.65\nfree_thresh: 0.196\n");
  Seed("map_yaml", "scale_comments",
       "# saved by nav2\nimage: \"my map.pgm\"  # the image\nmode: "
       "scale\nresolution: 0.1\n"
       "origin: [1.5, -2, 0]\nnegate: 1\noccupied_thresh: 0.9\nfree_thresh: "
       "0.1\n");

  std::string p5 = "P5\n# a comment\n4 3\n255\n";
  for (int i = 0; i < 12; ++i) p5.push_back(static_cast<char>(i * 21));
  Seed("pgm", "p5", p5);
  Seed("pgm", "p2_maxval_15", "P2\n3 2\n15\n0 5 10\n15 7 1\n");
  std::string p5_16 = "P5 2 2 65535\n";
  for (int i = 0; i < 8; ++i) p5_16.push_back(static_cast<char>(i * 31));
  Seed("pgm", "p5_16bit", p5_16);

  const std::string yaml = "image: a.pgm\nresolution: 0.05\norigin: [-10, -10, 0]\n";
  const auto with_length = [](const std::string& text) {
    return Byte(text.size() & 255) + Byte(text.size() >> 8) + text;
  };
  Seed("map_server", "trinary", with_length(yaml) + p5);
  Seed("map_server", "scale_p2", with_length(yaml + "mode: scale\n") + "P2\n3 2\n255\n0 128 255\n205 254 1\n");

  formats::Image gray(5, 3, 1);
  formats::Image rgb(4, 4, 3);
  for (size_t i = 0; i < gray.pixels.size(); ++i) gray.pixels[i] = static_cast<uint8_t>(i * 17);
  for (size_t i = 0; i < rgb.pixels.size(); ++i) rgb.pixels[i] = static_cast<uint8_t>(i * 5);
  Seed("png", "gray", *formats::EncodePng(gray));
  Seed("png", "rgb", *formats::EncodePng(rgb));

  Seed("grid_csv", "2d_header",
       "time,x,y,state\n1700000000,1,2,1\n1700000060,1,2,0\n# "
       "comment\n\n1700000120,3,4,0.5\n");
  Seed("grid_csv", "3d", "1700000000,1,2,3,1\n1700000000.5,0,0,0,0\n");

  Seed("observations", "two_columns", "# time state\n1700000000 1\n1700000600 0\n1700001200 0.5\n");
  Seed("observations", "tabs", "1700000000\t1\n\n1700003600\t0\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s CORPUS_DIR (fuzz/corpus)\n", argv[0]);
    return 2;
  }
  root = argv[1];
  IngestSeeds();
  MapSeeds();
  RecordSeeds();
  LogSeeds();
  QuerySeeds();
  TextSeeds();
  return 0;
}
