// End-to-end tests of `fremenctl eval`: the real binary (FREMENCTL_BINARY, set by CMake) is run on
// `time state` files generated in a temporary directory, and its output and exit code are checked.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "testing/temp_dir.h"
#include "tests/process_runner.h"

namespace {

namespace fs = std::filesystem;

using ::fremen::testing::RunProgram;
using ::fremen::testing::RunResult;
using Args = std::vector<std::string>;

// Epoch times, so that the tests also cover phase precision at realistic timestamps.
constexpr double kStart = 1.7e9;
constexpr double kDay = 86400;
constexpr double kWeek = 7 * kDay;

class FremenctlEvalTest : public ::testing::Test {
 protected:

  // Writes `text` to a file in the temporary directory; returns its path.
  std::string Write(const std::string& name, const std::string& text) {
    const std::string path = (dir_ / name).string();
    std::ofstream(path) << text;
    return path;
  }

  // Samples s(t) = [sin(2πt/day) > 0] (a door open half of each day) every 10 minutes in
  // [from, to); returns the file's path.
  std::string WriteDailySquareWave(const std::string& name, double from, double to) {
    std::ostringstream text;
    for (double t = from; t < to; t += 600) {
      text << static_cast<long long>(t) << ' ' << (std::sin(2 * M_PI * t / kDay) > 0 ? 1 : 0) << '\n';
    }
    return Write(name, text.str());
  }

  RunResult Run(const Args& args) { return RunProgram(FREMENCTL_BINARY, args); }

  // `fremenctl eval` trained on three weeks of the daily square wave, tested on the week after.
  RunResult EvalSquareWave(const Args& extra_args = {}) {
    const std::string train = WriteDailySquareWave("train.txt", kStart, kStart + 3 * kWeek);
    const std::string test = WriteDailySquareWave("test.txt", kStart + 3 * kWeek, kStart + 4 * kWeek);
    Args args = {"eval", "--train", train, "--test", test};
    args.insert(args.end(), extra_args.begin(), extra_args.end());
    return Run(args);
  }

