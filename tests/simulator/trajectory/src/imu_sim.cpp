#include "mrvs/sim/imu_sim.h"

#include <cmath>

#include <fmt/format.h>

#include "mrvs/sim/rng.h"

namespace mrvs::sim {
namespace {

constexpr std::uint64_t kGyro = 0;
constexpr std::uint64_t kAccel = 1;

/// At least 2 stamps, all equally spaced. Returns the period.
StatusOr<DurationNs> check_stamps(const std::vector<TimestampNs>& stamps) {
  if (stamps.size() < 2) {
    return absl::InvalidArgumentError(
        fmt::format("simulate_imu: needs at least 2 IMU stamps, got {}", stamps.size()));
  }
  const DurationNs period = stamps[1] - stamps[0];
  if (period <= 0) {
    return absl::InvalidArgumentError("simulate_imu: IMU stamps must strictly increase");
  }
  for (std::size_t k = 1; k < stamps.size(); ++k) {
    if (stamps[k] - stamps[k - 1] != period) {
      return absl::InvalidArgumentError(fmt::format(
          "simulate_imu: IMU stamps must be equally spaced ({} ns), but stamp {} is {} ns after stamp {}",
          period, k, stamps[k] - stamps[k - 1], k - 1));
    }
  }
  return period;
}

/// The noiseless sample at t_ns: instantaneous, or the Gauss-Legendre mean over
/// [t_ns - period, t_ns].
StatusOr<io::ImuSample> noiseless_sample(const SplineTrajectory& spline, TimestampNs t_ns,
                                         DurationNs period_ns, const ImuSimOptions& options) {
  if (options.sampling == ImuSampling::kInstant) {
    MRVS_ASSIGN_OR_RETURN(const Kinematics k, spline.evaluate(t_ns));
    return ideal_imu(k, t_ns, options.gravity_magnitude);
  }
  // Nodes mid +- sqrt(3/5) * half, weights 5/18, 8/18, 5/18 (normalised to a mean).
  const DurationNs half = period_ns / 2;
  const TimestampNs mid = t_ns - half;
  const DurationNs offset = std::llround(std::sqrt(0.6) * static_cast<double>(period_ns) * 0.5);
  const TimestampNs nodes[3] = {mid - offset, mid, mid + offset};
  const double weights[3] = {5.0 / 18.0, 8.0 / 18.0, 5.0 / 18.0};
  io::ImuSample mean;
  mean.t_ns = t_ns;
  for (int j = 0; j < 3; ++j) {
    MRVS_ASSIGN_OR_RETURN(const Kinematics k, spline.evaluate(nodes[j]));
    const io::ImuSample s = ideal_imu(k, nodes[j], options.gravity_magnitude);
    mean.gyro_radps += weights[j] * s.gyro_radps;
    mean.accel_mps2 += weights[j] * s.accel_mps2;
  }
  return mean;
}

}  // namespace

ImuNoiseDensities effective_noise_densities(const ImuSimOptions& options) {
  ImuNoiseDensities d;
  const double rw = options.noise_scale * options.bias_rw_scale;
  d.gyroscope_noise_density = options.gyroscope_noise_density * options.noise_scale;
  d.accelerometer_noise_density = options.accelerometer_noise_density * options.noise_scale;
  d.gyroscope_random_walk = options.gyroscope_random_walk * rw;
  d.accelerometer_random_walk = options.accelerometer_random_walk * rw;
  return d;
}

io::ImuSample ideal_imu(const Kinematics& k, TimestampNs t_ns, double gravity_magnitude) {
  io::ImuSample s;
  s.t_ns = t_ns;
  s.gyro_radps = k.omega_b;
  const Vec3d g_w(0.0, 0.0, -gravity_magnitude);
  s.accel_mps2 = k.T_w_b.quaternion().conjugate() * (k.a_w - g_w);
  return s;
}

StatusOr<std::vector<ImuSimSample>> simulate_imu(const SplineTrajectory& spline,
                                                 const std::vector<TimestampNs>& imu_stamps,
                                                 const ImuSimOptions& options, std::uint64_t seed) {
  MRVS_RETURN_IF_ERROR(config::validate_options(options, "imu"));
  MRVS_ASSIGN_OR_RETURN(const DurationNs period, check_stamps(imu_stamps));
  const double dt = to_seconds(period);
  const ImuNoiseDensities d = effective_noise_densities(options);
  const double sigma_g = d.gyroscope_noise_density / std::sqrt(dt);
  const double sigma_a = d.accelerometer_noise_density / std::sqrt(dt);
  const double sigma_bg = d.gyroscope_random_walk * std::sqrt(dt);
  const double sigma_ba = d.accelerometer_random_walk * std::sqrt(dt);
  const CounterRng noise(seed, Stream::kImuNoise);
  const CounterRng walk(seed, Stream::kBiasWalk);

  std::vector<ImuSimSample> out(imu_stamps.size());
  Vec3d b_g = options.initial_gyro_bias;
  Vec3d b_a = options.initial_accel_bias;
  for (std::size_t k = 0; k < imu_stamps.size(); ++k) {
    ImuSimSample& s = out[k];
    MRVS_ASSIGN_OR_RETURN(s.noiseless, noiseless_sample(spline, imu_stamps[k], period, options));
    s.bias_gyro = b_g;
    s.bias_accel = b_a;
    s.measured.t_ns = imu_stamps[k];
    s.measured.gyro_radps = s.noiseless.gyro_radps + b_g;
    s.measured.accel_mps2 = s.noiseless.accel_mps2 + b_a;
    for (int axis = 0; axis < 3; ++axis) {
      const std::uint64_t kk = k;
      const std::uint64_t ax = static_cast<std::uint64_t>(axis);
      if (sigma_g > 0.0) s.measured.gyro_radps[axis] += sigma_g * noise.normal(kk, ax, kGyro);
      if (sigma_a > 0.0) s.measured.accel_mps2[axis] += sigma_a * noise.normal(kk, ax, kAccel);
      // Increment from k to k + 1.
      if (sigma_bg > 0.0) b_g[axis] += sigma_bg * walk.normal(kk, ax, kGyro);
      if (sigma_ba > 0.0) b_a[axis] += sigma_ba * walk.normal(kk, ax, kAccel);
    }
  }
  return out;
}

}  // namespace mrvs::sim
