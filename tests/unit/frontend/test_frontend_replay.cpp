// frontend_replay end to end on a generated EuRoC folder: it reports tracks and the paper's
// timing columns, and a missing or wrongly sized image is a data error naming the file.
#include <algorithm>
#include <filesystem>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "mrvs/sim/generator.h"
#include "mrvs/test/run_tool.h"
#include "mrvs/test/shared_data.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::edge {
namespace {

using mrvs::test::quoted;
using mrvs::test::value_of;

class FrontendReplayTool : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new mrvs::test::TempDir();
    sim::GeneratorRequest r;
    r.trajectory = mrvs::test::euroc_groundtruth_file("V1_01_easy.txt");
    r.out = *dir_ / "seq";
    r.options = sim::default_options(sim::SceneProfile::kIndoor);
    ASSERT_TRUE(sim::apply_preset("easy", sim::SceneProfile::kIndoor, r.options).ok());
    r.options.trajectory.window_start_s = 20.0;
    r.options.trajectory.window_duration_s = 1.0;
    r.options.map.spacing_near_m = r.options.map.spacing_far_m = 0.2;
    const auto report = sim::generate_dataset(r);
    ASSERT_TRUE(report.ok()) << report.status();
    frames_ = report->frames;
  }
  static void TearDownTestSuite() { delete dir_; }

  static mrvs::test::RunResult replay(const std::filesystem::path& seq, const std::string& extra = "") {
    const std::filesystem::path config = std::filesystem::path(MRVS_CONFIG_DIR) / "euroc.yaml";
    return mrvs::test::run_tool(MRVS_FRONTEND_REPLAY, "--dataset " + quoted(seq) + " --config " +
                                                          quoted(config) + " --log-level warn " + extra);
  }
  /// A copy of the generated sequence to break.
  std::filesystem::path copy() const {
    const auto out = tmp_ / "copy";
    std::filesystem::copy(*dir_ / "seq", out, std::filesystem::copy_options::recursive);
    return out;
  }
  static std::filesystem::path first_image(const std::filesystem::path& seq, int cam) {
    std::vector<std::filesystem::path> files;
    for (const auto& e :
         std::filesystem::directory_iterator(seq / "mav0" / ("cam" + std::to_string(cam)) / "data"))
      files.push_back(e.path());
    std::sort(files.begin(), files.end());
    return files.at(3);
  }

  static mrvs::test::TempDir* dir_;
  static std::int64_t frames_;
  mrvs::test::TempDir tmp_;
};
mrvs::test::TempDir* FrontendReplayTool::dir_ = nullptr;
std::int64_t FrontendReplayTool::frames_ = 0;

TEST_F(FrontendReplayTool, ReportsTracksAndTimingColumns) {
  const auto r = replay(*dir_ / "seq");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(value_of(r.output, "FRAMES"), static_cast<double>(frames_)) << r.output;
  EXPECT_GT(value_of(r.output, "FEATURES_PER_FRAME"), 150.0);
  EXPECT_LE(value_of(r.output, "FEATURES_PER_FRAME"), 200.0);
  EXPECT_GT(value_of(r.output, "STEREO_FRACTION"), 0.5);
  EXPECT_GT(value_of(r.output, "IMAGE_MS_MEDIAN"), 0.0);
  EXPECT_GT(value_of(r.output, "TRACKING_MS_MEDIAN"), 0.0);
  EXPECT_GE(value_of(r.output, "TRACK_LENGTH_MEDIAN"), 2.0);
}

TEST_F(FrontendReplayTool, AWronglySizedImageIsADataErrorNamingTheFile) {
  const auto seq = copy();
  const auto victim = first_image(seq, 1);
  ASSERT_TRUE(cv::imwrite(victim.string(), cv::Mat(100, 120, CV_8UC1, cv::Scalar(7))));
  const auto r = replay(seq);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find(victim.string()), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("120x100"), std::string::npos) << r.output;
}

TEST_F(FrontendReplayTool, AMissingImageIsADataErrorNamingTheFile) {
  const auto seq = copy();
  const auto victim = first_image(seq, 0);
  std::filesystem::remove(victim);
  const auto r = replay(seq);
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find(victim.filename().string()), std::string::npos) << r.output;
}

TEST_F(FrontendReplayTool, ABadOptionIsAUsageErrorNamingTheKey) {
  const auto r = replay(*dir_ / "seq", "--set tracker.max_features=0");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("max_features"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace mrvs::edge
