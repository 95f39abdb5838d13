// End-to-end tests of fremenctl's file-heavy subcommands — ingest (time-state files, grid CSV,
// map_server snapshot directories), region (map_server + PNG export), model (--plot) and demo —
// running the real fremenctl binary (FREMENCTL_BINARY) against a real fremend (DaemonTest), and
// checking the files it writes and, over gRPC, what the daemon then predicts.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "client/formats/map_yaml.h"
#include "client/formats/occupancy_pixels.h"
#include "client/formats/pgm.h"
#include "client/formats/png_decode.h"
#include "client/formats/week_plot.h"
#include "fremen/v1/maps.grpc.pb.h"
#include "fremen/v1/query.grpc.pb.h"
#include "tests/fremend_fixture.h"

namespace fremen {
namespace {

using ::fremen::testing::CallContext;
using ::testing::HasSubstr;
using ::testing::Not;

constexpr double kDay = 86400;
// A Monday, 00:00 UTC.
constexpr double kMonday = 1700438400;

using ::fremen::testing::RunResult;

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

class FremenctlFormatsTest : public testing::DaemonTest {
 protected:
  // Runs fremenctl `args` --address <the daemon> to completion.
  RunResult Run(std::vector<std::string> args) {
    args.insert(args.end(), {"--address", daemon_->address()});
    return testing::RunProgram(FREMENCTL_BINARY, args);
  }

  // Runs and expects success, showing the output otherwise.
  RunResult RunOk(const std::vector<std::string>& args) {
    RunResult r = Run(args);
    EXPECT_EQ(r.exit_code, 0) << "fremenctl " << ::testing::PrintToString(args) << ": " << testing::Describe(r)
                              << "\nstdout: " << r.out
                              << "\nstderr: " << r.err;
    return r;
  }

  // p of `refs` at `time`, over gRPC.
  std::vector<float> Predict(const std::string& map, const v1::StateRefs& refs, double time) {
    auto stub = v1::QueryService::NewStub(daemon_->NewChannel());
    v1::PredictRequest request;
    request.set_map(map);
    *request.mutable_states() = refs;
    request.add_times(time);
    v1::PredictResponse response;
    const grpc::Status status = stub->Predict(CallContext().get(), request, &response);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return {response.probabilities().begin(), response.probabilities().end()};
  }

  v1::Map GetMap(const std::string& name) {
    auto stub = v1::MapService::NewStub(daemon_->NewChannel());
    v1::GetMapRequest request;
    request.set_map(name);
    v1::GetMapResponse response;
    const grpc::Status status = stub->GetMap(CallContext().get(), request, &response);
    EXPECT_TRUE(status.ok()) << status.error_message();
    return response.map();
  }

  // s(t) = door open 08:00-18:00 every day, every 10 minutes for `days` from day `first_day`.
  std::string WriteDoorFile(const std::string& name, int days, int first_day = 0) {
    std::ostringstream text;
    text << "# time state\n";
    for (double t = kMonday + first_day * kDay; t < kMonday + (first_day + days) * kDay; t += 600) {
      const double hour = std::fmod(t - kMonday, kDay) / 3600;
      text << static_cast<long long>(t) << ' ' << (hour >= 8 && hour < 18 ? 1 : 0) << '\n';
    }
    return dir_.Write(name, text.str());
  }

  // A 12 × 8 static office: walls all round (occupied), a 3 × 2 block never seen (unknown) and
  // free space elsewhere; image row 0 is the top.
  formats::Image StaticOffice() {
    formats::Image image(12, 8, 1, formats::kPixelFree);
    for (int y = 0; y < 8; ++y) {
      for (int x = 0; x < 12; ++x) {
        if (x == 0 || y == 0 || x == 11 || y == 7) image.at(x, y) = formats::kPixelOccupied;
        if (x >= 6 && x < 9 && y >= 2 && y < 4) image.at(x, y) = formats::kPixelUnknown;
      }
    }
    return image;
  }

