// GNSS in a generated outdoor sequence: mav0/gnss0 is there and the project's reader takes
// it, fixes come at the configured rate on IMU stamps, the truth file holds the antenna
// (body pose * lever arm, map frame), fixes minus truth are exactly the error model's
// stream, and the same seed gives the same bytes. The statistics of the error model are
// tested on long streams in test_gnss_sim.cpp (sim_trajectory), not here.
#include <cmath>
#include <fstream>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "generated_sequence.h"
#include "mrvs/io/dataset.h"
#include "mrvs/io/gnss.h"
#include "mrvs/sim/gnss_sim.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::sim {
namespace {

/// p_map = T_map_world * p_world, read from sim0/T_map_world.yaml.
SE3d read_T_map_world(const std::filesystem::path& yaml) {
  const YAML::Node data = YAML::LoadFile(yaml.string())["T_map_world"]["data"];
  Mat4d m;
  for (int i = 0; i < 16; ++i) m(i / 4, i % 4) = data[static_cast<std::size_t>(i)].as<double>();
  return SE3d::from_matrix(m);
}

class GeneratedOutdoorGnss : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new mrvs::test::TempDir();
    // Under CTest the fixture step generated it with dataset_simulator; it is only read here.
    const std::filesystem::path shared = test::shared_outdoor_gnss_sequence();
    request_ =
        new GeneratorRequest(test::outdoor_gnss_request(shared.empty() ? dir_->path() / "street" : shared));
    if (shared.empty()) {
      auto report = generate_dataset(*request_);
      ASSERT_TRUE(report.ok()) << report.status();
    }
    io::DatasetOptions options;
    options.path = request_->out;
    auto dataset = io::open_dataset("euroc", options);
    ASSERT_TRUE(dataset.ok()) << dataset.status();
    dataset_ = dataset->release();
  }
  static void TearDownTestSuite() {
    delete dataset_;
    delete request_;
    delete dir_;
  }
  static mrvs::test::TempDir* dir_;
  static GeneratorRequest* request_;
  static io::DatasetReader* dataset_;
};
mrvs::test::TempDir* GeneratedOutdoorGnss::dir_ = nullptr;
GeneratorRequest* GeneratedOutdoorGnss::request_ = nullptr;
io::DatasetReader* GeneratedOutdoorGnss::dataset_ = nullptr;

TEST_F(GeneratedOutdoorGnss, HasTheGnssFolderAtTheConfiguredRate) {
  ASSERT_NE(dataset_, nullptr);
  const std::filesystem::path seq = request_->out;
  for (const char* f : {"mav0/gnss0/data.csv", "mav0/gnss0/sensor.yaml", "sim0/gnss_truth.csv"}) {
    EXPECT_TRUE(std::filesystem::exists(seq / f)) << f;
  }
  EXPECT_TRUE(dataset_->warnings().empty()) << dataset_->warnings().front();
  const auto& gnss = dataset_->gnss();
  const auto& imu = dataset_->imu();
  ASSERT_EQ(imu.size(), 101u);  // 1 s at 100 Hz
  ASSERT_EQ(gnss.size(), 21u);  // 1 s at 20 Hz, the first fix on the first IMU sample
  EXPECT_EQ(gnss.front().t_ns, imu.front().t_ns);
  for (std::size_t k = 0; k < gnss.size(); ++k) {
    ASSERT_EQ(gnss[k].t_ns, imu[5 * k].t_ns) << k;  // on the IMU stamps, 50 ms apart
    ASSERT_EQ(gnss[k].sigma_horizontal_m, 1.5);
    ASSERT_EQ(gnss[k].sigma_vertical_m, 3.0);
  }
  ASSERT_TRUE(dataset_->summary().gnss.has_value());
  EXPECT_NEAR(dataset_->summary().gnss->rate_hz, 20.0, 1e-9);
  // sensor.yaml: the lever arm, rate and sigmas as configured.
  ASSERT_TRUE(dataset_->T_b_gnss().has_value());
  EXPECT_EQ(dataset_->T_b_gnss()->translation(), Vec3d(-0.30, 0.0, 0.25));
  auto sensor = io::read_gnss_sensor_yaml(seq / "mav0/gnss0/sensor.yaml");
  ASSERT_TRUE(sensor.ok()) << sensor.status();
  EXPECT_EQ(sensor->rate_hz, 20.0);
  EXPECT_EQ(sensor->sigma_horizontal_m, 1.5);
  EXPECT_EQ(sensor->sigma_vertical_m, 3.0);
  EXPECT_EQ(sensor->correlation_time_s, 30.0);
  EXPECT_TRUE(sensor->T_b_antenna.quaternion().isApprox(Quatd::Identity()));
}

TEST_F(GeneratedOutdoorGnss, AntennaTruthIsTheBodyPoseTimesTheLeverArmInTheMapFrame) {
  auto truth = read_gnss_truth_csv(request_->out / "sim0/gnss_truth.csv");
  ASSERT_TRUE(truth.ok()) << truth.status();
  const SE3d T_map_world = read_T_map_world(request_->out / "sim0/T_map_world.yaml");
  ASSERT_GT(T_map_world.translation().norm(), 0.1);  // the map frame is not the world frame here
  const auto& gt = dataset_->groundtruth();
  const Vec3d lever = *dataset_->T_b_gnss() * Vec3d::Zero();
  ASSERT_EQ(truth->size(), dataset_->gnss().size());
  for (std::size_t k = 0; k < truth->size(); ++k) {
    const GnssSimFix& f = (*truth)[k];
    ASSERT_EQ(f.t_ns, dataset_->gnss()[k].t_ns);
    ASSERT_EQ(gt[5 * k].t_ns, f.t_ns);
    const Vec3d expected = T_map_world * (gt[5 * k].T_w_b * lever);
    ASSERT_LT((f.p_true_map - expected).norm(), 1e-9) << k;
  }
  // The antenna is 0.25 m above the IMU, which rides 1.7 m above the road (z = 0 in the world).
  const Vec3d antenna_w = gt.front().T_w_b * lever;
  EXPECT_NEAR(antenna_w.z(), 1.7 + 0.25, 0.05);
}

