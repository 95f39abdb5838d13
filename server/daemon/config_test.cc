#include "server/daemon/config.h"
#include "testing/temp_dir.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <stdlib.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace fremen::server {
namespace {

using ::testing::HasSubstr;

// The error message of applying `text` as a config file named test.conf.
std::string ErrorOf(absl::string_view text) {
  ServerConfig config;
  const absl::Status status = ApplyConfigText(text, "test.conf", config);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument) << text;
  return std::string(status.message());
}


TEST(ConfigTest, DefaultsAreValid) {
  ServerConfig config;
  ASSERT_TRUE(FinishConfig(config).ok());
  EXPECT_EQ(config.listen, "127.0.0.1:50051");
  EXPECT_EQ(config.http_listen, "127.0.0.1:50052");
  EXPECT_EQ(config.data_dir, "./fremen-data");
  EXPECT_EQ(config.update_schedule, "0 0 * * *");
  EXPECT_EQ(config.keepalive_time, absl::Seconds(20));
  EXPECT_EQ(config.keepalive_timeout, absl::Seconds(10));
  EXPECT_TRUE(config.tokens.empty());
}

TEST(ConfigTest, EveryFieldReadsBackWhatItPrints) {
  const ServerConfig defaults;
  for (const ConfigField& field : ConfigFields()) {
    if (field.key == "tokens") continue;  // prints a count, never the secrets
    ServerConfig config;
    ASSERT_TRUE(field.set(field.get(defaults), config).ok()) << field.key;
    EXPECT_EQ(field.get(config), field.get(defaults)) << field.key;
  }
}

TEST(ConfigTest, ParsesKeyValueLinesCommentsAndQuotes) {
  ServerConfig config;
  const absl::Status status = ApplyConfigText(
      "# a comment\n"
      "\n"
      "  listen = 0.0.0.0:6000  \n"
      "data_dir=/var/lib/fremen\r\n"
      "update_schedule = \"30 2 * * 1-5\"\n"
      "keepalive_time = 1m30s\n"
      "keepalive_permit_without_calls = no\n"
      "shards = 8\n"
      "tokens = read:r0 write:w0,read:r1\n",
      "test.conf", config);
  ASSERT_TRUE(status.ok()) << status;
  EXPECT_EQ(config.listen, "0.0.0.0:6000");
  EXPECT_EQ(config.data_dir, "/var/lib/fremen");
  EXPECT_EQ(config.update_schedule, "30 2 * * 1-5");
  EXPECT_EQ(config.keepalive_time, absl::Seconds(90));
  EXPECT_FALSE(config.keepalive_permit_without_calls);
  EXPECT_EQ(config.shards, 8u);
  EXPECT_THAT(config.tokens, ::testing::ElementsAre(TokenGrant{"r0", Access::kRead}, TokenGrant{"w0", Access::kWrite},
                                                    TokenGrant{"r1", Access::kRead}));
}

TEST(ConfigTest, AcceptsListenAddressesOfEveryForm) {
  for (const char* listen : {"127.0.0.1:50051", "[::1]:50051", "[::]:0", "localhost:1", "unix-host.lan:65535"}) {
    ServerConfig config;
    EXPECT_TRUE(SetConfigValue("listen", listen, "--listen", config).ok()) << listen;
  }
}

TEST(ConfigTest, TheHttpPortTakesAnAddressOrNothing) {
  ServerConfig config;
  ASSERT_TRUE(SetConfigValue("http_listen", "", "--http-listen", config).ok());
  EXPECT_EQ(config.http_listen, "");
  ASSERT_TRUE(SetConfigValue("http_listen", "[::1]:0", "--http-listen", config).ok());
  EXPECT_EQ(config.http_listen, "[::1]:0");
  EXPECT_THAT(ErrorOf("http_listen = 8080"), HasSubstr("config: http_listen: \"8080\" is not HOST:PORT"));
}

