#pragma once
// IMU synthesis from a SplineTrajectory (simulator.md sections 2.3 and 2.4).
//
//   a_m(t_k) = R_w_b(t_k)^T (a_w(t_k) - g_w) + b_a(t_k) + n_a[k],   g_w = (0, 0, -g)
//   w_m(t_k) = omega_b(t_k) + b_g(t_k) + n_g[k]
//   n[k] ~ N(0, (sigma / sqrt(dt))^2)                 white noise
//   b[k+1] = b[k] + sigma_b * sqrt(dt) * N(0, 1)       bias random walk
// dt is the IMU period. The white noise comes from CounterRng(seed, Stream::kImuNoise) and
// the bias walk from CounterRng(seed, Stream::kBiasWalk), both keyed by (sample index k,
// axis, sensor 0 = gyro / 1 = accel): changing one knob never changes another stream.
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "mrvs/config/options.h"
#include "mrvs/core/status.h"
#include "mrvs/core/time.h"
#include "mrvs/io/types.h"
#include "mrvs/sim/spline_trajectory.h"

namespace mrvs::sim {

/// How a sample is taken from the continuous signal.
enum class ImuSampling {
  kInstant,  ///< the value at t_k (OpenVINS)
  kAverage,  ///< the mean over [t_k - dt, t_k], 3-point Gauss-Legendre quadrature
};

/// IMU model knobs. Defaults: EuRoC ADIS16448 datasheet densities, initial biases of the
/// real V1_01_easy ground truth (first row), g = 9.81, instantaneous sampling.
struct ImuSimOptions : config::OptionsEquality<ImuSimOptions> {
  double gyroscope_noise_density = 1.6968e-4;   ///< rad/s/sqrt(Hz)
  double gyroscope_random_walk = 1.9393e-5;     ///< rad/s^2/sqrt(Hz)
  double accelerometer_noise_density = 2.0e-3;  ///< m/s^2/sqrt(Hz)
  double accelerometer_random_walk = 3.0e-3;    ///< m/s^3/sqrt(Hz)
  double noise_scale = 1.0;                     ///< scales all four; 0 = no noise and no bias walk
  double bias_rw_scale = 1.0;                   ///< extra scale on the two random walks
  Eigen::Vector3d initial_gyro_bias{-0.00225, 0.02154, 0.07703};   ///< rad/s
  Eigen::Vector3d initial_accel_bias{-0.01801, 0.06598, 0.03098};  ///< m/s^2
  double gravity_magnitude = 9.81;                                 ///< m/s^2, g_w = (0, 0, -g)
  ImuSampling sampling = ImuSampling::kInstant;                    ///< instant | average

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("gyroscope_noise_density", gyroscope_noise_density, at_least(0.0), "rad/s/sqrt(Hz)");
    v("gyroscope_random_walk", gyroscope_random_walk, at_least(0.0), "rad/s^2/sqrt(Hz)");
    v("accelerometer_noise_density", accelerometer_noise_density, at_least(0.0), "m/s^2/sqrt(Hz)");
    v("accelerometer_random_walk", accelerometer_random_walk, at_least(0.0), "m/s^3/sqrt(Hz)");
    v("noise_scale", noise_scale, in_range(0.0, 1000.0), "scale on all densities, 0 = noiseless");
    v("bias_rw_scale", bias_rw_scale, in_range(0.0, 1000.0), "extra scale on the bias random walks");
    v("initial_gyro_bias", initial_gyro_bias, any(), "rad/s");
    v("initial_accel_bias", initial_accel_bias, any(), "m/s^2");
    v("gravity_magnitude", gravity_magnitude, in_range(0.0, 100.0), "m/s^2, g_w = (0, 0, -g)");
    v("sampling", sampling,
      enum_names<ImuSampling>({{"instant", ImuSampling::kInstant}, {"average", ImuSampling::kAverage}}),
      "instant | average over the sample interval");
  }
};

/// The densities actually simulated (noise_scale and bias_rw_scale applied): what
/// imu0/sensor.yaml must say.
struct ImuNoiseDensities {
  double gyroscope_noise_density = 0.0;      ///< rad/s/sqrt(Hz)
  double gyroscope_random_walk = 0.0;        ///< rad/s^2/sqrt(Hz)
  double accelerometer_noise_density = 0.0;  ///< m/s^2/sqrt(Hz)
  double accelerometer_random_walk = 0.0;    ///< m/s^3/sqrt(Hz)
};
ImuNoiseDensities effective_noise_densities(const ImuSimOptions& options);

/// One simulated IMU sample with its truth.
struct ImuSimSample {
  io::ImuSample measured;            ///< what imu0/data.csv holds
  io::ImuSample noiseless;           ///< true omega_b (rad/s) and specific force (m/s^2)
  Vec3d bias_gyro = Vec3d::Zero();   ///< true gyro bias at t_k, rad/s
  Vec3d bias_accel = Vec3d::Zero();  ///< true accel bias at t_k, m/s^2
};

/// Noiseless specific force R_w_b^T (a_w - g_w) and angular rate omega_b of one spline state.
io::ImuSample ideal_imu(const Kinematics& k, TimestampNs t_ns, double gravity_magnitude);

/// Simulates the IMU at `imu_stamps` (at least 2, equally spaced, e.g. TimeGrid::imu_ns).
/// Errors: invalid options, bad stamps, a stamp (or an averaging node before it) outside
/// the spline's evaluable range.
StatusOr<std::vector<ImuSimSample>> simulate_imu(const SplineTrajectory& spline,
                                                 const std::vector<TimestampNs>& imu_stamps,
                                                 const ImuSimOptions& options, std::uint64_t seed);

}  // namespace mrvs::sim
