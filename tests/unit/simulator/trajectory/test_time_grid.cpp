// make_time_grid: exact integer stamps, camera decimation, time offset, errors.
#include <gtest/gtest.h>

#include "mrvs/sim/time_grid.h"

namespace mrvs::sim {
namespace {

constexpr TimestampNs kT0 = 1'403'715'274'402'141'000;

TEST(TimeGrid, EurocRates) {
  auto grid = make_time_grid(kT0, kT0 + 2'000'000'000, euroc_time_grid());
  ASSERT_TRUE(grid.ok()) << grid.status();
  EXPECT_EQ(grid->imu_period_ns, 5'000'000);
  EXPECT_EQ(grid->imu_per_camera, 10);
  ASSERT_EQ(grid->imu_ns.size(), 401u);  // floor(duration * rate) + 1
  for (std::size_t k = 0; k < grid->imu_ns.size(); ++k) {
    ASSERT_EQ(grid->imu_ns[k], kT0 + static_cast<std::int64_t>(k) * 5'000'000);
  }
  ASSERT_EQ(grid->camera_true_ns.size(), 40u);  // IMU indices 1, 11, ..., 391
  for (std::size_t j = 0; j < grid->camera_true_ns.size(); ++j) {
    EXPECT_EQ(grid->camera_imu_index[j], 1 + 10 * j);
    EXPECT_EQ(grid->camera_true_ns[j], grid->imu_ns[grid->camera_imu_index[j]]);
    EXPECT_EQ(grid->camera_stamp_ns[j], grid->camera_true_ns[j]);  // t_d = 0: stamps are IMU stamps
    if (j > 0) {
      EXPECT_EQ(grid->camera_stamp_ns[j] - grid->camera_stamp_ns[j - 1], 50'000'000);
    }
  }
}

TEST(TimeGrid, KaistRatesAndTimeOffset) {
  TimeGridOptions options = kaist_time_grid();
  options.camera_time_offset_ns = 7'000'000;  // t_imu = t_cam + t_d
  options.first_camera_imu_index = 10;
  auto grid = make_time_grid(kT0, kT0 + 3'004'999'999, options);
  ASSERT_TRUE(grid.ok()) << grid.status();
  EXPECT_EQ(grid->imu_period_ns, 10'000'000);
  ASSERT_EQ(grid->imu_ns.size(), 301u);
  EXPECT_EQ(grid->imu_ns.back(), kT0 + 3'000'000'000);
  ASSERT_EQ(grid->camera_true_ns.size(), 30u);
  EXPECT_EQ(grid->camera_true_ns[0], kT0 + 100'000'000);
  for (std::size_t j = 0; j < grid->camera_true_ns.size(); ++j) {
    EXPECT_EQ(grid->camera_stamp_ns[j] + options.camera_time_offset_ns, grid->camera_true_ns[j]);
    if (j > 0) {
      EXPECT_EQ(grid->camera_true_ns[j] - grid->camera_true_ns[j - 1], 100'000'000);
    }
  }
}

TEST(TimeGrid, Errors) {
  TimeGridOptions options;
  options.imu_rate_hz = 300;  // 3333333.33 ns
  EXPECT_FALSE(make_time_grid(kT0, kT0 + 1'000'000'000, options).ok());
  options = {};
  options.camera_rate_hz = 30;  // does not divide 200
  EXPECT_FALSE(make_time_grid(kT0, kT0 + 1'000'000'000, options).ok());
  EXPECT_FALSE(make_time_grid(kT0, kT0 - 1, TimeGridOptions{}).ok());
  options = {};
  options.imu_rate_hz = 0;
  EXPECT_FALSE(make_time_grid(kT0, kT0 + 1, options).ok());
  auto single = make_time_grid(kT0, kT0, TimeGridOptions{});
  ASSERT_TRUE(single.ok());
  EXPECT_EQ(single->imu_ns.size(), 1u);
  EXPECT_TRUE(single->camera_true_ns.empty());
}

}  // namespace
}  // namespace mrvs::sim
