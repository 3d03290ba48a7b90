// edge_client (plain VIO, --no-map) end to end on a generated EuRoC folder: accuracy on a
// short realistic clip, determinism, and what bad datasets give (a named error or a logged
// skip, never a crash or a silent wrong result).
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include <gtest/gtest.h>

#include "mrvs/config/calibration.h"
#include "mrvs/eval/trajectory_eval.h"
#include "mrvs/io/trajectory_io.h"
#include "mrvs/test/generated_sequence.h"
#include "mrvs/test/run_tool.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::edge {
namespace {

namespace fs = std::filesystem;
using mrvs::test::quoted;
using mrvs::test::value_of;

/// V1_01 from its still start, 16 s, realistic preset (noise, exposure, textureless faces).
fs::path clip() {
  static const fs::path path = [] {
    auto p = mrvs::test::generated_sequence(
        "vio_v101_16s_realistic",
        mrvs::test::indoor_sequence_request("V1_01_easy.txt", 0.0, 16.0, "realistic"));
    EXPECT_TRUE(p.ok()) << p.status();
    return p.ok() ? *p : fs::path();
  }();
  return path;
}

mrvs::test::RunResult edge_client(const fs::path& seq, const fs::path& out,
                                  const std::string& extra = "--no-map") {
  const fs::path config = fs::path(MRVS_CONFIG_DIR) / "euroc.yaml";
  const std::string log = extra.find("--log-level") == std::string::npos ? " --log-level warn " : " ";
  return mrvs::test::run_tool(MRVS_EDGE_CLIENT, "--dataset " + quoted(seq) + " --config " + quoted(config) +
                                                    " --output " + quoted(out) + " --progress 0" + log +
                                                    extra);
}

/// SE(3)-aligned ATE RMSE (m) of the poses of `estimate` in [from_ns, to_ns).
double ate_se3(const fs::path& estimate, const fs::path& seq, TimestampNs from_ns = 0,
               TimestampNs to_ns = std::numeric_limits<TimestampNs>::max()) {
  auto est = io::read_tum_trajectory(estimate);
  auto gt = io::read_trajectory(seq / "mav0/state_groundtruth_estimate0/data.csv");
  if (!est.ok() || !gt.ok()) return 1e9;
  est->erase(std::remove_if(est->begin(), est->end(),
                            [&](const io::StampedPose& p) { return p.t_ns < from_ns || p.t_ns >= to_ns; }),
             est->end());
  auto assoc = eval::associate(*est, *gt, eval::AssociationOptions{});
  if (!assoc.ok()) return 1e9;
  auto alignment = eval::align(*assoc, eval::AlignmentMethod::kSE3);
  auto ate =
      alignment.ok() ? eval::compute_ate(*assoc, *alignment) : StatusOr<eval::AteResult>(alignment.status());
  return ate.ok() ? ate->position_m.rmse : 1e9;
}

/// A copy of the clip whose CSV files can be broken (images linked, not copied).
fs::path breakable_copy(const mrvs::test::TempDir& dir) {
  const fs::path out = dir / "seq";
  for (const auto& e : fs::recursive_directory_iterator(clip())) {
    const fs::path rel = fs::relative(e.path(), clip());
    if (e.is_directory()) {
      if (rel.filename() == "data" && rel.parent_path().filename().string().rfind("cam", 0) == 0) {
        fs::create_directories((out / rel).parent_path());
        fs::create_directory_symlink(e.path(), out / rel);
      } else if (!fs::exists(out / rel)) {
        fs::create_directories(out / rel);
      }
    } else if (!fs::exists(out / rel) && rel.string().find("/data/") == std::string::npos) {
      fs::copy_file(e.path(), out / rel);
    }
  }
  return out;
}

std::vector<std::string> lines_of(const fs::path& p) {
  std::ifstream in(p);
  std::vector<std::string> out;
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

void write_lines(const fs::path& p, const std::vector<std::string>& lines) {
  std::ofstream out(p);
  for (const auto& l : lines) out << l << "\n";
}

/// `lines` (a header, then "stamp_ns,...") with every stamp moved by shift_ns.
std::vector<std::string> shifted(std::vector<std::string> lines, TimestampNs shift_ns) {
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const std::size_t comma = lines[i].find(',');
    lines[i] = std::to_string(std::stoll(lines[i].substr(0, comma)) + shift_ns) + lines[i].substr(comma);
  }
  return lines;
}

// Online time-offset calibration: the IMU clock 1 ms ahead of the cameras' (t_d = +1 ms), so
// the estimate grows past the IMU sample at the frame stamp; the client feeds the IMU through
// the estimate's time, not the calibration's, and no frame is lost (before, every frame after
// the estimate first passed the buffered IMU was skipped for want of IMU).
TEST(EdgeClient, OnlineTimeOffsetCalibrationFeedsTheImuThroughItsEstimate) {
  const mrvs::test::TempDir dir;
  const fs::path seq = breakable_copy(dir);
  for (const char* csv : {"mav0/imu0/data.csv", "mav0/state_groundtruth_estimate0/data.csv"}) {
    write_lines(seq / csv, shifted(lines_of(seq / csv), 1'000'000));
  }
  const auto r = edge_client(seq, dir / "traj.txt", "--no-map --set estimator.state.calib_time_offset=true");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(value_of(r.output, "FRAMES_SKIPPED"), 0.0) << r.output;
  EXPECT_EQ(value_of(r.output, "POSES"),
            value_of(r.output, "FRAMES") - value_of(r.output, "INITIALIZED_AT_FRAME"))
      << r.output;
  EXPECT_LT(ate_se3(dir / "traj.txt", seq), 0.15);
  // The estimate it ends with (CALIB_TIME_OFFSET_MS) found the shift.
  EXPECT_NEAR(value_of(r.output, "CALIB_TIME_OFFSET_MS"), 1.0, 0.3) << r.output;
}

// Without online calibration the run ends with the calibration it read.
TEST(EdgeClient, TheFinalCalibrationIsPrintedAndIsTheWrittenOneWhenNotEstimated) {
  const mrvs::test::TempDir dir;
  const auto r = edge_client(clip(), dir / "traj.txt");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(value_of(r.output, "CALIB_TIME_OFFSET_MS"), 0.0);
  const auto cam1 = config::load_euroc_camera_yaml(clip() / "mav0/cam1/sensor.yaml");
  ASSERT_TRUE(cam1.ok()) << cam1.status();
  // "CALIB_CAM1_INTRINSICS: fx fy cx cy ...": the first value is fx.
  EXPECT_NEAR(value_of(r.output, "CALIB_CAM1_INTRINSICS"), cam1->model->fx(), 1e-6);
  const std::string key = "CALIB_CAM1_T_B_C: ";
  const std::size_t at = r.output.find(key);
  ASSERT_NE(at, std::string::npos) << r.output;
  double x = 0, y = 0, z = 0;
  ASSERT_EQ(std::sscanf(r.output.c_str() + at + key.size(), "%lf %lf %lf", &x, &y, &z), 3);
  EXPECT_NEAR(x, cam1->T_b_c.translation().x(), 1e-6);
  EXPECT_NEAR(y, cam1->T_b_c.translation().y(), 1e-6);
  EXPECT_NEAR(z, cam1->T_b_c.translation().z(), 1e-6);
}

TEST(EdgeClient, PlainVioTracksARealisticClip) {
  ASSERT_FALSE(clip().empty());
  const mrvs::test::TempDir dir;
  const auto r = edge_client(clip(), dir / "traj.txt");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_GT(value_of(r.output, "POSES"), 280.0) << r.output;  // of 320 frames
  EXPECT_EQ(value_of(r.output, "FRAMES_SKIPPED"), 0.0);
  for (const char* key :
       {"A_IMAGE_MS_MEDIAN", "B_TRACKING_MS_MEDIAN", "C_UPDATE_MS_MEDIAN", "FRAME_MS_P95"}) {
    EXPECT_GT(value_of(r.output, key), 0.0) << key;
  }
  const double ate = ate_se3(dir / "traj.txt", clip());
  testing::Test::RecordProperty("ate_se3_m", std::to_string(ate));
  EXPECT_LT(ate, 0.05);
}

TEST(EdgeClient, TheSameInputGivesTheSameTrajectory) {
  ASSERT_FALSE(clip().empty());
  const mrvs::test::TempDir dir;
  ASSERT_EQ(edge_client(clip(), dir / "a.txt", "--no-map --frames 120").exit_code, 0);
  ASSERT_EQ(edge_client(clip(), dir / "b.txt", "--no-map --frames 120").exit_code, 0);
  const auto a = lines_of(dir / "a.txt"), b = lines_of(dir / "b.txt");
  ASSERT_GT(a.size(), 50u);
  EXPECT_EQ(a, b);
}

TEST(EdgeClient, AMissingImuStreamIsADataErrorNamingTheFile) {
  const mrvs::test::TempDir dir;
  const fs::path seq = breakable_copy(dir);
  fs::remove(seq / "mav0/imu0/data.csv");
  const auto r = edge_client(seq, dir / "traj.txt");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("imu0/data.csv"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "traj.txt"));
}

