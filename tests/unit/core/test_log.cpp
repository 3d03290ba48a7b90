#include <gtest/gtest.h>

#include "mrvs/core/log.h"

namespace mrvs {
namespace {

TEST(Log, AcceptsKnownLevels) {
  for (const char* level : {"trace", "debug", "info", "warn", "error", "off"}) {
    EXPECT_TRUE(configure_logging(level).ok()) << level;
  }
  ASSERT_TRUE(configure_logging("warn").ok());
  EXPECT_EQ(spdlog::get_level(), spdlog::level::warn);
  ASSERT_TRUE(configure_logging("info").ok());
}

TEST(Log, RejectsUnknownLevelWithHelpfulMessage) {
  const Status s = configure_logging("verbose");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("verbose"), std::string::npos);
  EXPECT_NE(s.message().find("trace|debug|info|warn|error|off"), std::string::npos);
}

}  // namespace
}  // namespace mrvs

namespace mrvs {
namespace {

TEST(Log, LogsGoToStderrNotStdout) {
  ASSERT_TRUE(configure_logging("info").ok());
  ::testing::internal::CaptureStdout();
  ::testing::internal::CaptureStderr();
  spdlog::info("hello from the log test");
  spdlog::default_logger()->flush();
  const std::string out = ::testing::internal::GetCapturedStdout();
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(out.find("hello from the log test"), std::string::npos);
  EXPECT_NE(err.find("hello from the log test"), std::string::npos);
}

}  // namespace
}  // namespace mrvs
