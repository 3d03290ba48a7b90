// The Options mechanism: loading, defaults, printing, saving, equality, overrides.
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "example_options.h"
#include "mrvs/config/options.h"
#include "mrvs/test/temp_dir.h"

namespace {

/// Declared outside mrvs::config, as module code does (see the options.h example).
struct OutsideOptions : mrvs::config::OptionsEquality<OutsideOptions> {
  int count = 1;  ///< things

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("count", count, in_range(0, 10), "things");
  }
};

}  // namespace

namespace mrvs::config {
namespace {

using test_options::ExampleOptions;
using test_options::ImuNoiseOptions;
using test_options::RootOptions;
using test_options::UpdateMode;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

constexpr const char* kTuningFile = R"(# tuning file
tracker:
  max_features: 300
  window_ns: 7000000000
  min_px_dist: 12.5
  quality: 0.05
  use_fej: false
  mode: msckf_nullspace
  update: msckf_nullspace
  resolutions: [0.05, 0.1]
  levels: []
  cameras: [left, "right cam"]
  gravity: [0.0, 0.1, -9.8]
  calibration: euroc/camchain-imucam.yaml
  imu:
    rate_hz: 400
imu:
  gyroscope_noise_density: 0.001
)";

/// The line of `text` that starts (after indentation) with `key:`.
std::string line_of(const std::string& text, const std::string& key) {
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t end = text.find('\n', start);
    const std::string line = text.substr(start, end - start);
    const std::size_t first = line.find_first_not_of(' ');
    if (first != std::string::npos && line.compare(first, key.size() + 1, key + ":") == 0) return line;
    if (end == std::string::npos) break;
    start = end + 1;
  }
  return "";
}

/// Every field changed from its default, including awkward values for the writer.
ExampleOptions non_default_options() {
  ExampleOptions o;
  o.max_features = 4999;
  o.window_ns = 9'000'000'000'123;
  o.min_px_dist = 0.1 + 0.2;  // 0.30000000000000004: needs 17 digits
  o.quality = 0.3f;
  o.use_fej = false;
  o.mode = "msckf_nullspace";
  o.update = UpdateMode::kMsckfNullspace;
  o.resolutions = {1e-3, 1.0 / 3.0, 10.0};
  o.levels = {};
  o.cameras = {"true", "", "with space", "quote\"and\\backslash", "42", "/abs/path"};
  o.gravity = Eigen::Vector3d(-1e-300, 2.5e10, -9.80665);
  o.calibration = "/data/euroc/camchain-imucam.yaml";
  o.imu.gyroscope_noise_density = 2.0e-5;
  o.imu.rate_hz = 1000.0;
  return o;
}

TEST(Options, WorksForStructsOutsideTheConfigNamespace) {
  auto doc = parse_yaml_string("module:\n  count: 7\n");
  ASSERT_TRUE(doc.ok());
  auto o = load_options<OutsideOptions>(*doc, "module");
  ASSERT_TRUE(o.ok()) << o.status();
  EXPECT_EQ(o->count, 7);
  EXPECT_NE(*o, OutsideOptions{});
  EXPECT_EQ(options_to_yaml(*o, "module"), "module:\n  count: 7  # things\n");
}

TEST(Options, DefaultsSatisfyTheirOwnConstraints) {
  EXPECT_TRUE(validate_options(ExampleOptions{}).ok());
  EXPECT_TRUE(validate_options(non_default_options()).ok());
}

