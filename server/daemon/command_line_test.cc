#include "server/daemon/command_line.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <stdlib.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "testing/temp_dir.h"

namespace fremen::server {
namespace {

using ::testing::HasSubstr;

struct Outcome {
  CommandLine result;
  std::string out;
  std::string err;
};

Outcome Parse(std::vector<std::string> args) {
  args.insert(args.begin(), "fremend");
  std::vector<const char*> argv;
  for (const std::string& arg : args) argv.push_back(arg.c_str());
  std::ostringstream out, err;
  CommandLine result = ParseCommandLine(static_cast<int>(argv.size()), argv.data(), out, err);
  return {std::move(result), out.str(), err.str()};
}

class CommandLineTest : public ::testing::Test {
 protected:
  std::string WriteConfig(const std::string& text) {
    const std::string path = (dir_ / "fremend.conf").string();
    std::ofstream(path) << text;
    return path;
  }
  fremen::testing::TempDir temp_;
  const std::filesystem::path dir_{temp_.path()};
};

TEST_F(CommandLineTest, NoArgumentsRunWithTheDefaults) {
  const Outcome outcome = Parse({});
  ASSERT_TRUE(outcome.result.config.has_value()) << outcome.err;
  EXPECT_EQ(outcome.result.config->listen, "127.0.0.1:50051");
}

TEST_F(CommandLineTest, VerifyKeepsTheSettingsAndAsksForTheOfflineCheck) {
  const std::string config = WriteConfig("data_dir = /srv/fremen\n");
  const Outcome outcome = Parse({"--config", config, "--verify"});
  ASSERT_TRUE(outcome.result.config.has_value()) << outcome.err;
  EXPECT_TRUE(outcome.result.verify);
  EXPECT_EQ(outcome.result.exit_code, kExitOk);
  EXPECT_EQ(outcome.result.config->data_dir, "/srv/fremen");
  EXPECT_FALSE(Parse({}).result.verify);
}

TEST_F(CommandLineTest, FlagsOverrideTheFileWhichOverridesTheDefaults) {
  const std::string config = WriteConfig("listen = 0.0.0.0:7000\ndata_dir = /srv/fremen\nshards = 4\n");
  const Outcome outcome = Parse({"--config", config, "--listen", "127.0.0.1:7001", "--keepalive-time", "45s"});
  ASSERT_TRUE(outcome.result.config.has_value()) << outcome.err;
  EXPECT_EQ(outcome.result.config->listen, "127.0.0.1:7001");
  EXPECT_EQ(outcome.result.config->data_dir, "/srv/fremen");
  EXPECT_EQ(outcome.result.config->shards, 4u);
  EXPECT_EQ(outcome.result.config->keepalive_time, absl::Seconds(45));
}

TEST_F(CommandLineTest, FlagWithEqualsAndNothingAfterItSetsAnEmptyValue) {
  // `--update-schedule=` disables the schedule; the next argument stays an argument of its own.
  const Outcome outcome = Parse({"--update-schedule=", "--data-dir=/srv/fremen"});
  ASSERT_TRUE(outcome.result.config.has_value()) << outcome.err;
  EXPECT_EQ(outcome.result.config->update_schedule, "");
  EXPECT_EQ(outcome.result.config->data_dir, "/srv/fremen");
}

TEST_F(CommandLineTest, HelpListsEverySettingAsAFlag) {
  const Outcome outcome = Parse({"--help"});
  EXPECT_FALSE(outcome.result.config.has_value());
  EXPECT_EQ(outcome.result.exit_code, kExitOk);
  for (const char* flag : {"--config", "--listen", "--data-dir", "--tokens-file", "--update-schedule", "--check-config"}) {
    EXPECT_THAT(outcome.out, HasSubstr(flag));
  }
  EXPECT_THAT(outcome.out, HasSubstr("127.0.0.1:50051"));  // defaults are shown
}

TEST_F(CommandLineTest, BadValuesExitWithCodeTwoNamingTheSetting) {
  const Outcome outcome = Parse({"--listen", "abc"});
  EXPECT_FALSE(outcome.result.config.has_value());
  EXPECT_EQ(outcome.result.exit_code, kExitBadConfig);
  EXPECT_THAT(outcome.err, HasSubstr("config: listen: \"abc\" is not HOST:PORT"));
  EXPECT_THAT(outcome.err, HasSubstr("(--listen)"));
}

TEST_F(CommandLineTest, BadFileValueIsNamedByLine) {
  const std::string config = WriteConfig("# fremend\nmax_message_mb = lots\n");
  const Outcome outcome = Parse({"--config", config});
  EXPECT_EQ(outcome.result.exit_code, kExitBadConfig);
  EXPECT_THAT(outcome.err, HasSubstr("config: max_message_mb: \"lots\""));
  EXPECT_THAT(outcome.err, HasSubstr("fremend.conf line 2"));
}

TEST_F(CommandLineTest, UnknownFlagExitsWithCodeTwo) {
  const Outcome outcome = Parse({"--lisen", "127.0.0.1:1"});
  EXPECT_EQ(outcome.result.exit_code, kExitBadConfig);
  EXPECT_FALSE(outcome.err.empty());
}

TEST_F(CommandLineTest, CheckConfigValidatesAndExits) {
  const Outcome good = Parse({"--check-config", "--shards", "2"});
  EXPECT_FALSE(good.result.config.has_value());
  EXPECT_EQ(good.result.exit_code, kExitOk);
  EXPECT_THAT(good.out, HasSubstr("config OK"));
  const Outcome bad = Parse({"--check-config", "--tls-cert-file", "/nonexistent.pem"});
  EXPECT_EQ(bad.result.exit_code, kExitBadConfig);
}

}  // namespace
}  // namespace fremen::server