  void WriteSnapshot(const std::string& dir, const std::string& stem, const formats::Image& image) {
    ASSERT_TRUE(formats::WritePgm(dir + "/" + stem + ".pgm", image).ok());
    std::ofstream(dir + "/" + stem + ".yaml") << "image: " << stem << ".pgm\nresolution: 0.050000\n"
                                              << "origin: [-1.000000, 2.000000, 0.000000]\nnegate: 0\n"
                                              << "occupied_thresh: 0.65\nfree_thresh: 0.196\n";
  }
};

TEST_F(FremenctlFormatsTest, IngestStatesFileThenModelPrintsIt) {
  // A week, the update (it publishes P), then a week scored at every order and the update that
  // selects one.
  const RunResult ingest = RunOk(
      {"ingest", "--map", "lab", "--states", WriteDoorFile("week1.txt", 7), "--name", "door", "--create", "--update"});
  EXPECT_THAT(ingest.out, HasSubstr("created generic map lab"));
  EXPECT_THAT(ingest.out, HasSubstr("1 batch, 1008 observations accepted, 0 rejected"));
  EXPECT_THAT(ingest.out, HasSubstr("update of lab: 1 states published"));
  const RunResult second =
      RunOk({"ingest", "--map", "lab", "--states", WriteDoorFile("week2.txt", 7, 7), "--name", "door", "--update"});
  EXPECT_THAT(second.out, Not(HasSubstr("created")));

  const RunResult model = RunOk({"model", "--map", "lab", "--name", "door"});
  EXPECT_THAT(model.out, HasSubstr("name: door"));
  EXPECT_THAT(model.out, HasSubstr("observations: 2016 from t = 1700438400.000"));
  // The daily period (24 h) is the strongest component of P.
  EXPECT_THAT(model.out, HasSubstr("published model P"));
  EXPECT_THAT(model.out, HasSubstr("24.0000"));
  EXPECT_THAT(model.out, HasSubstr("<- selected"));
  EXPECT_THAT(model.out, Not(HasSubstr("order 0\n")));

  // The daemon predicts the door open at noon and closed at night of the next day.
  v1::StateRefs refs;
  refs.add_names("door");
  EXPECT_GT(Predict("lab", refs, kMonday + 14 * kDay + 12 * 3600)[0], 0.7f);
  EXPECT_LT(Predict("lab", refs, kMonday + 14 * kDay + 3 * 3600)[0], 0.3f);
}

TEST_F(FremenctlFormatsTest, IngestGridCsvCreatesAGridLargeEnough) {
  const std::string csv = dir_.Write("grid.csv",
                                     "time,x,y,state\n"
                                     "100,0,0,0\n100,4,2,1\n"
                                     "# second scan\n"
                                     "200,0,0,0\n200,4,2,1\n200,1,1,0.5\n");
  const RunResult ingest = RunOk({"ingest", "--map", "grid", "--csv", csv, "--create", "--resolution", "0.5"});
  EXPECT_THAT(ingest.out, HasSubstr("2 batches, 5 observations accepted, 0 rejected"));
  const v1::Map map = GetMap("grid");
  EXPECT_EQ(map.kind(), v1::MAP_KIND_GRID);
  EXPECT_EQ(map.grid().size().x(), 5u);
  EXPECT_EQ(map.grid().size().y(), 3u);
  EXPECT_DOUBLE_EQ(map.grid().resolution(), 0.5);
  v1::StateRefs refs;
  for (uint32_t c : {0u, 4u}) {
    refs.mutable_cells()->add_x(c);
    refs.mutable_cells()->add_y(c == 0 ? 0 : 2);
  }
  const std::vector<float> p = Predict("grid", refs, 300);
  ASSERT_EQ(p.size(), 2u);
  EXPECT_NEAR(p[0], 0.0f, 1e-6);
  EXPECT_NEAR(p[1], 1.0f, 1e-6);
}

TEST_F(FremenctlFormatsTest, MapServerImportThenRegionExportGivesTheSameCells) {
  const std::string snapshots = dir_.Path("snapshots");
  std::filesystem::create_directory(snapshots);
  const formats::Image office = StaticOffice();
  for (int i = 0; i < 3; ++i) WriteSnapshot(snapshots, "office_" + std::to_string(1700000000 + i * 3600), office);
  const RunResult ingest = RunOk({"ingest", "--map", "office", "--map-server", snapshots, "--create"});
  // 96 pixels, 6 unknown: 90 observations per snapshot.
  EXPECT_THAT(ingest.out, HasSubstr("ingested 3 map_server snapshots"));
  EXPECT_THAT(ingest.out, HasSubstr("270 observations accepted, 0 rejected"));
  const v1::Map map = GetMap("office");
  EXPECT_EQ(map.grid().size().x(), 12u);
  EXPECT_DOUBLE_EQ(map.grid().origin().x(), -1.0);

  const std::string prefix = dir_.Path("exported");
  const RunResult region = RunOk({"region", "--map", "office", "--time", "1700086400", "--out", prefix});
  EXPECT_THAT(region.out, HasSubstr("12 x 8 cells"));
  EXPECT_THAT(region.out, HasSubstr("(36 occupied, 54 free, 6 unknown)"));
  absl::StatusOr<formats::MapMetadata> yaml = formats::ReadMapYaml(prefix + ".yaml");
  ASSERT_TRUE(yaml.ok()) << yaml.status();
  EXPECT_EQ(yaml->image, "exported.pgm");
  EXPECT_DOUBLE_EQ(yaml->resolution, 0.05);
  EXPECT_DOUBLE_EQ(yaml->origin_x, -1.0);
  EXPECT_DOUBLE_EQ(yaml->origin_y, 2.0);
  absl::StatusOr<formats::Image> pgm = formats::ReadPgm(prefix + ".pgm");
  ASSERT_TRUE(pgm.ok()) << pgm.status();
  ASSERT_EQ(pgm->width, office.width);
  ASSERT_EQ(pgm->height, office.height);
  // Cell by cell, as map_server loads both files: occupied, free and unknown where they were.
  for (int y = 0; y < office.height; ++y) {
    for (int x = 0; x < office.width; ++x) {
      EXPECT_EQ(formats::CellFromPixel(pgm->at(x, y), *yaml), formats::CellFromPixel(office.at(x, y), *yaml))
          << "pixel " << x << "," << y;
    }
  }
  absl::StatusOr<formats::Image> png = formats::ReadPng(prefix + ".png");
  ASSERT_TRUE(png.ok()) << png.status();
  EXPECT_EQ(png->width, 12);
  EXPECT_EQ(png->at(0, 0), 0);    // a wall: p = 1, black
  EXPECT_EQ(png->at(2, 2), 255);  // free: p = 0, white
  EXPECT_EQ(png->at(7, 3), 128);  // never seen: p = 0.5

  // A sub-box: its YAML origin moves with it.
  RunOk({"region", "--map", "office", "--time", "1700086400", "--box", "2", "1", "5", "4", "--out", prefix + "-box"});
  absl::StatusOr<formats::MapMetadata> box = formats::ReadMapYaml(prefix + "-box.yaml");
  ASSERT_TRUE(box.ok()) << box.status();
  EXPECT_DOUBLE_EQ(box->origin_x, -1.0 + 2 * 0.05);
  EXPECT_DOUBLE_EQ(box->origin_y, 2.0 + 1 * 0.05);
  absl::StatusOr<formats::Image> box_pgm = formats::ReadPgm(prefix + "-box.pgm");
  ASSERT_TRUE(box_pgm.ok());
  EXPECT_EQ(box_pgm->width, 3);
  EXPECT_EQ(box_pgm->height, 3);
}

TEST_F(FremenctlFormatsTest, MapServerTimesFileIntoAnExistingMap) {
  const std::string snapshots = dir_.Path("named");
  std::filesystem::create_directory(snapshots);
  formats::Image closed = StaticOffice();
  WriteSnapshot(snapshots, "morning", StaticOffice());
  closed.at(5, 5) = formats::kPixelOccupied;  // something in the room at night
  WriteSnapshot(snapshots, "night", closed);
  RunOk({"ingest", "--map", "office", "--map-server", snapshots, "--times",
         dir_.Write("times.txt", "morning.yaml 1700000000\nnight.yaml 1700040000\n"), "--create"});
  // Image (5, 5) is cell (5, 8 - 1 - 5) = (5, 2): observed 0 then 1.
  v1::StateRefs refs;
  refs.mutable_cells()->add_x(5);
  refs.mutable_cells()->add_y(2);
  EXPECT_NEAR(Predict("office", refs, 1700050000)[0], 0.5f, 1e-6);
  // Without --times the names carry no time: the error says how to fix it.
  const RunResult untimed = Run({"ingest", "--map", "office", "--map-server", snapshots});
  EXPECT_EQ(untimed.exit_code, 1);
  EXPECT_THAT(untimed.err, HasSubstr("morning.yaml: the file name does not end with its time"));
  EXPECT_THAT(untimed.err, HasSubstr("--times"));
}

TEST_F(FremenctlFormatsTest, ModelPlotWritesSvgAndPng) {
  const std::string door = WriteDoorFile("door.txt", 7);
  RunOk({"ingest", "--map", "lab", "--states", door, "--name", "door", "--create", "--update"});
  const std::string svg_path = dir_.Path("door.svg");
  const RunResult svg_run =
      RunOk({"model", "--map", "lab", "--name", "door", "--plot", svg_path, "--observations", door});
  EXPECT_THAT(svg_run.out, HasSubstr("plot: " + svg_path));
  const std::string svg = ReadFile(svg_path);
  ASSERT_THAT(svg, HasSubstr("<svg"));
  EXPECT_THAT(svg, HasSubstr("</svg>"));
  std::smatch points;
  ASSERT_TRUE(std::regex_search(svg, points, std::regex("class=\"probability\"[^>]*points=\"([^\"]*)\"")));
  const std::string list = points[1].str();
  EXPECT_EQ(std::count(list.begin(), list.end(), ' ') + 1, 1009);  // a sample every 10 minutes
  // The default span ends a day after the last observation: 6 days of observations are drawn.
  const std::regex circle("<circle class=\"observation\"");
  EXPECT_EQ(std::distance(std::sregex_iterator(svg.begin(), svg.end(), circle), std::sregex_iterator()), 6 * 144 + 1);

  const std::string png_path = dir_.Path("door.png");
  RunOk({"model", "--map", "lab", "--name", "door", "--plot", png_path});
  absl::StatusOr<formats::Image> png = formats::ReadPng(png_path);
  ASSERT_TRUE(png.ok()) << png.status();
  EXPECT_EQ(png->channels, 3);
  size_t curve = 0;
  for (int y = 0; y < png->height; ++y) {
    for (int x = 0; x < png->width; ++x) {
      curve += png->at(x, y, 0) == formats::kCurveColor.r && png->at(x, y, 1) == formats::kCurveColor.g &&
               png->at(x, y, 2) == formats::kCurveColor.b;
    }
  }
  EXPECT_GT(curve, 800u);
}

TEST_F(FremenctlFormatsTest, DemoPopulatesMapsThatPredict) {
  const RunResult demo = RunOk({"demo"});
  EXPECT_THAT(demo.out, HasSubstr("demo-office (grid 40 x 20 cells of 0.25 m): 1008 batches, 806400 observations"));
  EXPECT_THAT(demo.out, HasSubstr("demo-states (door, meeting-room, kitchen-light): 1008 batches, 3024 observations"));
  EXPECT_THAT(demo.out, HasSubstr("7 updates of both maps"));
  EXPECT_THAT(demo.out, HasSubstr("Next, try:"));
  EXPECT_THAT(demo.out, HasSubstr("fremenctl region --map demo-office --time 2023-11-27T09:00:00Z --out morning"));

  // The Monday after the simulated week (a week of data cannot hold a weekly period; its 84 h
  // harmonic tells weekdays from the weekend): the door open at 13:00, closed at 03:00 — in the
  // generic map and, inverted, in the doorway cells of the grid.
  const double monday = kMonday + 7 * kDay;
  v1::StateRefs door;
  door.add_names("door");
  EXPECT_GT(Predict("demo-states", door, monday + 13 * 3600)[0], 0.6f);
  EXPECT_LT(Predict("demo-states", door, monday + 3 * 3600)[0], 0.4f);
  v1::StateRefs doorway;
  doorway.mutable_cells()->add_x(20);
  doorway.mutable_cells()->add_y(9);
  EXPECT_LT(Predict("demo-office", doorway, monday + 13 * 3600)[0], 0.4f);
  EXPECT_GT(Predict("demo-office", doorway, monday + 3 * 3600)[0], 0.6f);

  // The suggested predict command works (it is the other commands' syntax).
  const RunResult predict = RunOk({"predict", "--map", "demo-states", "--name", "door", "--name", "meeting-room",
                                       "--time", "2023-11-27T09:00:00Z", "--time", "2023-11-27T14:00:00Z"});
  EXPECT_THAT(predict.out, HasSubstr("door"));
  EXPECT_THAT(demo.out, HasSubstr("fremenctl predict --map demo-states --name door --name meeting-room --time "
                                  "2023-11-27T09:00:00Z --time 2023-11-27T14:00:00Z"));
  // The suggested region command works; the exported maps show the walls, and the doorway
  // occupied at night and mostly free at 13:00.
  RunOk({"region", "--map", "demo-office", "--time", "2023-11-27T09:00:00Z", "--out", dir_.Path("morning")});
  absl::StatusOr<formats::Image> morning = formats::ReadPgm(dir_.Path("morning.pgm"));
  ASSERT_TRUE(morning.ok());
  EXPECT_EQ(morning->at(0, 0), formats::kPixelOccupied);  // a wall (cell (0, 19))
  RunOk({"region", "--map", "demo-office", "--time", "2023-11-27T13:00:00Z", "--out", dir_.Path("noon")});
  RunOk({"region", "--map", "demo-office", "--time", "2023-11-27T03:00:00Z", "--out", dir_.Path("night")});
  absl::StatusOr<formats::Image> noon = formats::ReadPng(dir_.Path("noon.png"));
  absl::StatusOr<formats::Image> night = formats::ReadPgm(dir_.Path("night.pgm"));
  ASSERT_TRUE(noon.ok() && night.ok());
  // Cell (20, 9) is image row 20 - 1 - 9; in the PNG, p < 0.4 is lighter than 153.
  EXPECT_GT(noon->at(20, 10), 153);
  EXPECT_EQ(night->at(20, 10), formats::kPixelOccupied);

  // Running it again does not overwrite the maps unless asked.
  const RunResult again = Run({"demo", "--days", "1"});
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_THAT(again.err, HasSubstr("map demo-office already exists; pass --replace"));
  RunOk({"demo", "--days", "1", "--replace"});
}

TEST_F(FremenctlFormatsTest, BadInputsSayWhatToFix) {
  // ingest: a bad CSV line names file:line and field; no input at all is a usage error.
  const std::string bad_csv = dir_.Write("bad.csv", "time,x,y,state\n1,2,3,1\n2,-2,3,1\n");
  RunResult r = Run({"ingest", "--map", "grid", "--csv", bad_csv, "--create"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("bad.csv:3: field x: expected a cell index"));
  r = Run({"ingest", "--map", "grid"});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("give exactly one input"));
  // ingest --map-server: a YAML without resolution names the key and the file.
  const std::string snapshots = dir_.Path("broken");
  std::filesystem::create_directory(snapshots);
  std::ofstream(snapshots + "/map_5.yaml") << "image: map_5.pgm\norigin: [0, 0, 0]\n";
  r = Run({"ingest", "--map", "office", "--map-server", snapshots, "--create"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("map_5.yaml: resolution is missing"));
  // A snapshot that does not fit the grid of the first: nothing is sent and no empty map is left
  // behind, since every file is checked before the map is created.
  const std::string mixed = dir_.Path("mixed");
  std::filesystem::create_directory(mixed);
  WriteSnapshot(mixed, "office_1", StaticOffice());
  WriteSnapshot(mixed, "office_2", StaticOffice());
  std::ofstream(mixed + "/office_2.yaml") << "image: office_2.pgm\nresolution: 0.1\norigin: [-1, 2, 0]\n";
  r = Run({"ingest", "--map", "office", "--map-server", mixed, "--create"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("office_2.yaml: resolution 0.1 differs from the map's grid resolution 0.05"));
  {
    auto maps = v1::MapService::NewStub(daemon_->NewChannel());
    v1::GetMapRequest request;
    request.set_map("office");
    v1::GetMapResponse response;
    EXPECT_EQ(maps->GetMap(CallContext().get(), request, &response).error_code(), grpc::StatusCode::NOT_FOUND);
  }
  // ingest into a map that does not exist, without --create.
  r = Run({"ingest", "--map", "nomap", "--states", WriteDoorFile("d.txt", 1), "--name", "door"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("nomap"));

  // region: an unknown map; a time that is not one.
  r = Run({"region", "--map", "nomap", "--time", "1700000000", "--out", dir_.Path("x")});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("nomap"));
  r = Run({"region", "--map", "nomap", "--time", "tomorrow-ish", "--out", dir_.Path("x")});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("--time"));

  // model: a state never observed; a plot format fremenctl does not write.
  RunOk({"ingest", "--map", "lab", "--states", WriteDoorFile("door.txt", 1), "--name", "door", "--create"});
  r = Run({"model", "--map", "lab", "--name", "window"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_THAT(r.err, HasSubstr("window has never been observed in map lab"));
  r = Run({"model", "--map", "lab", "--name", "door", "--plot", dir_.Path("door.gif")});
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.err, HasSubstr("--plot FILE must end in .svg or .png"));

  // demo: a bad number of days.
  r = Run({"demo", "--days", "0"});
  EXPECT_EQ(r.exit_code, 2);
}

}  // namespace
}  // namespace fremen
