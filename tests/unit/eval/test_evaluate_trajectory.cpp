// End-to-end tests of the evaluate_trajectory executable on files written here.
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <gtest/gtest.h>

#include "mrvs/io/trajectory_io.h"
#include "mrvs/test/run_tool.h"
#include "mrvs/test/shared_data.h"
#include "mrvs/test/temp_dir.h"
#include "synthetic.h"

#ifndef MRVS_EVALUATE_TRAJECTORY
#error "MRVS_EVALUATE_TRAJECTORY (path of the executable) must be defined by the build"
#endif

namespace mrvs::eval {
namespace {

constexpr TimestampNs kT0 = 1'403'715'273'262'142'976;
constexpr DurationNs kMs = 1'000'000;

using test::quoted;
using test::RunResult;
using test::value_of;

RunResult run_tool(const std::string& args) { return test::run_tool(MRVS_EVALUATE_TRAJECTORY, args); }

io::Trajectory shifted(const io::Trajectory& trajectory, const Vec3d& t, DurationNs dt_ns) {
  io::Trajectory out = synthetic::transform(SE3d(Quatd::Identity(), t), trajectory);
  for (io::StampedPose& p : out) p.t_ns += dt_ns;
  return out;
}

TEST(EvalTool, HelpExitsZeroAndDocumentsEveryFlag) {
  const RunResult r = run_tool("--help");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  for (const char* flag : {"--est", "--gt", "--max-dt", "--time-offset", "--rpe-delta", "--rpe-delta-t",
                           "--align", "--log-level", "--json", "ATE_RMSE_m", "ATE_RMSE_SE3_m"}) {
    EXPECT_NE(r.output.find(flag), std::string::npos) << flag << "\n" << r.output;
  }
}

TEST(EvalTool, SyntheticShiftedCopyWithTimeOffsetAndJson) {
  const mrvs::test::TempDir dir;
  const synthetic::SmoothTrajectory traj(41);
  const io::Trajectory gt = synthetic::sample(traj, kT0, 5 * kMs, 4000);  // 200 Hz, 20 s
  io::Trajectory est;
  for (std::size_t i = 3; i < gt.size(); i += 7) est.push_back(gt[i]);
  // Shifted by 1.3 m, and stamped 25 ms late (compensated by --time-offset -0.025).
  est = shifted(est, Vec3d(0.3, -0.4, 1.2), 25 * kMs);
  ASSERT_TRUE(io::write_tum_trajectory(dir / "gt.txt", gt).ok());
  ASSERT_TRUE(io::write_tum_trajectory(dir / "est.txt", est).ok());
  const RunResult r = run_tool("--est " + quoted(dir / "est.txt") + " --gt " + quoted(dir / "gt.txt") +
                               " --time-offset -0.025 --log-level warn --json " + quoted(dir / "out.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NEAR(value_of(r.output, "ATE_RMSE_m"), 1.3, 1e-6) << r.output;
  EXPECT_LT(value_of(r.output, "ATE_RMSE_SE3_m"), 1e-6) << r.output;
  EXPECT_LT(value_of(r.output, "ATE_ROT_RMSE_SE3_deg"), 1e-4) << r.output;
  EXPECT_NEAR(value_of(r.output, "SIM3_SCALE"), 1.0, 1e-6) << r.output;
  EXPECT_LT(value_of(r.output, "RPE_TRANS_RMSE_m"), 1e-6) << r.output;
  EXPECT_LT(value_of(r.output, "RPE_ROT_RMSE_deg"), 1e-4) << r.output;
  EXPECT_EQ(value_of(r.output, "MATCHED_POSES"), static_cast<double>(est.size())) << r.output;
  std::ifstream json_file(dir / "out.json");
  std::stringstream json;
  json << json_file.rdbuf();
  EXPECT_NE(json.str().find("\"matched_poses\": " + std::to_string(est.size())), std::string::npos)
      << json.str();
  EXPECT_NE(json.str().find("\"alignment\": \"se3\""), std::string::npos) << json.str();

  // Without the time offset the estimate is compared 25 ms off: the SE(3) residual shows it.
  const RunResult off = run_tool("--est " + quoted(dir / "est.txt") + " --gt " + quoted(dir / "gt.txt") +
                                 " --align se3 --log-level off");
  ASSERT_EQ(off.exit_code, 0) << off.output;
  EXPECT_GT(value_of(off.output, "ATE_RMSE_SE3_m"), 1e-3) << off.output;
  EXPECT_TRUE(std::isnan(value_of(off.output, "ATE_RMSE_SIM3_m"))) << "sim3 not requested\n" << off.output;
}

// --at: the unaligned error of one pose (where the cloud placed the edge), here a pose turned
// 3 deg about +z and shifted 5 cm, among poses that are exact.
TEST(EvalTool, TheErrorOfOnePoseAtATime) {
  const mrvs::test::TempDir dir;
  const synthetic::SmoothTrajectory traj(7);
  const io::Trajectory gt = synthetic::sample(traj, kT0, 5 * kMs, 2000);
  io::Trajectory est;
  for (std::size_t i = 0; i < gt.size(); i += 10) est.push_back(gt[i]);
  io::StampedPose& p = est[50];
  const Quatd turn(Eigen::AngleAxisd(3.0 * M_PI / 180.0, Vec3d::UnitZ()));
  p.T_w_b = SE3d(turn * p.T_w_b.quaternion(), p.T_w_b.translation() + Vec3d(0.03, 0.04, 0.0));
  ASSERT_TRUE(io::write_tum_trajectory(dir / "gt.txt", gt).ok());
  ASSERT_TRUE(io::write_tum_trajectory(dir / "est.txt", est).ok());
  const std::string args = "--est " + quoted(dir / "est.txt") + " --gt " + quoted(dir / "gt.txt") + " --at ";
  RunResult r = run_tool(args + std::to_string(p.t_ns + 2 * kMs));  // the nearest pose within --max-dt
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(static_cast<TimestampNs>(value_of(r.output, "POSE_AT_T_NS")), p.t_ns);
  EXPECT_NEAR(value_of(r.output, "POSE_ERROR_AT_M"), 0.05, 1e-6);
  EXPECT_NEAR(value_of(r.output, "POSE_ERROR_AT_DEG"), 3.0, 1e-3);
  EXPECT_NEAR(value_of(r.output, "POSE_HEADING_ERROR_AT_DEG"), 3.0, 1e-3);
  r = run_tool(args + std::to_string(est[51].t_ns));
  EXPECT_NEAR(value_of(r.output, "POSE_ERROR_AT_M"), 0.0, 1e-6);
  r = run_tool(args + std::to_string(p.t_ns + 30 * kMs));  // between poses 50 ms apart: none within 10 ms
  EXPECT_EQ(r.exit_code, 1) << r.output;
}

TEST(EvalTool, EurocGroundTruthAgainstShiftedCopy) {
  const std::filesystem::path gt_path = mrvs::test::euroc_groundtruth_file("V1_01_easy.txt");
  ASSERT_TRUE(std::filesystem::exists(gt_path))
      << "missing " << gt_path << " (configure with -DMRVS_SHARED_DIR=...)";
  auto gt = io::read_trajectory(gt_path);
  ASSERT_TRUE(gt.ok()) << gt.status();
  const mrvs::test::TempDir dir;
  ASSERT_TRUE(io::write_tum_trajectory(dir / "est.txt", shifted(*gt, Vec3d(0.3, -0.4, 1.2), 0)).ok());
  const RunResult r = run_tool("--est " + quoted(dir / "est.txt") + " --gt " + quoted(gt_path));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NEAR(value_of(r.output, "ATE_RMSE_m"), 1.3, 1e-6) << r.output;
  EXPECT_LT(value_of(r.output, "ATE_RMSE_SE3_m"), 1e-6) << r.output;
  EXPECT_EQ(value_of(r.output, "MATCHED_POSES"), static_cast<double>(gt->size())) << r.output;
  EXPECT_EQ(value_of(r.output, "UNMATCHED_POSES"), 0.0) << r.output;
}

TEST(EvalTool, ReadsEurocGroundTruthCsv) {
  const test::TempDir dir;
  const synthetic::SmoothTrajectory traj(42);
  const io::Trajectory gt = synthetic::sample(traj, kT0, 5 * kMs, 2000);
  std::ostringstream csv;
  csv.precision(17);
  csv << "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], "
         "v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], b_w_RS_S_y [rad "
         "s^-1], "
         "b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], b_a_RS_S_z [m s^-2]\n";
  for (const io::StampedPose& p : gt) {
    const Vec3d t = p.T_w_b.translation();
    const Quatd q = p.T_w_b.quaternion();
    csv << p.t_ns << ',' << t.x() << ',' << t.y() << ',' << t.z() << ',' << q.w() << ',' << q.x() << ','
        << q.y() << ',' << q.z() << ",0,0,0,0,0,0,0,0,0\n";
  }
  const auto gt_path = dir.write("data.csv", csv.str());
  ASSERT_TRUE(io::write_tum_trajectory(dir / "est.txt", shifted(gt, Vec3d(0.3, -0.4, 1.2), 0)).ok());
  const RunResult r =
      run_tool("--est " + quoted(dir / "est.txt") + " --gt " + quoted(gt_path) + " --align se3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NEAR(value_of(r.output, "ATE_RMSE_m"), 1.3, 1e-6) << r.output;
  EXPECT_LT(value_of(r.output, "ATE_RMSE_SE3_m"), 1e-6) << r.output;
  EXPECT_EQ(value_of(r.output, "MATCHED_POSES"), static_cast<double>(gt.size())) << r.output;
}

TEST(EvalTool, DataErrorsExitOneAndNameTheFile) {
  const mrvs::test::TempDir dir;
  const auto gt_path = dir.write("gt.txt", "1.0 0 0 0 0 0 0 1\n1.1 1 0 0 0 0 0 1\n1.2 1 1 0 0 0 0 1\n");
  const auto missing = dir / "does_not_exist.txt";
  RunResult r = run_tool("--est " + quoted(missing) + " --gt " + quoted(gt_path));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find(missing.string()), std::string::npos) << r.output;

  const auto empty = dir.write("empty.txt", "# nothing here\n");
  r = run_tool("--est " + quoted(gt_path) + " --gt " + quoted(empty));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find(empty.string()), std::string::npos) << r.output;

  const auto two = dir.write("two.txt", "1.0 0 0 0 0 0 0 1\n1.1 1 0 0 0 0 0 1\n");
  r = run_tool("--est " + quoted(two) + " --gt " + quoted(gt_path) + " --align se3");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("at least 3"), std::string::npos) << r.output;
}

TEST(EvalTool, UsageErrorsExitTwo) {
  EXPECT_EQ(run_tool("--est a.txt").exit_code, 2);  // --gt missing
  EXPECT_EQ(run_tool("--est a.txt --gt b.txt --align affine").exit_code, 2);
  EXPECT_EQ(run_tool("--est a.txt --gt b.txt --max-dt -1").exit_code, 2);
  EXPECT_EQ(run_tool("--est a.txt --gt b.txt --rpe-delta 0").exit_code, 2);
  EXPECT_EQ(run_tool("--est a.txt --gt b.txt --log-level loud").exit_code, 2);
  EXPECT_EQ(run_tool("--est a.txt --gt b.txt --no-such-flag").exit_code, 2);
}

}  // namespace
}  // namespace mrvs::eval
