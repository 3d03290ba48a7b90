#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "mrvs/core/cli.h"
#include "mrvs/core/log.h"

namespace mrvs {
namespace {

// Runs parse_command_line on a fake argv.
std::optional<int> parse(CLI::App& app, std::vector<std::string> args, const std::string& level) {
  args.insert(args.begin(), "tool");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  return parse_command_line(app, static_cast<int>(argv.size()), argv.data(), level);
}

TEST(Cli, GoesOnAfterAValidCommandLine) {
  CLI::App app{"test", "tool"};
  int n = 0;
  std::string level = "info";
  app.add_option("--n", n);
  add_log_level_option(app, level);
  EXPECT_EQ(parse(app, {"--n", "3", "--log-level", "warn"}, level), std::nullopt);
  EXPECT_EQ(n, 3);
  EXPECT_EQ(level, "warn");
  EXPECT_EQ(spdlog::get_level(), spdlog::level::warn);
}

TEST(Cli, HelpExitsZeroAndUsageErrorsExitTwo) {
  CLI::App help_app{"test", "tool"};
  ::testing::internal::CaptureStdout();
  EXPECT_EQ(parse(help_app, {"--help"}, "info"), kExitOk);
  ::testing::internal::GetCapturedStdout();

  CLI::App app{"test", "tool"};
  int n = 0;
  app.add_option("--n", n)->required();
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(parse(app, {}, "info"), kExitUsageError);
  EXPECT_NE(::testing::internal::GetCapturedStderr().find("--n"), std::string::npos);
}

TEST(Cli, UnknownLogLevelIsAUsageErrorNamingIt) {
  CLI::App app{"test", "tool"};
  std::string level = "info";
  add_log_level_option(app, level);
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(parse(app, {"--log-level", "loud"}, level), kExitUsageError);
  EXPECT_NE(::testing::internal::GetCapturedStderr().find("loud"), std::string::npos);
}

}  // namespace
}  // namespace mrvs