TEST(ConfigTest, BadValuesAreNamedWithWhereTheyCameFrom) {
  EXPECT_THAT(ErrorOf("listen = abc"), HasSubstr("config: listen: \"abc\" is not HOST:PORT"));
  EXPECT_THAT(ErrorOf("listen = abc"), HasSubstr("(test.conf line 1)"));
  EXPECT_THAT(ErrorOf("\n\nlisten = ::1:80"), HasSubstr("is not HOST:PORT"));
  EXPECT_THAT(ErrorOf("listen = host:"), HasSubstr("is not HOST:PORT"));
  EXPECT_THAT(ErrorOf("listen = host:-1"), HasSubstr("is not HOST:PORT"));
  EXPECT_THAT(ErrorOf("listen = host:70000"), HasSubstr("config: listen: \"host:70000\": port must be in [0, 65535]"));
  EXPECT_THAT(ErrorOf("data_dir ="), HasSubstr("config: data_dir: must not be empty"));
  EXPECT_THAT(ErrorOf("shards = 300"), HasSubstr("config: shards: \"300\" is not a whole number in [0, 256]"));
  EXPECT_THAT(ErrorOf("shards = -1"), HasSubstr("config: shards:"));
  EXPECT_THAT(ErrorOf("max_message_mb = 0"), HasSubstr("config: max_message_mb:"));
  EXPECT_THAT(ErrorOf("keepalive_time = 20"), HasSubstr("config: keepalive_time: \"20\" is not a duration"));
  EXPECT_THAT(ErrorOf("keepalive_timeout = 0s"), HasSubstr("config: keepalive_timeout: \"0s\" is outside [1s, 10m]"));
  EXPECT_THAT(ErrorOf("keepalive_permit_without_calls = maybe"),
              HasSubstr("config: keepalive_permit_without_calls: \"maybe\" is not true or false"));
  EXPECT_THAT(ErrorOf("update_schedule = 0 24 * * *"), HasSubstr("config: update_schedule: hour: 24 is outside"));
  EXPECT_THAT(ErrorOf("update_time_zone = Mars/Olympus"),
              HasSubstr("config: update_time_zone: unknown time zone \"Mars/Olympus\""));
  EXPECT_THAT(ErrorOf("log_level = loud"), HasSubstr("config: log_level: \"loud\" is not one of trace, debug"));
  EXPECT_THAT(ErrorOf("tokens = admin:x"), HasSubstr("config: tokens: role \"admin\" is neither read nor write"));
  EXPECT_THAT(ErrorOf("tokens = secret"), HasSubstr("is not ROLE:TOKEN"));
  EXPECT_THAT(ErrorOf("tokens = read:a b"), HasSubstr("is not ROLE:TOKEN"));
  EXPECT_THAT(ErrorOf("tokens = read:"), HasSubstr("a read token must be 1 or more of"));
}

TEST(ConfigTest, PerMapUpdateSchedules) {
  ServerConfig config;
  const absl::Status status =
      ApplyConfigText("update_map_schedules = \"lab = 30 2 * * *; yard=never;; hall=\"\n", "test.conf", config);
  ASSERT_TRUE(status.ok()) << status;
  EXPECT_THAT(config.update_map_schedules,
              ::testing::ElementsAre(MapSchedule{"lab", "30 2 * * *"}, MapSchedule{"yard", ""}, MapSchedule{"hall", ""}));
  // Written back as the file would spell it.
  for (const ConfigField& field : ConfigFields()) {
    if (field.key == "update_map_schedules") {
      EXPECT_EQ(field.get(config), "lab=30 2 * * *; yard=never; hall=never");
    }
  }
  EXPECT_THAT(ErrorOf("update_map_schedules = lab"),
              HasSubstr("config: update_map_schedules: \"lab\" is not MAP=CRON or MAP=never (test.conf line 1)"));
  EXPECT_THAT(ErrorOf("update_map_schedules = =0 0 * * *"), HasSubstr("names no map before '='"));
  EXPECT_THAT(ErrorOf("update_map_schedules = lab=0 24 * * *"),
              HasSubstr("config: update_map_schedules: map \"lab\": hour: 24 is outside"));
  EXPECT_THAT(ErrorOf("update_map_schedules = lab=never; lab=0 1 * * *"),
              HasSubstr("config: update_map_schedules: map \"lab\" is given twice"));
}

TEST(ConfigTest, ScrubIsOffByDefaultAndItsDurationsAreChecked) {
  EXPECT_EQ(ServerConfig().scrub_interval, absl::ZeroDuration());
  ServerConfig config;
  ASSERT_TRUE(ApplyConfigText("scrub_interval = 168h\n", "test.conf", config).ok());
  EXPECT_EQ(config.scrub_interval, absl::Hours(168));
  EXPECT_THAT(ErrorOf("scrub_interval = -1s"), HasSubstr("config: scrub_interval: \"-1s\" is outside [0, "));
  EXPECT_THAT(ErrorOf("scrub_interval = weekly"), HasSubstr("config: scrub_interval: \"weekly\""));
  EXPECT_EQ(ServerConfig().scrub_map_timeout, absl::Hours(1));
  ASSERT_TRUE(ApplyConfigText("scrub_map_timeout = 10m\n", "test.conf", config).ok());
  EXPECT_EQ(config.scrub_map_timeout, absl::Minutes(10));
  EXPECT_THAT(ErrorOf("scrub_map_timeout = 0s"), HasSubstr("config: scrub_map_timeout: \"0s\" is outside [1s, "));
}

