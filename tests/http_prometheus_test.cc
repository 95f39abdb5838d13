// A real Prometheus (Debian's `prometheus`, installed by scripts/install-deps.sh) scrapes a real
// fremend — with a read token, as docs/http.md says to configure it (`authorization:
// credentials_file`) — and after an ingest over gRPC its own HTTP API answers
// fremen_ingest_observations_total for the map with what was sent. The test polls Prometheus's
// API until the sample arrives, under a generous overall deadline (a slow machine waits longer;
// nothing is asserted about how long it takes).
#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "gtest/gtest.h"
#include "tests/metrics_helpers.h"

namespace fremen::testing {
namespace {

constexpr char kPrometheus[] = "/usr/bin/prometheus";

// A TCP port free on loopback now (Prometheus cannot listen on port 0 and say which it took).
int FreePort() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = 0;
  socklen_t length = sizeof(address);
  if (bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) != 0 ||
      getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
    close(fd);
    return 0;
  }
  close(fd);
  return ntohs(address.sin_port);
}

// A prometheus server for the test's lifetime, its output in a log file.
class PrometheusProcess {
 public:
  PrometheusProcess(const std::vector<std::string>& args, const std::string& log_path) {
    pid_ = fork();
    if (pid_ == 0) {
      const int log = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(log, 1);
      dup2(log, 2);
      std::vector<char*> argv;
      argv.push_back(const_cast<char*>(kPrometheus));
      for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
      argv.push_back(nullptr);
      execv(kPrometheus, argv.data());
      _exit(127);
    }
  }
  ~PrometheusProcess() {
    if (pid_ <= 0 || exited_) return;
    kill(pid_, SIGTERM);
    int status = 0;
    waitpid(pid_, &status, 0);
  }
  bool started() const { return pid_ > 0; }
  // Whether it is still running (once it has exited, it is reaped and never signalled).
  bool running() {
    if (pid_ > 0 && !exited_ && waitpid(pid_, nullptr, WNOHANG) != 0) exited_ = true;
    return pid_ > 0 && !exited_;
  }

 private:
  pid_t pid_ = -1;
  bool exited_ = false;
};

std::string ReadFile(const std::string& path) {
  std::ifstream file(path);
  std::stringstream text;
  text << file.rdbuf();
  return text.str();
}

TEST(HttpPrometheusTest, ARealPrometheusScrapesTheIngestCounters) {
  if (!std::filesystem::exists(kPrometheus)) {
    // Loudly: scripts/install-deps.sh installs it, so this is a broken setup, not a normal skip.
    GTEST_SKIP() << "\n\n*** " << kPrometheus << " IS MISSING: the real-Prometheus test did not run. "
                 << "Run scripts/install-deps.sh (Debian package prometheus). ***\n";
  }
  TempDir dir;
  const std::string tokens = dir.Write("tokens", "read:scraper-token\nwrite:writer-token\n");
  auto daemon = FremendProcess::Start(dir.Path("data"), {"--tokens-file", tokens});
  ASSERT_TRUE(daemon.ok()) << daemon.status();
  const Metadata writer = {{"authorization", "Bearer writer-token"}};
  CreateGridMap(**daemon, "lab", writer);

  const std::string credentials = dir.Write("scrape-token", "scraper-token\n");
  const std::string config = dir.Write("prometheus.yml", absl::StrCat(R"(global:
  scrape_interval: 1s
  scrape_timeout: 1s
scrape_configs:
  - job_name: fremend
    authorization:
      type: Bearer
      credentials_file: )", credentials, R"(
    static_configs:
      - targets: [")", (*daemon)->http_address(), R"("]
)"));
  const int port = FreePort();
  ASSERT_NE(port, 0);
  const std::string log = dir.Path("prometheus.log");
  PrometheusProcess prometheus({"--config.file=" + config, "--storage.tsdb.path=" + dir.Path("tsdb"),
                                absl::StrCat("--web.listen-address=127.0.0.1:", port)},
                               log);
  ASSERT_TRUE(prometheus.started());

  const uint64_t sent = IngestCells(**daemon, "lab", 4, 120, writer);
  httplib::Client api("127.0.0.1", port);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(3);
  double value = 0;
  std::string last_answer;
  while (std::chrono::steady_clock::now() < deadline && prometheus.running()) {
    const httplib::Params query = {{"query", "fremen_ingest_observations_total{map=\"lab\"}"}};
    const httplib::Result answer = api.Get("/api/v1/query", query, httplib::Headers());
    if (answer && answer->status == 200) {
      last_answer = answer->body;
      google::protobuf::Struct json;
      ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(answer->body, &json).ok()) << answer->body;
      const auto& result = json.fields().at("data").struct_value().fields().at("result").list_value();
      if (result.values_size() > 0) {
        // A vector sample: "value": [<unix time>, "<value>"].
        const auto& sample = result.values(0).struct_value().fields().at("value").list_value();
        ASSERT_TRUE(absl::SimpleAtod(sample.values(1).string_value(), &value)) << answer->body;
        if (value >= static_cast<double>(sent)) break;
      }
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
  }
  EXPECT_EQ(value, static_cast<double>(sent)) << "Prometheus answered: " << last_answer
                                               << "\nits log:\n" << ReadFile(log);
  EXPECT_EQ((*daemon)->Stop(), 0);
}

}  // namespace
}  // namespace fremen::testing
