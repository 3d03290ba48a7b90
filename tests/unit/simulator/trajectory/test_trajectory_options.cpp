// The trajectory/IMU Options structs work with the config machinery: defaults validate,
// YAML text round-trips, and a changed knob loads from a file.
#include <gtest/gtest.h>

#include "mrvs/config/options.h"
#include "mrvs/sim/car_route.h"
#include "mrvs/sim/imu_sim.h"
#include "mrvs/sim/spline_trajectory.h"
#include "mrvs/sim/time_grid.h"

namespace mrvs::sim {
namespace {

template <class T>
void expect_round_trip(const T& options) {
  EXPECT_TRUE(config::validate_options(options).ok());
  const std::string text = config::options_to_yaml(options, "section");
  auto doc = config::parse_yaml_string(text);
  ASSERT_TRUE(doc.ok()) << doc.status();
  auto loaded = config::load_options<T>(*doc, "section");
  ASSERT_TRUE(loaded.ok()) << loaded.status() << "\n" << text;
  EXPECT_TRUE(*loaded == options) << text;
}

TEST(TrajectoryOptions, RoundTripThroughYaml) {
  ImuSimOptions imu;
  imu.sampling = ImuSampling::kAverage;
  imu.noise_scale = 2.0;
  expect_round_trip(imu);
  TrajectoryOptions traj;
  traj.window_start_ns = 1'403'715'274'302'140'000;
  expect_round_trip(traj);
  expect_round_trip(kaist_time_grid());
  expect_round_trip(long_car_route());

  auto doc = config::parse_yaml_string("imu:\n  sampling: average\n  gravity_magnitude: 9.80766\n");
  ASSERT_TRUE(doc.ok());
  auto loaded = config::load_options<ImuSimOptions>(*doc, "imu");
  ASSERT_TRUE(loaded.ok()) << loaded.status();
  EXPECT_EQ(loaded->sampling, ImuSampling::kAverage);
  EXPECT_EQ(loaded->gravity_magnitude, 9.80766);
  auto bad = config::parse_yaml_string("imu:\n  sampling: midpoint\n");
  EXPECT_FALSE(config::load_options<ImuSimOptions>(*bad, "imu").ok());
}

}  // namespace
}  // namespace mrvs::sim
