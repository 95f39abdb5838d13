// GET /metrics end to end: a real fremend fed over gRPC, scraped over HTTP with cpp-httplib's
// client. The ingest counters equal what was sent, each method's calls are counted by status code
// (an error included), the per-map gauges follow the map, an update job is counted with what it
// published, the read token is required when tokens are configured (401 without or with an unknown
// one, 200 with a read or write token), and every metric the Grafana dashboard
// (deploy/grafana-fremen.json) queries is one the daemon exports.
#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>

#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>

#include "absl/strings/str_cat.h"
#include "fremen/v1/admin.grpc.pb.h"
#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tests/metrics_helpers.h"

namespace fremen::testing {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;

class HttpMetricsTest : public DaemonTest {
 protected:
  std::string Scrape(const httplib::Headers& headers = {}) {
    httplib::Client client = HttpClientFor(daemon_->http_address());
    const httplib::Result result = client.Get("/metrics", headers);
    EXPECT_TRUE(result) << httplib::to_string(result.error());
    if (!result) return "";
    EXPECT_EQ(result->status, 200) << result->body;
    EXPECT_THAT(result->get_header_value("Content-Type"), HasSubstr("text/plain; version=0.0.4"));
    return result->body;
  }
};

TEST_F(HttpMetricsTest, IngestAndCallsAreCountedAsTheyHappened) {
  CreateGridMap(*daemon_, "lab");
  const uint64_t sent = IngestCells(*daemon_, "lab", 3, 150);
  auto maps = v1::MapService::NewStub(daemon_->NewChannel());
  v1::GetMapRequest missing;
  missing.set_map("no-such-map");
  v1::GetMapResponse ignored;
  for (int i = 0; i < 2; ++i) {
    EXPECT_EQ(maps->GetMap(CallContext().get(), missing, &ignored).error_code(), grpc::StatusCode::NOT_FOUND);
  }

  const std::string text = Scrape();
  EXPECT_THAT(text, HasSubstr(absl::StrCat("fremen_ingest_observations_total{map=\"lab\"} ", sent, "\n")));
  EXPECT_THAT(text, HasSubstr("fremen_ingest_batches_total{map=\"lab\",result=\"applied\"} 3\n"));
  EXPECT_THAT(text, HasSubstr("fremen_ingest_rejected_observations_total{map=\"lab\"} 0\n"));
  EXPECT_THAT(text, HasSubstr("fremen_log_appends_total{map=\"lab\"} 3\n"));
  EXPECT_THAT(text, HasSubstr("fremen_grpc_calls_total{code=\"OK\",method=\"CreateMap\"} 1\n"));
  EXPECT_THAT(text, HasSubstr("fremen_grpc_calls_total{code=\"OK\",method=\"Ingest\"} 1\n"));
  EXPECT_THAT(text, HasSubstr("fremen_grpc_calls_total{code=\"NOT_FOUND\",method=\"GetMap\"} 2\n"));
  EXPECT_THAT(text, HasSubstr("fremen_grpc_call_duration_seconds_count{method=\"GetMap\"} 2\n"));
  EXPECT_THAT(text, HasSubstr(absl::StrCat("fremen_map_observations{map=\"lab\"} ", sent, "\n")));
  EXPECT_THAT(text, HasSubstr("fremen_maps 1\n"));
  EXPECT_THAT(text, HasSubstr("fremen_failed_maps 0\n"));
  EXPECT_THAT(text, HasSubstr("fremen_recovery_duration_seconds{map=\"lab\"}"));
  EXPECT_THAT(text, HasSubstr("fremen_ingest_received_bytes_total{map=\"lab\"}"));
}

TEST_F(HttpMetricsTest, TheMetricsOfARecoveredMapCarryItsRecovery) {
  CreateGridMap(*daemon_, "lab");
  IngestCells(*daemon_, "lab", 1, 100);
  StopDaemon();
  StartDaemon();
  const std::string text = Scrape();
  EXPECT_THAT(text, HasSubstr("fremen_recovery_duration_seconds{map=\"lab\"}"));
  EXPECT_THAT(text, HasSubstr("fremen_map_observations{map=\"lab\"} 100\n"));  // recovered, not re-ingested
  EXPECT_THAT(text, HasSubstr("fremen_ingest_observations_total{map=\"lab\"} 0\n"));  // counters restart
  EXPECT_THAT(text, HasSubstr("fremen_checkpoints_total{map=\"lab\"} 0\n"));
}

TEST_F(HttpMetricsTest, AnUpdateJobIsCountedWithTheStatesItPublished) {
  CreateGridMap(*daemon_, "lab");
  IngestCells(*daemon_, "lab", 4, 200);
  auto admin = v1::AdminService::NewStub(daemon_->NewChannel());
  v1::RunUpdateRequest run;
  run.set_map("lab");
  v1::Operation operation;
  ASSERT_TRUE(admin->RunUpdate(CallContext().get(), run, &operation).ok());
  // Polled until done; the job's own pace, not a timed assertion (a hung job fails at ctest's timeout).
  while (!operation.done()) {
    v1::GetOperationRequest get;
    get.set_map("lab");
    get.set_name(operation.name());
    ASSERT_TRUE(admin->GetOperation(CallContext().get(), get, &operation).ok());
  }
  ASSERT_EQ(operation.error().code(), 0) << operation.error().message();
  const std::string text = Scrape();
  EXPECT_THAT(text, HasSubstr("fremen_update_jobs_total{result=\"ok\"} 1\n"));
  EXPECT_THAT(text, HasSubstr("fremen_update_jobs_total{result=\"failed\"} 0\n"));
  EXPECT_THAT(text, HasSubstr(absl::StrCat("fremen_update_states_published_total ",
                                           operation.update().states_published(), "\n")));
  EXPECT_THAT(text, HasSubstr("fremen_update_job_duration_seconds_count 1\n"));
  EXPECT_THAT(text, HasSubstr("fremen_update_jobs_active 0\n"));
  EXPECT_THAT(text, HasSubstr("fremen_grpc_calls_total{code=\"OK\",method=\"RunUpdate\"} 1\n"));
}

class HttpMetricsTokenTest : public HttpMetricsTest {
 protected:
  void SetUp() override {
    const std::string tokens = dir_.Write("tokens", "read:reader-token\nwrite:writer-token\n");
    StartDaemon({"--tokens-file", tokens});
  }
  int Status(const httplib::Headers& headers) {
    httplib::Client client = HttpClientFor(daemon_->http_address());
    const httplib::Result result = client.Get("/metrics", headers);
    EXPECT_TRUE(result) << httplib::to_string(result.error());
    return result ? result->status : 0;
  }
};

TEST_F(HttpMetricsTokenTest, ScrapesNeedAReadOrWriteToken) {
  EXPECT_EQ(Status({}), 401);
  EXPECT_EQ(Status({{"Authorization", "Bearer not-a-token"}}), 401);
  EXPECT_EQ(Status({{"Authorization", "reader-token"}}), 401);  // no Bearer scheme
  EXPECT_EQ(Status({{"Authorization", "Bearer reader-token"}}), 200);
  EXPECT_EQ(Status({{"Authorization", "Bearer writer-token"}}), 200);
  httplib::Client client = HttpClientFor(daemon_->http_address());
  const httplib::Result refused = client.Get("/metrics");
  ASSERT_TRUE(refused);
  EXPECT_EQ(refused->get_header_value("WWW-Authenticate"), "Bearer");
  EXPECT_THAT(refused->body, Not(HasSubstr("fremen_")));
  // The probes stay open: a load balancer has no token.
  EXPECT_EQ(client.Get("/healthz")->status, 200);
}

// Every "expr" string anywhere in `value`.
void CollectExprs(const google::protobuf::Value& value, std::vector<std::string>& out) {
  if (value.has_struct_value()) {
    for (const auto& [key, field] : value.struct_value().fields()) {
      if (key == "expr" && field.has_string_value()) out.push_back(field.string_value());
      CollectExprs(field, out);
    }
  } else if (value.has_list_value()) {
    for (const auto& item : value.list_value().values()) CollectExprs(item, out);
  }
}

TEST_F(HttpMetricsTest, EveryMetricTheGrafanaDashboardQueriesIsExported) {
  std::ifstream file(std::string(FREMEN_SOURCE_DIR) + "/deploy/grafana-fremen.json");
  ASSERT_TRUE(file) << "deploy/grafana-fremen.json is missing";
  std::stringstream json;
  json << file.rdbuf();
  google::protobuf::Value dashboard;
  const auto parsed = google::protobuf::util::JsonStringToMessage(json.str(), &dashboard);
  ASSERT_TRUE(parsed.ok()) << parsed.ToString();
  std::vector<std::string> exprs;
  CollectExprs(dashboard, exprs);
  ASSERT_GE(exprs.size(), 10u) << "the dashboard's panels have no queries";

  CreateGridMap(*daemon_, "lab");
  IngestCells(*daemon_, "lab", 1, 10);
  const std::string text = Scrape();
  const std::regex metric("fremen_[a-z0-9_]+");
  const std::regex histogram_part("_(bucket|sum|count)$");
  std::set<std::string> queried;
  for (const std::string& expr : exprs) {
    for (auto it = std::sregex_iterator(expr.begin(), expr.end(), metric); it != std::sregex_iterator(); ++it) {
      queried.insert(it->str());
    }
  }
  ASSERT_FALSE(queried.empty());
  for (const std::string& name : queried) {
    const std::string family = std::regex_replace(name, histogram_part, "");
    const bool exported = text.find("# TYPE " + name + " ") != std::string::npos ||
                          text.find("# TYPE " + family + " histogram") != std::string::npos;
    EXPECT_TRUE(exported) << "the dashboard queries " << name << ", which /metrics does not export";
  }
}

}  // namespace
}  // namespace fremen::testing
