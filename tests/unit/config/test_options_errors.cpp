// Error reporting of the Options loader: every message names the file, line and column,
// the dotted key and what was expected.
#include <algorithm>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "example_options.h"
#include "mrvs/config/options.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::config {
namespace {

using test_options::ExampleOptions;
using test_options::RootOptions;
using ::testing::HasSubstr;

std::vector<std::string> lines(const Status& s) {
  std::vector<std::string> out;
  std::string text(s.message());
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = text.find('\n', start);
    out.push_back(text.substr(start, end - start));
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return out;
}

/// Loads `text` (written to a temporary file) as the "tracker" section; returns the
/// status and the file name used in messages.
std::pair<Status, std::string> load_tracker(const std::string& text) {
  test::TempDir dir;
  const auto path = dir.write("tuning.yaml", text);
  auto o = load_options_file<ExampleOptions>(path, "tracker");
  return {o.status(), path.string()};
}

TEST(OptionsErrors, AllErrorsAreCollectedWithFileLineColumnKeyAndExpectation) {
  const std::string text =
      "tracker:\n"                    // 1
      "  max_features: 100000\n"      // 2: out of range
      "  min_px_dist: abc\n"          // 3: wrong type
      "  use_fej: maybe\n"            // 4: not a boolean
      "  mode: fast\n"                // 5: not one of
      "  resolutions: [0.5, 20.0]\n"  // 6: element out of range
      "  gravity: [1, 2]\n"           // 7: wrong size
      "  max_featurs: 3\n"            // 8: unknown key, near miss
      "  update: slow\n"              // 9: unknown enum name
      "  imu:\n"                      // 10
      "    rate_hz: 0\n"              // 11: out of range
      "    gyro_noise: 1\n";          // 12: unknown key, no near miss
  const auto [status, f] = load_tracker(text);
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.code(), absl::StatusCode::kInvalidArgument);
  const std::vector<std::string> expected = {
      f + ":2:17: key 'tracker.max_features': expected an integer in [1, 5000], got '100000'",
      f + ":3:16: key 'tracker.min_px_dist': expected a number in [0, 100], got 'abc'",
      f + ":4:12: key 'tracker.use_fej': expected a boolean (true/false), got 'maybe'",
      f + ":5:9: key 'tracker.mode': expected one of 'known_landmark', 'msckf_nullspace', got 'fast'",
      f + ":9:11: key 'tracker.update': expected one of 'known_landmark', 'msckf_nullspace', got 'slow'",
      f + ":6:16: key 'tracker.resolutions': expected a list of 1 to 16 numbers, each in [0.001, 10], got "
          "'[0.5, 20.0]'",
      f + ":7:12: key 'tracker.gravity': expected a list of 3 numbers, got '[1, 2]'",
      f + ":11:14: key 'tracker.imu.rate_hz': expected a number in [1, 10000], got '0'",
      f + ":12:5: key 'tracker.imu.gyro_noise': unknown key (known keys here: gyroscope_noise_density, "
          "rate_hz)",
      f + ":8:3: key 'tracker.max_featurs': unknown key, did you mean 'max_features'?",
  };
  EXPECT_EQ(lines(status), expected);
}

TEST(OptionsErrors, FailedLoadLeavesTheStructUnchanged) {
  auto doc = parse_yaml_string("max_features: 10\nmin_px_dist: -1\n", "t.yaml");
  ASSERT_TRUE(doc.ok());
  ExampleOptions o;
  o.max_features = 7;
  EXPECT_FALSE(update_options(*doc, "", o).ok());
  EXPECT_EQ(o.max_features, 7);  // the valid key was not applied either
}

TEST(OptionsErrors, WrongScalarKinds) {
  const auto [status, f] = load_tracker(
      "tracker:\n"
      "  max_features: 300.5\n"
      "  window_ns:\n"
      "  levels: [1, x]\n"
      "  resolutions: []\n"
      "  cameras: {a: 1}\n"
      "  quality: [0.5]\n");
  ASSERT_FALSE(status.ok());
  const std::vector<std::string> got = lines(status);
  ASSERT_EQ(got.size(), 6u) << status;
  EXPECT_EQ(got[0], f + ":2:17: key 'tracker.max_features': expected an integer in [1, 5000], got '300.5'");
  EXPECT_THAT(got[1], HasSubstr("key 'tracker.window_ns': expected an integer >= 0, got ''"));
  EXPECT_EQ(got[2], f + ":7:12: key 'tracker.quality': expected a number in [0, 1], got '[0.5]'");
  EXPECT_EQ(got[3], f + ":5:16: key 'tracker.resolutions': expected a list of 1 to 16 numbers, each in "
                        "[0.001, 10], got '[]'");
  EXPECT_EQ(got[4], f + ":4:11: key 'tracker.levels': expected a list of up to 8 integers, got '[1, x]'");
  EXPECT_EQ(got[5], f + ":6:12: key 'tracker.cameras': expected a list of strings, got '{a: 1}'");
}