TEST_F(GeneratedOutdoorGnss, FixesMinusTruthAreTheErrorModelsStream) {
  auto truth = read_gnss_truth_csv(request_->out / "sim0/gnss_truth.csv");
  ASSERT_TRUE(truth.ok()) << truth.status();
  const auto& fixes = dataset_->gnss();
  const auto errors = simulate_gnss_errors(fixes.size(), 0.05, request_->options.gnss,
                                           static_cast<std::uint64_t>(request_->options.seed));
  int outliers = 0;
  for (std::size_t k = 0; k < fixes.size(); ++k) {
    const Vec3d e = fixes[k].p_map - (*truth)[k].p_true_map;
    ASSERT_LT((e - errors[k].total()).norm(), 1e-9) << k;
    ASSERT_EQ((*truth)[k].outlier, errors[k].outlier) << k;
    outliers += errors[k].outlier;
    // Non-outliers are within 6 sigma; outliers are about 15 m off horizontally.
    const double horizontal = (e - errors[k].gauss_markov_m).head<2>().norm();
    ASSERT_NEAR(horizontal, errors[k].outlier ? 15.0 : 0.0, 1e-9) << k;
    if (!errors[k].outlier) {
      ASSERT_LT(e.head<2>().norm(), 6.0 * 1.5 * std::sqrt(2.0)) << k;
    }
  }
  EXPECT_GT(outliers, 0);
  EXPECT_LT(outliers, static_cast<int>(fixes.size()));
}

TEST_F(GeneratedOutdoorGnss, SameSeedGivesIdenticalBytes) {
  GeneratorRequest again = test::outdoor_gnss_request(dir_->path() / "again");
  auto report = generate_dataset(again);
  ASSERT_TRUE(report.ok()) << report.status();
  EXPECT_EQ(report->gnss_fixes, 21);
  const auto a = test::read_tree(request_->out);
  const auto b = test::read_tree(again.out);
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [name, bytes] : a) {
    ASSERT_TRUE(b.count(name)) << name;
    EXPECT_TRUE(bytes == b.at(name)) << name << " differs";
  }
}

TEST(GeneratorGnss, SeedOffsetRedrawsTheGnssErrorsOnly) {
  GeneratorRequest r = test::outdoor_gnss_request("unused");
  auto a = build_world(r);
  r.options.gnss.seed_offset = 1;
  auto b = build_world(r);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->gnss.size(), b->gnss.size());
  for (std::size_t k = 0; k < a->gnss.size(); ++k) {
    EXPECT_EQ(a->gnss[k].p_true_map, b->gnss[k].p_true_map);
    EXPECT_NE(a->gnss[k].p_measured_map, b->gnss[k].p_measured_map);
  }
  for (std::size_t k = 0; k < a->imu.size(); ++k)
    ASSERT_EQ(a->imu[k].measured.accel_mps2, b->imu[k].measured.accel_mps2);
  EXPECT_EQ(a->map.points.size(), b->map.points.size());
}

TEST(GeneratorGnss, ProfilesAndPresetsSetTheGnssKnobs) {
  EXPECT_FALSE(default_options(SceneProfile::kIndoor).gnss.enabled);
  SimulatorOptions outdoor = default_options(SceneProfile::kOutdoor);
  EXPECT_TRUE(outdoor.gnss.enabled);
  EXPECT_EQ(outdoor.gnss.rate_hz, 1.0);
  EXPECT_EQ(outdoor.gnss.sigma_horizontal_m, 1.5);
  EXPECT_EQ(outdoor.gnss.sigma_vertical_m, 3.0);
  EXPECT_EQ(outdoor.gnss.correlation_time_s, 30.0);
  EXPECT_EQ(outdoor.gnss.outlier_m, 15.0);
  SimulatorOptions easy = outdoor;
  SimulatorOptions realistic = outdoor;
  ASSERT_TRUE(apply_preset("easy", SceneProfile::kOutdoor, easy).ok());
  ASSERT_TRUE(apply_preset("realistic", SceneProfile::kOutdoor, realistic).ok());
  EXPECT_TRUE(easy.gnss.enabled);
  EXPECT_EQ(easy.gnss.outlier_probability, 0.0);
  EXPECT_TRUE(realistic.gnss.enabled);
  EXPECT_EQ(realistic.gnss.outlier_probability, 0.02);
}

TEST(GeneratorGnss, ARateOffTheImuGridFailsCleanlyNamingTheKey) {
  mrvs::test::TempDir dir;
  GeneratorRequest r = test::outdoor_gnss_request(dir / "street");
  r.options.gnss.rate_hz = 3.0;  // 33.3 ms: not a whole number of 10 ms IMU periods
  auto report = generate_dataset(r);
  ASSERT_FALSE(report.ok());
  EXPECT_NE(std::string(report.status().message()).find("gnss.rate_hz"), std::string::npos)
      << report.status();
  EXPECT_FALSE(std::filesystem::exists(r.out));
}

}  // namespace
}  // namespace mrvs::sim