TEST(EdgeClient, NonMonotonicTimestampsAreADataErrorNamingTheLine) {
  const mrvs::test::TempDir dir;
  const fs::path seq = breakable_copy(dir);
  auto imu = lines_of(seq / "mav0/imu0/data.csv");
  ASSERT_GT(imu.size(), 200u);
  std::swap(imu[100], imu[101]);  // line 101 of the file goes back in time
  write_lines(seq / "mav0/imu0/data.csv", imu);
  const auto r = edge_client(seq, dir / "traj.txt");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("imu0/data.csv"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("101"), std::string::npos) << r.output;
}

TEST(EdgeClient, AnImuGapIsALoggedSkipAndTheFilterStartsAgain) {
  const mrvs::test::TempDir dir;
  const fs::path seq = breakable_copy(dir);
  auto imu = lines_of(seq / "mav0/imu0/data.csv");
  // 0.5 s of IMU missing 8 s in (200 Hz, one header line).
  imu.erase(imu.begin() + 1 + 1600, imu.begin() + 1 + 1700);
  write_lines(seq / "mav0/imu0/data.csv", imu);
  const auto r = edge_client(seq, dir / "traj.txt", "--no-map --log-level info");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("IMU gap of 0.505 s"), std::string::npos) << r.output;
  EXPECT_GE(value_of(r.output, "FRAMES_SKIPPED"), 1.0);
  EXPECT_GT(value_of(r.output, "POSES"), 200.0) << r.output;  // it goes on after the gap
  // Plain VIO: one odometry frame per filter run, the second continuing from the last pose
  // before the gap (the motion during the gap is lost); each run is accurate on its own.
  const TimestampNs gap_end = std::stoll(imu[1 + 1600].substr(0, imu[1 + 1600].find(',')));
  EXPECT_LT(ate_se3(dir / "traj.txt", seq, 0, gap_end), 0.15);
  EXPECT_LT(ate_se3(dir / "traj.txt", seq, gap_end), 0.15);
  EXPECT_LT(ate_se3(dir / "traj.txt", seq), 0.4) << "the second run starts where the first ended";
}

TEST(EdgeClient, UsageErrorsExitWithTwo) {
  const mrvs::test::TempDir dir;
  const auto no_map = edge_client(clip(), dir / "t.txt", "");
  EXPECT_EQ(no_map.exit_code, 2) << no_map.output;
  EXPECT_NE(no_map.output.find("--no-map"), std::string::npos);
  EXPECT_NE(no_map.output.find("--dds-profile"), std::string::npos)
      << no_map.output;  // the map needs the link
  const auto bad = edge_client(clip(), dir / "t.txt", "--no-map --set estimator.msckf.sigma_px=-1");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("estimator.msckf.sigma_px"), std::string::npos) << bad.output;
}

}  // namespace
}  // namespace mrvs::edge
