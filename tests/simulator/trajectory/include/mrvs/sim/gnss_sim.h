#pragma once
// GNSS-like position fixes for the outdoor profile: a receiver whose antenna sits on the car
// roof, reporting the antenna position in the map frame (mav0/gnss0, format in mrvs/io/gnss.h).
//
// Fix k is taken at t_k = t_0 + k T on the IMU grid: T = 1 / rate_hz must be a whole number
// of IMU periods, t_0 is the first IMU stamp, the last fix is the last t_k within the window.
//   p_true[k] = T_map_world * T_w_b(t_k) * lever_arm_m          (antenna, map frame)
//   p_fix[k]  = p_true[k] + e[k] + o[k]
// e: first-order Gauss-Markov error, independent per axis, sigma = sigma_horizontal_m for x
//    and y (each), sigma_vertical_m for z; phi = exp(-T / correlation_time_s) (0 when the
//    time constant is 0: white noise):
//      e[0] = sigma n[0],   e[k] = phi e[k-1] + sigma sqrt(1 - phi^2) n[k],   n ~ N(0, 1)
//    so e is stationary from the first fix: sd sigma, lag-1 autocorrelation phi.
// o: an outlier with probability outlier_probability per fix: outlier_m (cos a, sin a, 0), a
//    uniform in [0, 2 pi) (horizontal, in the map frame); else 0. Outliers are transient:
//    they do not enter the recursion of e.
// Random numbers: CounterRng(seed + seed_offset, Stream::kGnss) keyed by (k, draw): draws 0-2
// the axes of n[k], 3 the outlier decision, 4 the direction a. No other stream changes when a
// GNSS knob does, and the same seed gives the same fixes.
#include <cstdint>
#include <filesystem>
#include <vector>

#include <Eigen/Core>

#include "mrvs/config/options.h"
#include "mrvs/core/status.h"
#include "mrvs/core/time.h"
#include "mrvs/geometry/se3.h"
#include "mrvs/io/types.h"

namespace mrvs::sim {

/// GNSS knobs. Defaults: a KAIST-Urban-like single-point receiver at 1 Hz on the car roof.
/// `enabled` is off here (indoor); default_options(kOutdoor) turns it on.
struct GnssSimOptions : config::OptionsEquality<GnssSimOptions> {
  bool enabled = false;               ///< write mav0/gnss0 and sim0/gnss_truth.csv
  double rate_hz = 1.0;               ///< fixes per second; 1 / rate_hz = whole IMU periods, Hz
  double sigma_horizontal_m = 1.5;    ///< stationary sd of each horizontal axis (x, y), m
  double sigma_vertical_m = 3.0;      ///< stationary sd of z, m
  double correlation_time_s = 30.0;   ///< Gauss-Markov time constant, s (0 = white noise)
  double outlier_probability = 0.02;  ///< chance per fix of an outlier
  double outlier_m = 15.0;            ///< size of an outlier (horizontal, random direction), m
  /// Antenna in the IMU body frame (x forward, y left, z up), m: on the roof, 0.25 m above and
  /// 0.30 m behind the IMU (which sits at roof level, route.imu_height_m = 1.7 m above the road).
  Eigen::Vector3d lever_arm_m{-0.30, 0.0, 0.25};
  std::int64_t seed_offset = 0;  ///< GNSS noise uses seed + seed_offset (redraw it alone)

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("enabled", enabled, any(), "write mav0/gnss0 (outdoor default: on)");
    v("rate_hz", rate_hz, in_range(0.01, 1000.0), "fixes per second, Hz; 1 / rate_hz = whole IMU periods");
    v("sigma_horizontal_m", sigma_horizontal_m, in_range(1e-6, 1000.0), "sd of each horizontal axis, m");
    v("sigma_vertical_m", sigma_vertical_m, in_range(1e-6, 1000.0), "sd of the vertical axis, m");
    v("correlation_time_s", correlation_time_s, in_range(0.0, 1e6),
      "Gauss-Markov time constant of the error, s (0 = white)");
    v("outlier_probability", outlier_probability, in_range(0.0, 1.0), "chance per fix of an outlier");
    v("outlier_m", outlier_m, in_range(0.0, 1e4), "outlier size, m (horizontal, random direction)");
    v("lever_arm_m", lever_arm_m, any(), "antenna in the IMU body frame, m");
    v("seed_offset", seed_offset, at_least(std::int64_t{0}), "added to seed for the GNSS noise only");
  }
};

/// The error of one fix (p_fix - p_true = gauss_markov_m + outlier_m).
struct GnssErrorSample {
  Vec3d gauss_markov_m = Vec3d::Zero();  ///< e[k], m
  Vec3d outlier_m = Vec3d::Zero();       ///< o[k], m (zero unless `outlier`)
  bool outlier = false;
  Vec3d total() const { return gauss_markov_m + outlier_m; }
};

/// The errors of `count` consecutive fixes `period_s` apart (the model above): a pure
/// function of its arguments (the grid and `enabled` are not looked at).
std::vector<GnssErrorSample> simulate_gnss_errors(std::size_t count, double period_s,
                                                  const GnssSimOptions& options, std::uint64_t seed);

/// One simulated fix with its truth.
struct GnssSimFix {
  TimestampNs t_ns = 0;                  ///< IMU clock, on an IMU stamp
  Vec3d p_true_map = Vec3d::Zero();      ///< true antenna position, map frame, m
  Vec3d p_measured_map = Vec3d::Zero();  ///< what mav0/gnss0/data.csv holds, m
  bool outlier = false;
};

/// The fix period in ns: 1e9 / rate_hz, which must be a whole multiple of imu_period_ns.
/// Error naming gnss.rate_hz and the rates that fit otherwise.
StatusOr<DurationNs> gnss_period_ns(double rate_hz, DurationNs imu_period_ns);

/// Fixes over the sequence whose ground truth is `states` (one per IMU stamp, equally
/// spaced: World::states). Errors: invalid options, a rate off the IMU grid, bad stamps.
StatusOr<std::vector<GnssSimFix>> simulate_gnss(const std::vector<io::GroundTruthState>& states,
                                                const SE3d& T_map_world, const GnssSimOptions& options,
                                                std::uint64_t seed);

/// sim0/gnss_truth.csv: "#timestamp [ns],p_x [m],p_y [m],p_z [m],outlier": the true antenna
/// position in the map frame at each fix of mav0/gnss0/data.csv (same rows, same order) and
/// 1 when that fix is an outlier, else 0. Doubles in the shortest round-trip text.
Status write_gnss_truth_csv(const std::filesystem::path& path, const std::vector<GnssSimFix>& fixes);
/// Reads it back (p_measured_map stays zero). Errors name the file and line.
StatusOr<std::vector<GnssSimFix>> read_gnss_truth_csv(const std::filesystem::path& path);

}  // namespace mrvs::sim
