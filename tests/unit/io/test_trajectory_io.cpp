#include <algorithm>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "mrvs/io/trajectory_io.h"
#include "mrvs/test/shared_data.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::io {
namespace {

using ::testing::HasSubstr;

std::string message(const Status& s) { return std::string(s.message()); }

std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

TEST(TumTrajectory, ReadsValuesAndExactTimes) {
  test::TempDir dir;
  const auto path =
      dir.write("traj.txt",
                "# timestamp(s) tx ty tz qx qy qz qw\r\n"
                "1403715273.262142976 1.5 -2.25 0.125 0 0 0 1\r\n"
                "\r\n"
                "1403715273.267142976\t0.5  1e-3 -7 0.7071067811865476 0 0 0.7071067811865476\r\n");
  Warnings warnings;
  const auto traj = read_tum_trajectory(path, {}, &warnings);
  ASSERT_TRUE(traj.ok()) << traj.status();
  ASSERT_EQ(traj->size(), 2u);
  EXPECT_TRUE(warnings.empty());
  EXPECT_EQ((*traj)[0].t_ns, std::int64_t{1403715273262142976});
  EXPECT_EQ((*traj)[1].t_ns, std::int64_t{1403715273267142976});
  EXPECT_EQ((*traj)[0].T_w_b.translation(), Vec3d(1.5, -2.25, 0.125));
  EXPECT_EQ((*traj)[1].T_w_b.translation(), Vec3d(0.5, 1e-3, -7));
  // 90 degrees about x: y -> z.
  const Vec3d y_rotated = (*traj)[1].T_w_b.rotation_matrix() * Vec3d::UnitY();
  EXPECT_NEAR((y_rotated - Vec3d::UnitZ()).norm(), 0.0, 1e-12);
}

TEST(TumTrajectory, NormalisesNearUnitQuaternions) {
  test::TempDir dir;
  const auto path = dir.write("traj.txt", "1 0 0 0 0 0 0 1.0005\n");
  const auto traj = read_tum_trajectory(path);
  ASSERT_TRUE(traj.ok()) << traj.status();
  EXPECT_NEAR((*traj)[0].T_w_b.quaternion().norm(), 1.0, 1e-15);
  EXPECT_EQ((*traj)[0].T_w_b.quaternion().w(), 1.0);
}

TEST(TumTrajectory, RejectsNonUnitAndZeroQuaternionsNamingTheLine) {
  test::TempDir dir;
  const auto half = dir.write("half.txt", "# c\n1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 0.5\n");
  const auto r1 = read_tum_trajectory(half);
  ASSERT_FALSE(r1.ok());
  EXPECT_THAT(message(r1.status()), HasSubstr(half.string() + ":3: quaternion"));
  EXPECT_THAT(message(r1.status()), HasSubstr("norm 0.5"));
  const auto zero = dir.write("zero.txt", "1 0 0 0 0 0 0 0\n");
  const auto r2 = read_tum_trajectory(zero);
  ASSERT_FALSE(r2.ok());
  EXPECT_THAT(message(r2.status()), HasSubstr(zero.string() + ":1: quaternion"));
  EXPECT_THAT(message(r2.status()), HasSubstr("norm 0,"));
}

TEST(TumTrajectory, BadRowsNameFileAndLine) {
  test::TempDir dir;
  const auto text = dir.write("text.txt", "1 0 0 0 0 0 0 1\n2 0 x 0 0 0 0 1\n");
  const auto r1 = read_tum_trajectory(text);
  ASSERT_FALSE(r1.ok());
  EXPECT_EQ(message(r1.status()),
            text.string() + ":2: field 3 ('ty'): 'x' is not a number; fix or delete this line");
  const auto time = dir.write("time.txt", "1e9 0 0 0 0 0 0 1\n");
  const auto r2 = read_tum_trajectory(time);
  ASSERT_FALSE(r2.ok());
  EXPECT_THAT(message(r2.status()), HasSubstr(time.string() + ":1: field 1 ('t'): '1e9' is not a number"));
  const auto cut = dir.write("cut.txt", "1 0 0 0 0 0 0 1\n2 0 0 0 0");
  const auto r3 = read_tum_trajectory(cut);
  ASSERT_FALSE(r3.ok());
  EXPECT_EQ(r3.status().code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(message(r3.status()), HasSubstr(cut.string() + ":2: expected 8 blank-separated fields"));
  const auto empty = dir.write("empty.txt", "# only a header\n\n");
  const auto r4 = read_tum_trajectory(empty);
  ASSERT_FALSE(r4.ok());
  EXPECT_THAT(message(r4.status()), HasSubstr(empty.string() + ": no data rows"));
  const auto missing = read_tum_trajectory(dir / "missing.txt");
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(message(missing.status()), HasSubstr((dir / "missing.txt").string()));
}

TEST(TumTrajectory, UnterminatedLastLineIsReadWithAWarning) {
  test::TempDir dir;
  const auto path = dir.write("t.txt", "1 0 0 0 0 0 0 1\n2 0 0 0 0 0 0 1");
  Warnings warnings;
  const auto traj = read_tum_trajectory(path, {}, &warnings);
  ASSERT_TRUE(traj.ok()) << traj.status();
  EXPECT_EQ(traj->size(), 2u);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_THAT(warnings[0], HasSubstr(path.string() + ":2: the file does not end in a newline"));
}

TEST(ReadPolicy, OutOfOrderRowIsAnErrorUnlessSortingIsAsked) {
  test::TempDir dir;
  const auto path = dir.write("t.txt",
                              "# header\n"
                              "1.0 1 0 0 0 0 0 1\n"
                              "3.0 3 0 0 0 0 0 1\n"
                              "2.0 2 0 0 0 0 0 1\n");
  const auto strict = read_tum_trajectory(path);
  ASSERT_FALSE(strict.ok());
  EXPECT_EQ(
      message(strict.status()),
      path.string() +
          ":4: timestamp 2.000000000 s is not after the previous timestamp 3.000000000 s (line 3); rows "
          "must be in strictly increasing time order: sort the file by its first column (keeping the header "
          "first), or read it with ReadPolicy::sort_out_of_order = true");
  Warnings warnings;
  const auto sorted = read_tum_trajectory(path, ReadPolicy{true}, &warnings);
  ASSERT_TRUE(sorted.ok()) << sorted.status();
  ASSERT_EQ(sorted->size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ((*sorted)[i].t_ns, (i + 1) * kNanosecondsPerSecond);
    EXPECT_EQ((*sorted)[i].T_w_b.translation().x(), i + 1.0);
  }
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_THAT(warnings[0], HasSubstr(path.string() + ":4: rows are not in time order"));
  EXPECT_THAT(warnings[0], HasSubstr("sorted all 3 rows"));
}

TEST(ReadPolicy, ExactDuplicatesAreDroppedWithAWarning) {
  test::TempDir dir;
  const auto path = dir.write("t.txt",
                              "1.0 1 0 0 0 0 0 1\n"
                              "2.0 2 0 0 0 0 0 1\n"
                              "2.000000000 2.0 0 0 0 0 0 1\n"
                              "3.0 3 0 0 0 0 0 1\n");
  Warnings warnings;
  const auto traj = read_tum_trajectory(path, {}, &warnings);
  ASSERT_TRUE(traj.ok()) << traj.status();
  EXPECT_EQ(traj->size(), 3u);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_EQ(warnings[0], path.string() + ":3: duplicate of line 2, dropped");
}

TEST(ReadPolicy, ManyDuplicatesAreSummarised) {
  test::TempDir dir;
  std::string text;
  for (int i = 0; i < 15; ++i) text += "1.0 1 0 0 0 0 0 1\n";
  const auto path = dir.write("t.txt", text);
  Warnings warnings;
  const auto traj = read_tum_trajectory(path, {}, &warnings);
  ASSERT_TRUE(traj.ok()) << traj.status();
  EXPECT_EQ(traj->size(), 1u);
  ASSERT_EQ(warnings.size(), 11u);
  EXPECT_EQ(warnings[9], path.string() + ":11: duplicate of line 1, dropped");
  EXPECT_EQ(warnings[10], path.string() + ": 4 more exact duplicate rows dropped (not listed; 14 in total)");
}

TEST(ReadPolicy, ConflictingDuplicatesNameBothLines) {
  test::TempDir dir;
  const auto path = dir.write("t.txt",
                              "1.0 1 0 0 0 0 0 1\n"
                              "2.0 2 0 0 0 0 0 1\n"
                              "# comment\n"
                              "2.0 2.5 0 0 0 0 0 1\n");
  for (const bool sort : {false, true}) {
    const auto traj = read_tum_trajectory(path, ReadPolicy{sort});
    ASSERT_FALSE(traj.ok());
    EXPECT_EQ(message(traj.status()),
              path.string() +
                  ":4: timestamp 2.000000000 s also appears on line 2 with different values; a time can have "
                  "only one row: delete the wrong one of lines 2 and 4");
  }
}

TEST(ReadPolicy, SortingKeepsDuplicateDetection) {
  test::TempDir dir;
  const auto path = dir.write("t.txt",
                              "2.0 2 0 0 0 0 0 1\n"
                              "1.0 1 0 0 0 0 0 1\n"
                              "2.0 2 0 0 0 0 0 1\n");
  Warnings warnings;
  const auto traj = read_tum_trajectory(path, ReadPolicy{true}, &warnings);
  ASSERT_TRUE(traj.ok()) << traj.status();
  ASSERT_EQ(traj->size(), 2u);
  ASSERT_EQ(warnings.size(), 2u);
  EXPECT_EQ(warnings[1], path.string() + ":3: duplicate of line 1, dropped");
}

Trajectory random_trajectory(int n) {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> u(-100.0, 100.0);
  std::uniform_int_distribution<std::int64_t> step(1, 60'000'000'000);
  Trajectory traj;
  TimestampNs t = 1403715273262142976;
  for (int i = 0; i < n; ++i) {
    Quatd q(u(rng), u(rng), u(rng), u(rng));
    traj.push_back(StampedPose{t, SE3d(q, Vec3d(u(rng), u(rng) * 1e-7, u(rng) * 1e5))});
    t += step(rng);
  }
  traj.push_back(StampedPose{t + 1, SE3d()});  // 1 ns apart, identity
  return traj;
}

TEST(TumTrajectory, WriteReadRoundTripIsExact) {
  test::TempDir dir;
  const Trajectory traj = random_trajectory(200);
  const auto path = dir / "sub/folder/traj.txt";
  ASSERT_TRUE(write_tum_trajectory(path, traj).ok());
  EXPECT_FALSE(std::filesystem::exists(dir / "sub/folder/traj.txt.tmp"));
  const std::string text = read_text(path);
  EXPECT_EQ(text.rfind("# timestamp(s) tx ty tz qx qy qz qw\n1403715273.262142976 ", 0), 0u)
      << text.substr(0, 100);
  const auto back = read_tum_trajectory(path);
  ASSERT_TRUE(back.ok()) << back.status();
  ASSERT_EQ(back->size(), traj.size());
  for (std::size_t i = 0; i < traj.size(); ++i) {
    EXPECT_EQ((*back)[i].t_ns, traj[i].t_ns);
    EXPECT_EQ((*back)[i].T_w_b.translation(), traj[i].T_w_b.translation()) << i;
    EXPECT_LE(
        ((*back)[i].T_w_b.quaternion().coeffs() - traj[i].T_w_b.quaternion().coeffs()).cwiseAbs().maxCoeff(),
        1e-15)
        << i;
  }
}

TEST(TumTrajectory, WriteRejectsUnorderedOrNonFiniteInput) {
  test::TempDir dir;
  Trajectory traj = random_trajectory(3);
  std::swap(traj[1], traj[2]);
  const Status unordered = write_tum_trajectory(dir / "a.txt", traj);
  ASSERT_FALSE(unordered.ok());
  EXPECT_THAT(message(unordered), HasSubstr("entry 2"));
  EXPECT_FALSE(std::filesystem::exists(dir / "a.txt"));
  traj = random_trajectory(3);
  traj[1].T_w_b.translation().y() = std::nan("");
  const Status nan = write_tum_trajectory(dir / "b.txt", traj);
  ASSERT_FALSE(nan.ok());
  EXPECT_THAT(message(nan), HasSubstr("entry 1"));
  EXPECT_THAT(message(nan), HasSubstr("non-finite"));
}

constexpr const char* kEurocGtHeader =
    "#timestamp,p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z [],v_RS_R_x [m "
    "s^-1],"
    "v_RS_R_y [m s^-1],v_RS_R_z [m s^-1],b_w_RS_S_x [rad s^-1],b_w_RS_S_y [rad s^-1],b_w_RS_S_z [rad s^-1],"
    "b_a_RS_S_x [m s^-2],b_a_RS_S_y [m s^-2],b_a_RS_S_z [m s^-2]\r\n";

TEST(EurocGroundTruth, MapsWFirstQuaternionAndAllColumns) {
  test::TempDir dir;
  // q = (w, x, y, z) = (cos 45, 0, 0, sin 45): 90 degrees about z.
  const auto path = dir.write(
      "data.csv",
      std::string(kEurocGtHeader) +
          "1403636580838555648, 4.688319, -1.786938, 0.783338, 0.7071067811865476, 0, 0, "
          "0.7071067811865476, -0.027876, 0.033207, 0.800006, -0.002229, 0.020700, 0.076126, -0.012492, "
          "0.547666, 0.069073\r\n"
          "1403636580843555328,4.688177,-1.786770,0.787350,1,0,0,0,-0.024725,0.029006,0.805135,-0.002229,"
          "0.020700,0.076126,-0.012492,0.547666,0.069073\r\n");
  const auto gt = read_euroc_groundtruth(path);
  ASSERT_TRUE(gt.ok()) << gt.status();
  ASSERT_EQ(gt->size(), 2u);
  const GroundTruthState& s = (*gt)[0];
  EXPECT_EQ(s.t_ns, std::int64_t{1403636580838555648});
  EXPECT_EQ(s.T_w_b.translation(), Vec3d(4.688319, -1.786938, 0.783338));
  EXPECT_NEAR(s.T_w_b.quaternion().w(), std::sqrt(0.5), 1e-15);
  EXPECT_NEAR(s.T_w_b.quaternion().z(), std::sqrt(0.5), 1e-15);
  EXPECT_EQ(s.T_w_b.quaternion().x(), 0.0);
  const Vec3d x_rotated = s.T_w_b.rotation_matrix() * Vec3d::UnitX();
  EXPECT_NEAR((x_rotated - Vec3d::UnitY()).norm(), 0.0, 1e-12);
  EXPECT_EQ(s.v_w_b, Vec3d(-0.027876, 0.033207, 0.800006));
  EXPECT_EQ(s.bias_gyro, Vec3d(-0.002229, 0.020700, 0.076126));
  EXPECT_EQ(s.bias_accel, Vec3d(-0.012492, 0.547666, 0.069073));
  EXPECT_EQ((*gt)[1].t_ns, std::int64_t{1403636580843555328});
  EXPECT_EQ((*gt)[1].T_w_b.quaternion().w(), 1.0);
}

TEST(EurocGroundTruth, RejectsBadRowsNamingFileAndLine) {
  test::TempDir dir;
  const auto short_row = dir.write("a.csv", std::string(kEurocGtHeader) + "1,2,3,4,1,0,0,0\r\n");
  const auto r1 = read_euroc_groundtruth(short_row);
  ASSERT_FALSE(r1.ok());
  EXPECT_THAT(message(r1.status()), HasSubstr(short_row.string() + ":2: expected 17 comma-separated fields"));
  EXPECT_THAT(message(r1.status()), HasSubstr("found 8"));
  const auto bad_q = dir.write("b.csv", std::string(kEurocGtHeader) + "1,0,0,0,2,0,0,0,0,0,0,0,0,0,0,0,0\n");
  const auto r2 = read_euroc_groundtruth(bad_q);
  ASSERT_FALSE(r2.ok());
  EXPECT_THAT(message(r2.status()), HasSubstr(bad_q.string() + ":2: quaternion (q_RS_w x y z"));
  EXPECT_THAT(message(r2.status()), HasSubstr("norm 2"));
}

TEST(EurocGroundTruth, WriteReadRoundTrip) {
  test::TempDir dir;
  std::vector<GroundTruthState> states;
  for (const StampedPose& p : random_trajectory(20)) {
    GroundTruthState s;
    s.t_ns = p.t_ns;
    s.T_w_b = p.T_w_b;
    s.v_w_b = p.T_w_b.translation() * 0.1;
    s.bias_gyro = Vec3d(1e-3, -2e-4, 3.5e-5) * static_cast<double>(states.size());
    s.bias_accel = Vec3d(0.1, 0.2, -0.3) / 3.0;
    states.push_back(s);
  }
  const auto path = dir / "data.csv";
  ASSERT_TRUE(write_euroc_groundtruth(path, states).ok());
  const auto back = read_euroc_groundtruth(path);
  ASSERT_TRUE(back.ok()) << back.status();
  ASSERT_EQ(back->size(), states.size());
  for (std::size_t i = 0; i < states.size(); ++i) {
    EXPECT_EQ((*back)[i].t_ns, states[i].t_ns);
    EXPECT_EQ((*back)[i].T_w_b.translation(), states[i].T_w_b.translation());
    EXPECT_LE(((*back)[i].T_w_b.quaternion().coeffs() - states[i].T_w_b.quaternion().coeffs())
                  .cwiseAbs()
                  .maxCoeff(),
              1e-15);
    EXPECT_EQ((*back)[i].v_w_b, states[i].v_w_b);
    EXPECT_EQ((*back)[i].bias_gyro, states[i].bias_gyro);
    EXPECT_EQ((*back)[i].bias_accel, states[i].bias_accel);
  }
  // The same poses through the auto-detecting reader.
  const auto traj = read_trajectory(path);
  ASSERT_TRUE(traj.ok()) << traj.status();
  ASSERT_EQ(traj->size(), states.size());
  EXPECT_EQ((*traj)[5].t_ns, states[5].t_ns);
  EXPECT_EQ((*traj)[5].T_w_b.translation(), states[5].T_w_b.translation());
}

TEST(ReadTrajectory, DetectsFormatsByContent) {
  test::TempDir dir;
  const auto tum = dir.write("a.txt", "# tum\n1.5 1 2 3 0 0 0 1\n");
  const auto tum_comma = dir.write("b.csv", "#t,x\n1.5, 1, 2, 3, 0, 0, 0, 1\n");
  const auto euroc =
      dir.write("c.csv", std::string(kEurocGtHeader) + "1500000000,1,2,3,0,0,0,1,0,0,0,0,0,0,0,0,0\n");
  EXPECT_EQ(*detect_trajectory_format(tum), TrajectoryFormat::kTum);
  EXPECT_EQ(*detect_trajectory_format(tum_comma), TrajectoryFormat::kTumComma);
  EXPECT_EQ(*detect_trajectory_format(euroc), TrajectoryFormat::kEurocGroundTruth);
  for (const auto& path : {tum, tum_comma, euroc}) {
    const auto traj = read_trajectory(path);
    ASSERT_TRUE(traj.ok()) << traj.status();
    ASSERT_EQ(traj->size(), 1u);
    EXPECT_EQ((*traj)[0].t_ns, 1'500'000'000) << path;
    EXPECT_EQ((*traj)[0].T_w_b.translation(), Vec3d(1, 2, 3)) << path;
  }
  // EuRoC's w-first quaternion (0,0,0,1 as w,x,y,z) is a 180 degree turn about z.
  EXPECT_EQ((*read_trajectory(euroc))[0].T_w_b.quaternion().z(), 1.0);
  EXPECT_EQ((*read_trajectory(tum))[0].T_w_b.quaternion().w(), 1.0);

  const auto odd = dir.write("d.txt", "# x\n1 2 3 4 5\n");
  const auto r = read_trajectory(odd);
  ASSERT_FALSE(r.ok());
  EXPECT_THAT(message(r.status()), HasSubstr(odd.string() + ":2: cannot tell the trajectory format"));
  EXPECT_THAT(message(r.status()), HasSubstr("5 blank-separated fields"));
}

class RealEurocGroundTruth : public ::testing::TestWithParam<const char*> {};

TEST_P(RealEurocGroundTruth, ReadsAt200HzWithUnitQuaternions) {
  const std::filesystem::path path = test::euroc_groundtruth_file(GetParam());
  ASSERT_TRUE(std::filesystem::exists(path))
      << "missing " << path << " (configure with -DMRVS_SHARED_DIR=...)";
  Warnings warnings;
  const auto traj = read_trajectory(path, {}, &warnings);
  ASSERT_TRUE(traj.ok()) << traj.status();
  EXPECT_TRUE(warnings.empty()) << warnings.front();
  ASSERT_GT(traj->size(), 10000u);
  std::vector<DurationNs> periods;
  for (std::size_t i = 1; i < traj->size(); ++i) {
    ASSERT_GT((*traj)[i].t_ns, (*traj)[i - 1].t_ns) << i;
    periods.push_back((*traj)[i].t_ns - (*traj)[i - 1].t_ns);
  }
  std::nth_element(periods.begin(), periods.begin() + periods.size() / 2, periods.end());
  EXPECT_EQ(periods[periods.size() / 2], 5'000'000);
  for (const StampedPose& p : *traj) {
    ASSERT_NEAR(p.T_w_b.quaternion().norm(), 1.0, 1e-12);
    ASSERT_TRUE(p.T_w_b.translation().allFinite());
    ASSERT_LT(p.T_w_b.translation().norm(), 20.0);  // Vicon room
  }
}

INSTANTIATE_TEST_SUITE_P(Files, RealEurocGroundTruth,
                         ::testing::Values("V1_01_easy.txt", "V1_02_medium.txt", "V2_01_easy.txt"));

TEST(RealEurocGroundTruthValues, FirstRowOfV101) {
  const auto traj = read_tum_trajectory(test::euroc_groundtruth_file("V1_01_easy.txt"));
  ASSERT_TRUE(traj.ok()) << traj.status();
  // "1403715274.30214 0.878612 2.142470 0.947262 -0.828459 -0.058956 -0.553641 0.060514"
  EXPECT_EQ(traj->front().t_ns, std::int64_t{1403715274302140000});
  EXPECT_EQ(traj->front().T_w_b.translation(), Vec3d(0.878612, 2.142470, 0.947262));
  const Quatd q(0.060514, -0.828459, -0.058956, -0.553641);
  EXPECT_LT((traj->front().T_w_b.quaternion().coeffs() - q.normalized().coeffs()).norm(), 1e-15);
}

}  // namespace
}  // namespace mrvs::io