TEST(Options, LoadsEveryFieldTypeFromASection) {
  test::TempDir dir;
  const auto path = dir.write("tuning.yaml", kTuningFile);
  auto doc = load_yaml_file(path);
  ASSERT_TRUE(doc.ok()) << doc.status();
  auto o = load_options<ExampleOptions>(*doc, "tracker");
  ASSERT_TRUE(o.ok()) << o.status();
  EXPECT_EQ(o->max_features, 300);
  EXPECT_EQ(o->window_ns, 7'000'000'000);
  EXPECT_EQ(o->min_px_dist, 12.5);
  EXPECT_EQ(o->quality, 0.05f);
  EXPECT_FALSE(o->use_fej);
  EXPECT_EQ(o->mode, "msckf_nullspace");
  EXPECT_EQ(o->update, UpdateMode::kMsckfNullspace);
  EXPECT_THAT(o->resolutions, ElementsAre(0.05, 0.1));
  EXPECT_TRUE(o->levels.empty());
  EXPECT_THAT(o->cameras, ElementsAre("left", "right cam"));
  EXPECT_EQ(o->gravity, Eigen::Vector3d(0.0, 0.1, -9.8));
  EXPECT_EQ(o->calibration, dir.path() / "euroc/camchain-imucam.yaml");  // relative to the file
  EXPECT_EQ(o->imu.rate_hz, 400.0);
  // Absent from the file: the in-class default.
  EXPECT_EQ(o->imu.gyroscope_noise_density, ImuNoiseOptions{}.gyroscope_noise_density);
}

TEST(Options, LoadsTheWholeFileThroughARootStruct) {
  auto doc = parse_yaml_string(kTuningFile, "tuning.yaml");
  ASSERT_TRUE(doc.ok());
  auto root = load_options<RootOptions>(*doc);
  ASSERT_TRUE(root.ok()) << root.status();
  EXPECT_EQ(root->tracker.max_features, 300);
  EXPECT_EQ(root->imu.gyroscope_noise_density, 0.001);
  EXPECT_EQ(root->imu.rate_hz, 200.0);
}

TEST(Options, MissingSectionMeansAllDefaults) {
  auto doc = parse_yaml_string("other: 1\n");
  ASSERT_TRUE(doc.ok());
  auto o = load_options<ExampleOptions>(*doc, "tracker");
  ASSERT_TRUE(o.ok()) << o.status();
  EXPECT_EQ(*o, ExampleOptions{});
  auto empty = load_options<ExampleOptions>(*parse_yaml_string("tracker:\n"), "tracker");
  ASSERT_TRUE(empty.ok()) << empty.status();
  EXPECT_EQ(*empty, ExampleOptions{});
}

TEST(Options, LoadsNestedDottedSection) {
  auto doc = parse_yaml_string("a:\n  b:\n    rate_hz: 50\n");
  ASSERT_TRUE(doc.ok());
  auto o = load_options<ImuNoiseOptions>(*doc, "a.b");
  ASSERT_TRUE(o.ok()) << o.status();
  EXPECT_EQ(o->rate_hz, 50.0);
}

TEST(Options, AcceptsOpenCvHeader) {
  test::TempDir dir;
  const auto path = dir.write("cv.yaml", "%YAML:1.0\nrate_hz: 100\n");
  auto o = load_options_file<ImuNoiseOptions>(path);
  ASSERT_TRUE(o.ok()) << o.status();
  EXPECT_EQ(o->rate_hz, 100.0);
}

TEST(Options, PrintShowsValuesCommentsAndDefaultMarkers) {
  auto doc = parse_yaml_string(kTuningFile, "tuning.yaml");
  ASSERT_TRUE(doc.ok());
  auto o = load_options<ExampleOptions>(*doc, "tracker");
  ASSERT_TRUE(o.ok()) << o.status();
  o->min_px_dist = ExampleOptions{}.min_px_dist;  // back to the default
  const std::string text = options_to_yaml(*o, "tracker");
  EXPECT_EQ(text.rfind("tracker:\n", 0), 0u) << text;
  const std::string max_features = line_of(text, "max_features");
  EXPECT_THAT(max_features, ::testing::StartsWith("  max_features: 300 "));
  EXPECT_THAT(max_features, HasSubstr("# features per frame"));
  EXPECT_THAT(max_features, ::testing::Not(HasSubstr("(default)")));
  const std::string min_px = line_of(text, "min_px_dist");
  EXPECT_THAT(min_px, ::testing::StartsWith("  min_px_dist: 10.0 "));
  EXPECT_THAT(min_px, HasSubstr("# px between features (default)"));
  EXPECT_THAT(line_of(text, "resolutions"), ::testing::StartsWith("  resolutions: [0.05, 0.1] "));
  EXPECT_THAT(line_of(text, "cameras"), ::testing::StartsWith("  cameras: [left, \"right cam\"] "));
  EXPECT_THAT(line_of(text, "update"), ::testing::StartsWith("  update: msckf_nullspace "));
  EXPECT_THAT(line_of(text, "imu"), ::testing::StartsWith("  imu: "));
  EXPECT_THAT(line_of(text, "gyroscope_noise_density"), HasSubstr("(default)"));
  EXPECT_THAT(line_of(text, "gyroscope_noise_density"),
              ::testing::StartsWith("    gyroscope_noise_density: "));
  // Comments start in one column.
  EXPECT_EQ(max_features.find('#'), min_px.find('#'));
}

TEST(Options, PrintedTextLoadsBackEqual) {
  const ExampleOptions o = non_default_options();
  const std::string text = options_to_yaml(o, "x.y");
  auto doc = parse_yaml_string(text, "printed");
  ASSERT_TRUE(doc.ok()) << doc.status() << "\n" << text;
  auto back = load_options<ExampleOptions>(*doc, "x.y");
  ASSERT_TRUE(back.ok()) << back.status() << "\n" << text;
  EXPECT_TRUE(options_diff(o, *back).empty()) << ::testing::PrintToString(options_diff(o, *back)) << "\n"
                                              << text;
}

TEST(Options, SaveThenLoadGivesAnEqualStruct) {
  test::TempDir dir;
  const ExampleOptions o = non_default_options();
  const auto path = dir / "saved.yaml";
  ASSERT_TRUE(save_options(path, o, "tracker").ok());
  auto back = load_options_file<ExampleOptions>(path, "tracker");
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(*back, o);
  EXPECT_EQ(back->min_px_dist, 0.1 + 0.2);
  EXPECT_EQ(back->gravity.x(), -1e-300);
  EXPECT_EQ(back->quality, 0.3f);
  EXPECT_EQ(back->cameras, o.cameras);

  // Defaults round-trip too, and saved files carry no "(default)" markers.
  const auto defaults_path = dir / "defaults.yaml";
  ASSERT_TRUE(save_options(defaults_path, ExampleOptions{}).ok());
  auto defaults = load_options_file<ExampleOptions>(defaults_path);
  ASSERT_TRUE(defaults.ok()) << defaults.status();
  EXPECT_EQ(*defaults, ExampleOptions{});
  std::ifstream in(defaults_path);
  std::stringstream saved;
  saved << in.rdbuf();
  EXPECT_THAT(saved.str(), HasSubstr("max_features: 200"));
  EXPECT_THAT(saved.str(), HasSubstr("# features per frame"));
  EXPECT_THAT(saved.str(), ::testing::Not(HasSubstr("(default)")));
}

TEST(Options, SaveToUnwritablePathIsAnError) {
  test::TempDir dir;
  // A folder path that runs through a regular file can never be created.
  dir.write("not_a_folder", "x");
  const Status s = save_options(dir / "not_a_folder" / "x.yaml", ExampleOptions{});
  ASSERT_FALSE(s.ok());
  EXPECT_THAT(std::string(s.message()), HasSubstr("not_a_folder"));
}

TEST(Options, NonFiniteDoublesRoundTrip) {
  ImuNoiseOptions o;
  o.gyroscope_noise_density = std::numeric_limits<double>::infinity();
  const std::string text = options_to_yaml(o);
  EXPECT_THAT(text, HasSubstr("gyroscope_noise_density: .inf"));
  auto back = load_options<ImuNoiseOptions>(*parse_yaml_string(text));
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_TRUE(std::isinf(back->gyroscope_noise_density));
}

TEST(Options, EqualityAndDiffNameTheChangedKeys) {
  ExampleOptions a;
  ExampleOptions b;
  EXPECT_TRUE(options_equal(a, b));
  EXPECT_EQ(a, b);
  b.imu.rate_hz = 100.0;
  b.gravity.z() = -9.8;
  b.cameras.push_back("cam2");
  EXPECT_NE(a, b);
  EXPECT_THAT(options_diff(a, b), ElementsAre("cameras", "gravity", "imu.rate_hz"));
  b = a;
  b.update = UpdateMode::kMsckfNullspace;
  EXPECT_THAT(options_diff(a, b), ElementsAre("update"));
  b = a;
  b.calibration = "x";
  EXPECT_THAT(options_diff(a, b), ElementsAre("calibration"));
}

TEST(Options, UpdateKeepsGivenValuesForAbsentKeys) {
  ExampleOptions o;
  o.max_features = 42;
  auto doc = parse_yaml_string("min_px_dist: 3.0\n");
  ASSERT_TRUE(doc.ok());
  ASSERT_TRUE(update_options(*doc, "", o).ok());
  EXPECT_EQ(o.max_features, 42);
  EXPECT_EQ(o.min_px_dist, 3.0);
}

TEST(Options, OverridesChangeValuesWithTheSameRules) {
  auto doc = parse_yaml_string(kTuningFile, "tuning.yaml");
  ASSERT_TRUE(doc.ok());
  ASSERT_TRUE(
      apply_overrides(*doc, {"tracker.max_features=301", "tracker.resolutions=[0.5, 1.0]",
                             "tracker.imu.gyroscope_noise_density=3e-4", "tracker.calibration=rel/cc.yaml"})
          .ok());
  auto o = load_options<ExampleOptions>(*doc, "tracker");
  ASSERT_TRUE(o.ok()) << o.status();
  EXPECT_EQ(o->max_features, 301);
  EXPECT_THAT(o->resolutions, ElementsAre(0.5, 1.0));
  EXPECT_EQ(o->imu.gyroscope_noise_density, 3e-4);
  EXPECT_EQ(o->imu.rate_hz, 400.0);                                 // untouched keys still come from the file
  EXPECT_EQ(o->calibration, std::filesystem::path("rel/cc.yaml"));  // command-line paths stay as given
}

TEST(Options, LoadOptionsFileAppliesOverrides) {
  test::TempDir dir;
  const auto path = dir.write("t.yaml", kTuningFile);
  auto o = load_options_file<ExampleOptions>(path, "tracker", {"tracker.use_fej=true"});
  ASSERT_TRUE(o.ok()) << o.status();
  EXPECT_TRUE(o->use_fej);
  EXPECT_EQ(o->max_features, 300);
}

TEST(Constraints, DescribeWhatTheyAccept) {
  EXPECT_EQ(in_range(1, 5000).describe<int>(), "an integer in [1, 5000]");
  EXPECT_EQ(in_range(0.0, 100.0).describe<double>(), "a number in [0, 100]");
  EXPECT_EQ(positive().describe<double>(), "a number > 0");
  EXPECT_EQ(at_least(0).describe<std::int64_t>(), "an integer >= 0");
  EXPECT_EQ(at_most(1.5).describe<double>(), "a number <= 1.5");
  EXPECT_EQ(any().describe<bool>(), "a boolean (true/false)");
  EXPECT_EQ(one_of({"a", "b"}).describe<std::string>(), "one of 'a', 'b'");
  EXPECT_EQ(each_in_range(0.001, 10.0).size(1, 16).describe<std::vector<double>>(),
            "a list of 1 to 16 numbers, each in [0.001, 10]");
  EXPECT_EQ(list_size(0, 8).describe<std::vector<int>>(), "a list of up to 8 integers");
  EXPECT_EQ(any().describe<Eigen::Vector3d>(), "a list of 3 numbers");
  EXPECT_EQ(each_in_range(-1, 1).describe<Eigen::Vector2d>(), "a list of 2 numbers, each in [-1, 1]");
}

TEST(Constraints, AcceptAndRejectValues) {
  EXPECT_TRUE(in_range(1, 5000).accepts(1));
  EXPECT_TRUE(in_range(1, 5000).accepts(5000));
  EXPECT_FALSE(in_range(1, 5000).accepts(5001));
  EXPECT_FALSE(in_range(0.0, 1.0).accepts(std::nan("")));
  EXPECT_FALSE(positive().accepts(0.0));
  EXPECT_TRUE(positive().accepts(1e-300));
  EXPECT_TRUE(in_range(0, 1).accepts(0.5));  // int bounds, double field: compared as double
  EXPECT_FALSE(greater_than(2.5).accepts(2));
  EXPECT_FALSE(one_of({"a"}).accepts(std::string("b")));
  EXPECT_FALSE(each_in_range(0.0, 1.0).accepts(std::vector<double>{0.5, 2.0}));
  EXPECT_FALSE(list_size(1, 2).accepts(std::vector<int>{}));
  EXPECT_TRUE(list_size(1, 2).accepts(std::vector<int>{7, 8}));
}

TEST(Codecs, NumbersAndStringsReadBackUnchanged) {
  for (const double v : {0.1, 1.0 / 3.0, 1e-300, -2.5e300, 10.0, 0.0, 123456789.0}) {
    const std::string text = detail::format_double(v);
    double back = 0.0;
    ASSERT_TRUE(detail::parse_double(text, &back)) << text;
    EXPECT_EQ(back, v) << text;
    EXPECT_NE(text.find_first_of(".e"), std::string::npos) << text;  // reads as a float in YAML
  }
  EXPECT_EQ(detail::format_double(10.0), "10.0");
  EXPECT_EQ(detail::format_double(-std::numeric_limits<double>::infinity()), "-.inf");
  double nan_back = 0.0;
  ASSERT_TRUE(detail::parse_double(detail::format_double(std::nan("")), &nan_back));
  EXPECT_TRUE(std::isnan(nan_back));
  double d = 0.0;
  EXPECT_FALSE(detail::parse_double("1.5x", &d));
  EXPECT_FALSE(detail::parse_double("", &d));
  EXPECT_FALSE(detail::parse_double("1e999", &d));
  EXPECT_TRUE(detail::parse_double("+2", &d));
  EXPECT_EQ(d, 2.0);

  for (const std::string s :
       {"plain", "true", "No", "", "a b", "x: y", "q\"b\\s", "tab\there", "-dash", "12"}) {
    auto node = YAML::Load("k: " + detail::yaml_quote(s));
    EXPECT_EQ(node["k"].as<std::string>(), s) << detail::yaml_quote(s);
  }
  EXPECT_EQ(detail::yaml_quote("known_landmark"), "known_landmark");
  EXPECT_EQ(detail::yaml_quote("true"), "\"true\"");
}

TEST(Codecs, IntegersRejectOverflowAndFractions) {
  int i = 0;
  EXPECT_TRUE(detail::Codec<int>::decode(YAML::Load("+17"), i));
  EXPECT_EQ(i, 17);
  EXPECT_FALSE(detail::Codec<int>::decode(YAML::Load("1.5"), i));
  EXPECT_FALSE(detail::Codec<int>::decode(YAML::Load("99999999999"), i));
  std::int64_t big = 0;
  EXPECT_TRUE(detail::Codec<std::int64_t>::decode(YAML::Load("9223372036854775807"), big));
  EXPECT_EQ(big, std::numeric_limits<std::int64_t>::max());
  unsigned u = 0;
  EXPECT_FALSE(detail::Codec<unsigned>::decode(YAML::Load("-1"), u));
  float f = 0.0f;
  EXPECT_FALSE(detail::Codec<float>::decode(YAML::Load("1e300"), f));
}

}  // namespace
}  // namespace mrvs::config