TEST(ConfigTest, MalformedFilesAreNamedByLine) {
  EXPECT_THAT(ErrorOf("listen"), HasSubstr("config: expected key = value, got \"listen\" (test.conf line 1)"));
  EXPECT_THAT(ErrorOf("# x\nlisten_on = 1.2.3.4:5"),
              HasSubstr("config: unknown setting \"listen_on\" (test.conf line 2)"));
  EXPECT_THAT(ErrorOf("shards = 1\n\nshards = 2"), HasSubstr("config: shards: set twice, on lines 1 and 3"));
}

TEST(ConfigTest, MissingConfigFileIsNamed) {
  ServerConfig config;
  const absl::Status status = ApplyConfigFile("/nonexistent/fremend.conf", config);
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(status.message(), HasSubstr("config: cannot read \"/nonexistent/fremend.conf\""));
}

TEST(ConfigTest, TlsNeedsCertificateAndKey) {
  ServerConfig cert_only;
  cert_only.tls_cert_file = "/etc/fremen/cert.pem";
  EXPECT_THAT(FinishConfig(cert_only).message(), HasSubstr("config: tls_key_file: required with tls_cert_file"));
  ServerConfig ca_only;
  ca_only.tls_client_ca_file = "/etc/fremen/ca.pem";
  EXPECT_THAT(FinishConfig(ca_only).message(), HasSubstr("config: tls_client_ca_file: needs tls_cert_file"));
  ServerConfig unreadable;
  unreadable.tls_cert_file = "/nonexistent/cert.pem";
  unreadable.tls_key_file = "/nonexistent/key.pem";
  EXPECT_THAT(FinishConfig(unreadable).message(), HasSubstr("config: tls_cert_file: cannot read"));
}

TEST(ConfigTest, TlsFilesAreRead) {
  fremen::testing::TempDir files;
  ServerConfig config;
  config.tls_cert_file = files.Write("cert.pem", "CERT");
  config.tls_key_file = files.Write("key.pem", "KEY");
  ASSERT_TRUE(FinishConfig(config).ok());
  EXPECT_EQ(config.tls_cert_pem, "CERT");
  EXPECT_EQ(config.tls_key_pem, "KEY");
}

TEST(ConfigTest, TokensFileAddsToInlineTokens) {
  fremen::testing::TempDir files;
  ServerConfig config;
  ASSERT_TRUE(SetConfigValue("tokens", "read:inline", "--tokens", config).ok());
  config.tokens_file = files.Write("tokens", "# robots\nwrite:robot-1\n\n  read:dashboard  \n");
  ASSERT_TRUE(FinishConfig(config).ok());
  EXPECT_THAT(config.tokens,
              ::testing::ElementsAre(TokenGrant{"inline", Access::kRead}, TokenGrant{"robot-1", Access::kWrite},
                                     TokenGrant{"dashboard", Access::kRead}));
}

TEST(ConfigTest, BadTokensFileIsNamedByLine) {
  fremen::testing::TempDir files;
  ServerConfig config;
  config.tokens_file = files.Write("tokens", "write:robot-1\nsuper:x\n");
  EXPECT_THAT(FinishConfig(config).message(),
              HasSubstr("config: tokens_file: " + config.tokens_file + " line 2: role \"super\" is neither"));
}

TEST(ConfigTest, ATokenHasOneRole) {
  ServerConfig config;
  ASSERT_TRUE(SetConfigValue("tokens", "read:same write:same", "--tokens", config).ok());
  EXPECT_THAT(FinishConfig(config).message(), HasSubstr("config: tokens: a token is given twice"));
}

// The example shipped in deploy/ documents every setting and is itself a valid config.
TEST(ConfigTest, ExampleConfigParsesAndDocumentsEveryField) {
  const std::string path = std::string(FREMEN_SOURCE_DIR) + "/deploy/fremend.conf.example";
  std::ifstream in(path);
  ASSERT_TRUE(in) << path;
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ServerConfig config;
  EXPECT_TRUE(ApplyConfigText(text, path, config).ok());
  for (const ConfigField& field : ConfigFields()) {
    EXPECT_THAT(text, HasSubstr(std::string(field.key) + " =")) << "not in the example: " << field.key;
  }
}

}  // namespace
}  // namespace fremen::server
