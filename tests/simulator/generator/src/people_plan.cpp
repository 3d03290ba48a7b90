#include "mrvs/sim/people_plan.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <optional>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "mrvs/core/file.h"
#include "mrvs/io/csv.h"
#include "mrvs/sim/rng.h"

namespace mrvs::sim {
namespace {

constexpr int kAttempts = 50;
constexpr DurationNs kCheckStepNs = 50'000'000;
constexpr const char* kCsvHeader = "#timestamp [ns],cam0_pixels,cam1_pixels";

/// The segment a-b clipped to the box [lo, hi] (xy); nullopt when nothing is left.
std::optional<std::pair<Eigen::Vector2d, Eigen::Vector2d>> clip(const Eigen::Vector2d& a,
                                                                const Eigen::Vector2d& b,
                                                                const Eigen::Vector2d& lo,
                                                                const Eigen::Vector2d& hi) {
  double t0 = 0.0, t1 = 1.0;
  const Eigen::Vector2d d = b - a;
  for (int k = 0; k < 2; ++k) {
    if (std::abs(d[k]) < 1e-12) {
      if (a[k] < lo[k] || a[k] > hi[k]) return std::nullopt;
      continue;
    }
    double s0 = (lo[k] - a[k]) / d[k], s1 = (hi[k] - a[k]) / d[k];
    if (s0 > s1) std::swap(s0, s1);
    t0 = std::max(t0, s0);
    t1 = std::min(t1, s1);
  }
  if (t0 >= t1) return std::nullopt;
  return std::make_pair(Eigen::Vector2d(a + t0 * d), Eigen::Vector2d(a + t1 * d));
}

/// True when the walker stays clear of the body and both cameras over the window.
bool keeps_clear(const Walker& w, const World& world, double clearance_m) {
  const double radius = clearance_m + 0.5 * std::hypot(w.width_m, w.depth_m);
  const TimestampNs begin = world.grid.camera_true_ns.front(), end = world.grid.camera_true_ns.back();
  for (TimestampNs t = begin; t <= end; t += kCheckStepNs) {
    const StatusOr<Kinematics> kin = world.spline->evaluate(t);
    if (!kin.ok()) continue;
    const Eigen::Vector2d person = w.centre(t).head<2>();
    if ((kin->T_w_b.translation().head<2>() - person).norm() < radius) return false;
    for (const auto& cam : world.calibration.cameras) {
      if (((kin->T_w_b * cam.T_b_c).translation().head<2>() - person).norm() < radius) return false;
    }
  }
  return true;
}

/// Attempt `attempt` of walker `i` (nullopt when the draw is unusable).
std::optional<Walker> draw_walker(const PeopleOptions& o, const World& world, const CounterRng& rng, int i,
                                  int attempt) {
  const auto uniform = [&](int component) {
    return rng.uniform(static_cast<std::uint64_t>(i), static_cast<std::uint64_t>(attempt),
                       static_cast<std::uint64_t>(component));
  };
  const TimestampNs begin = world.grid.camera_true_ns.front(), end = world.grid.camera_true_ns.back();
  const TimestampNs t = begin + static_cast<TimestampNs>(uniform(0) * static_cast<double>(end - begin));
  const StatusOr<Kinematics> kin = world.spline->evaluate(t);
  if (!kin.ok()) return std::nullopt;
  const SE3d T_w_c = kin->T_w_b * world.calibration.cameras[0].T_b_c;
  const Vec3d axis = T_w_c.rotation_matrix().col(2);
  if (axis.head<2>().norm() < 0.3) return std::nullopt;  // looking (nearly) straight down or up
  const Eigen::Vector2d forward = axis.head<2>().normalized();
  const Eigen::Vector2d across(-forward.y(), forward.x());
  const Eigen::Vector2d middle =
      T_w_c.translation().head<2>() + o.view_distance_m * forward + (uniform(1) - 0.5) * across;
  const Eigen::Vector2d dir = uniform(2) < 0.5 ? across : Eigen::Vector2d(-across);
  const Eigen::AlignedBox3d bounds = world.scene->bounds();
  const Eigen::Vector2d lo = bounds.min().head<2>().array() + 0.5, hi = bounds.max().head<2>().array() - 0.5;
  const auto path = clip(middle - 0.5 * o.path_length_m * dir, middle + 0.5 * o.path_length_m * dir, lo, hi);
  if (!path || (path->second - path->first).norm() < 1.0) return std::nullopt;
  Walker w;
  w.a = path->first;
  w.b = path->second;
  w.floor_z = bounds.min().z();
  w.speed_mps = o.speed_mps;
  w.width_m = o.width_m;
  w.depth_m = o.depth_m;
  w.height_m = o.height_m;
  w.texture_seed = rng.bits(static_cast<std::uint64_t>(i), static_cast<std::uint64_t>(attempt), 99);
  // At `middle` (projected on the clipped path) at time t, walking a -> b.
  const double s = std::clamp((middle - w.a).dot(dir), 0.0, (w.b - w.a).norm());
  w.at_a_ns = t - static_cast<DurationNs>(std::llround(s / w.speed_mps * 1e9));
  if (!world.scene->bounds().contains(Vec3d(middle.x(), middle.y(), w.floor_z + 0.5 * w.height_m))) {
    return std::nullopt;
  }
  return keeps_clear(w, world, o.clearance_m) ? std::optional<Walker>(w) : std::nullopt;
}

}  // namespace

StatusOr<std::vector<Walker>> plan_people(const PeopleOptions& o, const World& world, std::uint64_t seed) {
  std::vector<Walker> walkers;
  if (o.count == 0) return walkers;
  if (!world.spline || !world.scene || world.grid.camera_true_ns.empty()) {
    return absl::FailedPreconditionError("plan_people: the world has no trajectory, scene or frames yet");
  }
  const CounterRng rng(seed, Stream::kPeople);
  for (int i = 0; i < o.count; ++i) {
    std::optional<Walker> w;
    for (int attempt = 0; attempt < kAttempts && !w; ++attempt) w = draw_walker(o, world, rng, i, attempt);
    if (w) {
      walkers.push_back(*w);
    } else {
      spdlog::warn("people: walker {} found no path clear of the camera in {} draws; left out", i, kAttempts);
    }
  }
  return walkers;
}

Status write_people_yaml(const std::filesystem::path& path, const std::vector<Walker>& walkers) {
  fmt::memory_buffer out;
  fmt::format_to(std::back_inserter(out),
                 "# Walking people (in the images, not in the map): each walks back and forth between a\n"
                 "# and b (world xy, m) at speed_mps, at a at time at_a_ns walking to b; an upright box.\n"
                 "people:\n");
  for (const Walker& w : walkers) {
    fmt::format_to(std::back_inserter(out),
                   "  - {{a: [{}, {}], b: [{}, {}], floor_z: {}, speed_mps: {}, at_a_ns: {}, width_m: {}, "
                   "depth_m: {}, height_m: {}}}\n",
                   w.a.x(), w.a.y(), w.b.x(), w.b.y(), w.floor_z, w.speed_mps, w.at_a_ns, w.width_m,
                   w.depth_m, w.height_m);
  }
  return write_file_atomically(path, fmt::to_string(out));
}

Status write_people_csv(const std::filesystem::path& path, const std::vector<PeoplePixels>& rows) {
  fmt::memory_buffer out;
  fmt::format_to(std::back_inserter(out), "{}\n", kCsvHeader);
  for (const PeoplePixels& r : rows) {
    fmt::format_to(std::back_inserter(out), "{},{},{}\n", r.t_ns, r.pixels[0], r.pixels[1]);
  }
  return write_file_atomically(path, fmt::to_string(out));
}

StatusOr<std::vector<PeoplePixels>> read_people_csv(const std::filesystem::path& path) {
  MRVS_ASSIGN_OR_RETURN(io::TableReader reader, io::TableReader::open(path, io::Separator::kComma));
  std::vector<PeoplePixels> rows;
  io::TextRow row;
  while (reader.next(row)) {
    MRVS_RETURN_IF_ERROR(reader.check_field_count(row, 3, kCsvHeader));
    PeoplePixels r;
    MRVS_ASSIGN_OR_RETURN(r.t_ns, reader.parse_ns(row, 0, "#timestamp [ns]"));
    MRVS_ASSIGN_OR_RETURN(r.pixels[0], reader.parse_ns(row, 1, "cam0_pixels"));
    MRVS_ASSIGN_OR_RETURN(r.pixels[1], reader.parse_ns(row, 2, "cam1_pixels"));
    rows.push_back(r);
  }
  MRVS_RETURN_IF_ERROR(reader.status());
  return rows;
}

}  // namespace mrvs::sim
