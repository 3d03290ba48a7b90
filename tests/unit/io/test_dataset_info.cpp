// The dataset_info tool end to end on a generated EuRoC folder.
#include <gtest/gtest.h>

#include "euroc_fixture.h"
#include "mrvs/io/gnss.h"
#include "mrvs/test/run_tool.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::io {
namespace {

using test::quoted;
using test::value_of;

test::RunResult run_dataset_info(const std::string& args) { return test::run_tool(MRVS_DATASET_INFO, args); }

TEST(DatasetInfoTool, SummarisesAGeneratedSequence) {
  const test::TempDir dir;
  test_fixture::EurocSpec spec;
  const auto sequence = test_fixture::write_euroc_sequence(dir, spec);
  const auto r = run_dataset_info("--dataset " + quoted(sequence) + " --log-level warn");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(value_of(r.output, "STEREO_FRAMES"), spec.frames) << r.output;
  EXPECT_EQ(value_of(r.output, "IMU_SAMPLES"), spec.frames * spec.imu_per_frame) << r.output;
  EXPECT_EQ(value_of(r.output, "GROUNDTRUTH_STATES"), spec.frames * spec.imu_per_frame) << r.output;
  EXPECT_EQ(value_of(r.output, "GNSS_FIXES"), 0) << r.output;
  EXPECT_NE(r.output.find("cam0"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("gnss: none"), std::string::npos) << r.output;
}

TEST(DatasetInfoTool, CountsGnssFixesAndShowsTheLeverArm) {
  const test::TempDir dir;
  test_fixture::EurocSpec spec;
  const auto sequence = test_fixture::write_euroc_sequence(dir, spec);
  std::vector<GnssFix> fixes;
  for (int k = 0; k < 3; ++k)
    fixes.push_back({test_fixture::imu_t_ns(spec, 20 * k), Vec3d(k, 2, 3), 1.5, 3.0});
  ASSERT_TRUE(write_euroc_gnss_csv(sequence / "mav0/gnss0/data.csv", fixes).ok());
  dir.write("MH_test/mav0/gnss0/sensor.yaml",
            "sensor_type: gnss\nT_BS:\n  cols: 4\n  rows: 4\n"
            "  data: [1, 0, 0, -0.3, 0, 1, 0, 0, 0, 0, 1, 0.25, 0, 0, 0, 1]\nrate_hz: 10.0\n");
  const auto r = run_dataset_info("--dataset " + quoted(sequence) + " --log-level warn");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(value_of(r.output, "GNSS_FIXES"), 3) << r.output;
  EXPECT_NE(r.output.find("gnss0: 3 samples"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("gnss0 antenna in the body frame: [-0.300, 0.000, 0.250] m"), std::string::npos)
      << r.output;
}

TEST(DatasetInfoTool, MissingFolderIsADataErrorNamingIt) {
  const test::TempDir dir;
  const auto missing = dir / "no_such_sequence";
  const auto r = run_dataset_info("--dataset " + quoted(missing));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find(missing.string()), std::string::npos) << r.output;
}

TEST(DatasetInfoTool, UsageErrorsExitWithTwo) {
  EXPECT_EQ(run_dataset_info("").exit_code, 2);
  EXPECT_EQ(run_dataset_info("--dataset x --format rosbag").exit_code, 2);
  EXPECT_EQ(run_dataset_info("--help").exit_code, 0);
}

}  // namespace
}  // namespace mrvs::io
