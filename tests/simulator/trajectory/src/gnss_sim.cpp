#include "mrvs/sim/gnss_sim.h"

#include <cmath>
#include <iterator>

#include <fmt/format.h>

#include "mrvs/core/file.h"
#include "mrvs/geometry/angles.h"
#include "mrvs/io/csv.h"
#include "mrvs/sim/rng.h"

namespace mrvs::sim {
namespace {

constexpr const char* kTruthHeader = "#timestamp [ns],p_x [m],p_y [m],p_z [m],outlier";
constexpr std::uint64_t kOutlierDraw = 3;
constexpr std::uint64_t kDirectionDraw = 4;

/// The IMU period of `states` (at least 1 state, equally spaced); 0 for a single state.
StatusOr<DurationNs> state_period(const std::vector<io::GroundTruthState>& states) {
  if (states.empty()) return absl::InvalidArgumentError("simulate_gnss: no ground-truth states");
  if (states.size() < 2) return DurationNs{0};
  const DurationNs period = states[1].t_ns - states[0].t_ns;
  for (std::size_t k = 1; k < states.size(); ++k) {
    if (period <= 0 || states[k].t_ns - states[k - 1].t_ns != period) {
      return absl::InvalidArgumentError(fmt::format(
          "simulate_gnss: the states must be equally spaced in time ({} ns), but state {} is {} ns after "
          "state {}",
          period, k, states[k].t_ns - states[k - 1].t_ns, k - 1));
    }
  }
  return period;
}

}  // namespace

std::vector<GnssErrorSample> simulate_gnss_errors(std::size_t count, double period_s,
                                                  const GnssSimOptions& options, std::uint64_t seed) {
  const CounterRng rng(seed + static_cast<std::uint64_t>(options.seed_offset), Stream::kGnss);
  const Vec3d sigma(options.sigma_horizontal_m, options.sigma_horizontal_m, options.sigma_vertical_m);
  const double phi =
      options.correlation_time_s > 0.0 ? std::exp(-period_s / options.correlation_time_s) : 0.0;
  const double drive = std::sqrt(1.0 - phi * phi);
  std::vector<GnssErrorSample> out(count);
  Vec3d e = Vec3d::Zero();
  for (std::size_t k = 0; k < count; ++k) {
    const std::uint64_t kk = k;
    for (int axis = 0; axis < 3; ++axis) {
      const double n = rng.normal(kk, static_cast<std::uint64_t>(axis));
      e[axis] = k == 0 ? sigma[axis] * n : phi * e[axis] + sigma[axis] * drive * n;
    }
    GnssErrorSample& s = out[k];
    s.gauss_markov_m = e;
    s.outlier = rng.uniform(kk, kOutlierDraw) < options.outlier_probability;
    if (s.outlier) {
      const double a = rng.uniform(0.0, 2.0 * kPi, kk, kDirectionDraw);
      s.outlier_m = Vec3d(options.outlier_m * std::cos(a), options.outlier_m * std::sin(a), 0.0);
    }
  }
  return out;
}

StatusOr<DurationNs> gnss_period_ns(double rate_hz, DurationNs imu_period_ns) {
  if (!(rate_hz > 0.0) || imu_period_ns <= 0) {
    return absl::InvalidArgumentError(fmt::format(
        "gnss.rate_hz = {} Hz with an IMU period of {} ns: both must be > 0", rate_hz, imu_period_ns));
  }
  const double exact = 1e9 / rate_hz;
  const DurationNs period = std::llround(exact);
  if (period < imu_period_ns || period % imu_period_ns != 0 ||
      std::abs(exact - static_cast<double>(period)) > 1e-3) {
    return absl::InvalidArgumentError(
        fmt::format("gnss.rate_hz = {} Hz: a fix every {:.6g} ns is not a whole number of IMU periods ({} "
                    "ns); use a rate "
                    "of {:.6g} Hz divided by a whole number (e.g. 1, 2, 5 or 10 Hz with a 100 Hz IMU)",
                    rate_hz, exact, imu_period_ns, 1e9 / static_cast<double>(imu_period_ns)));
  }
  return period;
}

StatusOr<std::vector<GnssSimFix>> simulate_gnss(const std::vector<io::GroundTruthState>& states,
                                                const SE3d& T_map_world, const GnssSimOptions& options,
                                                std::uint64_t seed) {
  MRVS_RETURN_IF_ERROR(config::validate_options(options, "gnss"));
  MRVS_ASSIGN_OR_RETURN(const DurationNs imu_period, state_period(states));
  // A single state: any period works (one fix at the first stamp).
  MRVS_ASSIGN_OR_RETURN(const DurationNs period,
                        gnss_period_ns(options.rate_hz, imu_period > 0 ? imu_period : DurationNs{1}));
  const std::size_t stride = imu_period > 0 ? static_cast<std::size_t>(period / imu_period) : 1;
  const std::size_t count = (states.size() - 1) / stride + 1;
  const std::vector<GnssErrorSample> errors = simulate_gnss_errors(count, to_seconds(period), options, seed);
  std::vector<GnssSimFix> fixes(count);
  for (std::size_t k = 0; k < count; ++k) {
    const io::GroundTruthState& s = states[k * stride];
    GnssSimFix& f = fixes[k];
    f.t_ns = s.t_ns;
    f.p_true_map = T_map_world * (s.T_w_b * Vec3d(options.lever_arm_m));
    f.p_measured_map = f.p_true_map + errors[k].total();
    f.outlier = errors[k].outlier;
  }
  return fixes;
}

Status write_gnss_truth_csv(const std::filesystem::path& path, const std::vector<GnssSimFix>& fixes) {
  fmt::memory_buffer out;
  fmt::format_to(std::back_inserter(out), "{}\n", kTruthHeader);
  for (const GnssSimFix& f : fixes) {
    fmt::format_to(std::back_inserter(out), "{},{},{},{},{}\n", f.t_ns, f.p_true_map.x(), f.p_true_map.y(),
                   f.p_true_map.z(), f.outlier ? 1 : 0);
  }
  return write_file_atomically(path, fmt::to_string(out));
}

StatusOr<std::vector<GnssSimFix>> read_gnss_truth_csv(const std::filesystem::path& path) {
  MRVS_ASSIGN_OR_RETURN(io::TableReader reader, io::TableReader::open(path, io::Separator::kComma));
  std::vector<GnssSimFix> fixes;
  io::TextRow row;
  while (reader.next(row)) {
    MRVS_RETURN_IF_ERROR(reader.check_field_count(row, 5, kTruthHeader));
    GnssSimFix f;
    MRVS_ASSIGN_OR_RETURN(f.t_ns, reader.parse_ns(row, 0, "#timestamp [ns]"));
    MRVS_ASSIGN_OR_RETURN(f.p_true_map.x(), reader.parse_double(row, 1, "p_x [m]"));
    MRVS_ASSIGN_OR_RETURN(f.p_true_map.y(), reader.parse_double(row, 2, "p_y [m]"));
    MRVS_ASSIGN_OR_RETURN(f.p_true_map.z(), reader.parse_double(row, 3, "p_z [m]"));
    if (row.fields[4] != "0" && row.fields[4] != "1") {
      return reader.row_error(row, fmt::format("field 5 ('outlier'): '{}' is not 0 or 1", row.fields[4]));
    }
    f.outlier = row.fields[4] == "1";
    fixes.push_back(f);
  }
  MRVS_RETURN_IF_ERROR(reader.status());
  return fixes;
}

}  // namespace mrvs::sim