  fremen::testing::TempDir temp_;
  const fs::path dir_{temp_.path()};
};

struct Row {
  int order;
  double err, mse;
};

// Parses the table, failing the test on a line not of the form order<TAB>err<TAB>mse.
std::vector<Row> ParseTable(const std::string& out) {
  static const std::regex kLine(R"((\d+)\t(\d+\.\d+)\t(\d+\.\d+))");
  std::vector<Row> rows;
  std::istringstream lines(out);
  for (std::string line; std::getline(lines, line);) {
    std::smatch m;
    EXPECT_TRUE(std::regex_match(line, m, kLine)) << "bad line: \"" << line << "\"";
    if (m.empty()) continue;
    rows.push_back({std::stoi(m[1]), std::stod(m[2]), std::stod(m[3])});
  }
  return rows;
}

TEST_F(FremenctlEvalTest, PrintsOneLinePerOrderUpToMaxOrder) {
  for (int max_order : {0, 3, 5}) {
    const RunResult result = EvalSquareWave({"--max-order", std::to_string(max_order)});
    ASSERT_EQ(result.exit_code, 0) << result.err;
    const std::vector<Row> rows = ParseTable(result.out);
    ASSERT_EQ(rows.size(), static_cast<size_t>(max_order + 1)) << result.out;
    for (int order = 0; order <= max_order; ++order) {
      EXPECT_EQ(rows[order].order, order);
      EXPECT_GE(rows[order].err, 0);
      EXPECT_LE(rows[order].err, 1);
      EXPECT_GE(rows[order].mse, 0);
      EXPECT_LE(rows[order].mse, 1);
    }
  }
}

TEST_F(FremenctlEvalTest, DefaultsToOrdersZeroToFive) {
  const RunResult result = EvalSquareWave();
  ASSERT_EQ(result.exit_code, 0) << result.err;
  EXPECT_EQ(ParseTable(result.out).size(), 6u);
}

TEST_F(FremenctlEvalTest, PeriodicModelBeatsTheMeanOnAPeriodicSignal) {
  for (const Args& args : {Args{}, Args{"--periods", "100", "--floor-periods"}, Args{"--persistence"}}) {
    SCOPED_TRACE(::testing::PrintToString(args));
    const RunResult result = EvalSquareWave(args);
    ASSERT_EQ(result.exit_code, 0) << result.err;
    SCOPED_TRACE(result.out);
    const std::vector<Row> rows = ParseTable(result.out);
    ASSERT_EQ(rows.size(), 6u);
    // The mean (order 0) is wrong half of the time; the daily component gets almost all right.
    EXPECT_GT(rows[0].err, 0.4);
    for (size_t order = 1; order < rows.size(); ++order) {
      EXPECT_LT(rows[order].err, rows[0].err / 5) << "order " << order;
      EXPECT_LT(rows[order].mse, rows[0].mse) << "order " << order;
    }
  }
}

TEST_F(FremenctlEvalTest, ReplayAddsTheOrderEachRuleSelects) {
  const RunResult result = EvalSquareWave({"--replay"});
  ASSERT_EQ(result.exit_code, 0) << result.err;
  static const std::regex kRuleLine(R"((paper|margin|default|weighted)\t(\d+)\t(\d+\.\d+)\t(\d+\.\d+))");
  std::istringstream lines(result.out);
  std::vector<std::string> rules;
  int table_lines = 0;
  for (std::string line; std::getline(lines, line);) {
    std::smatch m;
    if (std::regex_match(line, m, kRuleLine)) {
      rules.push_back(m[1]);
      EXPECT_GE(std::stoi(m[2]), 1) << line;  // the daily component, by every rule
      EXPECT_LT(std::stod(m[3]), 0.1) << line;
    } else {
      ++table_lines;
      EXPECT_EQ(rules.size(), 0u) << "table line after the rules: " << line;
    }
  }
  EXPECT_EQ(table_lines, 6);
  EXPECT_EQ(rules, (std::vector<std::string>{"paper", "margin", "default", "weighted"}));
  // Without --replay, the table alone.
  const RunResult plain = EvalSquareWave();
  EXPECT_EQ(plain.out.find("paper"), std::string::npos);
}

// A bad training file: its contents (or none: the file is missing), and the line the error names
// (0: the message names the file only).
struct BadFile {
  std::string name;
  const char* text;  // nullptr: no file
  int line;
};

class FremenctlEvalBadInputTest : public FremenctlEvalTest, public ::testing::WithParamInterface<BadFile> {};

TEST_P(FremenctlEvalBadInputTest, FailsNamingFileAndLine) {
  const std::string test = WriteDailySquareWave("test.txt", kStart, kStart + kDay);
  const std::string train = GetParam().text ? Write("train.txt", GetParam().text) : (dir_ / "missing.txt").string();
  const RunResult result = Run({"eval", "--train", train, "--test", test});
  EXPECT_EQ(result.exit_code, 1);
  EXPECT_EQ(result.out, "");
  const std::string place = GetParam().line > 0 ? train + ":" + std::to_string(GetParam().line) + ":" : train;
  EXPECT_NE(result.err.find(place), std::string::npos) << "stderr: " << result.err << "expected: " << place;
}

INSTANTIATE_TEST_SUITE_P(Cases, FremenctlEvalBadInputTest,
                         ::testing::Values(BadFile{"MissingFile", nullptr, 0},
                                           BadFile{"MalformedLine", "0 0\n60 1\n120 open\n", 3},
                                           BadFile{"StateAboveOne", "0 0\n60 2.0\n", 2},
                                           BadFile{"NaNTime", "0 0\n60 1\nnan 1\n180 0\n", 3}),
                         [](const ::testing::TestParamInfo<BadFile>& info) { return info.param.name; });

TEST_F(FremenctlEvalTest, UsageErrorsExitWithTwo) {
  const std::string data = WriteDailySquareWave("data.txt", kStart, kStart + kDay);
  const Args eval = {"eval", "--train", data, "--test", data};
  auto with = [&](const Args& more) {
    Args args = eval;
    args.insert(args.end(), more.begin(), more.end());
    return args;
  };
  for (const Args& args : {with({"--no-such-option"}), Args{"eval", "--train", data}, with({"--max-order", "65"}),
                           with({"--periods", "x"}), Args{"no-such-command"}, Args{}}) {
    const RunResult result = Run(args);
    EXPECT_EQ(result.exit_code, 2) << "fremenctl " << ::testing::PrintToString(args);
    EXPECT_NE(result.err, "") << "fremenctl " << ::testing::PrintToString(args);
    // Usage errors say so on stderr only: stdout is for results.
    EXPECT_EQ(result.out, "") << "fremenctl " << ::testing::PrintToString(args);
  }
}

TEST_F(FremenctlEvalTest, HelpDescribesEveryOption) {
  const RunResult result = Run({"eval", "--help"});
  EXPECT_EQ(result.exit_code, 0);
  for (const char* option : {"--train", "--test", "--periods", "--longest", "--floor-periods", "--max-order",
                             "--persistence"}) {
    EXPECT_NE(result.out.find(option), std::string::npos) << option;
  }
  EXPECT_EQ(Run({"--help"}).exit_code, 0);
}

}  // namespace