TEST(OptionsErrors, SectionThatIsNotAMap) {
  {
    const auto [status, f] = load_tracker("tracker: 5\n");
    EXPECT_EQ(std::string(status.message()),
              f + ":1:10: key 'tracker': expected a section (a map of keys), got '5'");
  }
  {
    const auto [status, f] = load_tracker("tracker:\n  imu: [1]\n");
    EXPECT_EQ(std::string(status.message()),
              f + ":2:8: key 'tracker.imu': expected a section (a map of keys), got '[1]'");
  }
}

TEST(OptionsErrors, DuplicateKeysAreReported) {
  const auto [status, f] = load_tracker("tracker:\n  max_features: 10\n  max_features: 20\n");
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(std::string(status.message()),
            f + ":3:3: key 'tracker.max_features': duplicate key (first at " + f + ":2:3)");
}

TEST(OptionsErrors, MisspeltSectionOfARootStruct) {
  auto doc = parse_yaml_string("trackr:\n  max_features: 10\n", "root.yaml");
  ASSERT_TRUE(doc.ok());
  auto root = load_options<RootOptions>(*doc);
  ASSERT_FALSE(root.ok());
  EXPECT_EQ(std::string(root.status().message()),
            "root.yaml:1:1: key 'trackr': unknown key, did you mean 'tracker'?");
}

TEST(OptionsErrors, SuggestionIsCaseInsensitiveAndHandlesSwaps) {
  auto doc = parse_yaml_string("MAX_FEATURES: 10\nmin_dx_pist: 1\nuse_fje: true\n", "t.yaml");
  ASSERT_TRUE(doc.ok());
  auto o = load_options<ExampleOptions>(*doc);
  ASSERT_FALSE(o.ok());
  const std::string message(o.status().message());
  EXPECT_THAT(message, HasSubstr("key 'MAX_FEATURES': unknown key, did you mean 'max_features'?"));
  EXPECT_THAT(message, HasSubstr("key 'min_dx_pist': unknown key, did you mean 'min_px_dist'?"));
  EXPECT_THAT(message, HasSubstr("key 'use_fje': unknown key, did you mean 'use_fej'?"));
}

TEST(OptionsErrors, OverridesAreValidatedAndNamed) {
  auto doc = parse_yaml_string("tracker:\n  max_features: 10\n", "t.yaml");
  ASSERT_TRUE(doc.ok());
  ASSERT_TRUE(apply_overrides(
                  *doc, {"tracker.max_features=100000", "tracker.max_featurs=3", "tracker.imu.rate_hz=fast"})
                  .ok());
  auto o = load_options<ExampleOptions>(*doc, "tracker");
  ASSERT_FALSE(o.ok());
  const std::vector<std::string> expected = {
      "override 'tracker.max_features=100000': key 'tracker.max_features': expected an integer in [1, 5000], "
      "got "
      "'100000'",
      "override 'tracker.imu.rate_hz=fast': key 'tracker.imu.rate_hz': expected a number in [1, 10000], got "
      "'fast'",
      "override 'tracker.max_featurs=3': key 'tracker.max_featurs': unknown key, did you mean "
      "'max_features'?",
  };
  EXPECT_EQ(lines(o.status()), expected);
}

TEST(OptionsErrors, ValidateNamesKeyAndValue) {
  ExampleOptions o;
  o.max_features = 0;
  o.imu.rate_hz = -1.0;
  o.mode = "other";
  const Status s = validate_options(o, "tracker");
  const std::vector<std::string> expected = {
      "key 'tracker.max_features': expected an integer in [1, 5000], got '0'",
      "key 'tracker.mode': expected one of 'known_landmark', 'msckf_nullspace', got 'other'",
      "key 'tracker.imu.rate_hz': expected a number in [1, 10000], got '-1.0'",
  };
  EXPECT_EQ(lines(s), expected);
}

TEST(OptionsErrors, MalformedYamlAndMissingFile) {
  test::TempDir dir;
  const auto bad = dir.write("bad.yaml", "tracker:\n  max_features: 10\n   min_px_dist: 3\n");
  auto o = load_options_file<ExampleOptions>(bad, "tracker");
  ASSERT_FALSE(o.ok());
  EXPECT_THAT(std::string(o.status().message()), ::testing::StartsWith(bad.string() + ":3:"));

  const auto missing = dir / "missing.yaml";
  auto m = load_options_file<ExampleOptions>(missing, "tracker");
  ASSERT_FALSE(m.ok());
  EXPECT_EQ(m.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(std::string(m.status().message()), HasSubstr(missing.string()));
}

TEST(OptionsErrors, OpenCvHeaderKeepsErrorLinesRight) {
  const auto [status, f] = load_tracker("%YAML:1.0\ntracker:\n  max_features: 0\n");
  EXPECT_EQ(std::string(status.message()),
            f + ":3:17: key 'tracker.max_features': expected an integer in [1, 5000], got '0'");
}

}  // namespace
}  // namespace mrvs::config
