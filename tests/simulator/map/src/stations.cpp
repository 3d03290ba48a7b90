// Survey stations along the trajectory, and the per-tile spacing and intensity models.
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "mrvs/sim/prior_map.h"

namespace mrvs::sim {
namespace {

/// Cumulative path length at every trajectory sample (metres).
std::vector<double> cumulative_length(const std::vector<Vec3d>& trajectory_w) {
  std::vector<double> s(trajectory_w.size(), 0.0);
  for (std::size_t i = 1; i < trajectory_w.size(); ++i) {
    s[i] = s[i - 1] + (trajectory_w[i] - trajectory_w[i - 1]).norm();
  }
  return s;
}

/// Trajectory position at path length `target` (linear between samples).
Vec3d position_at_length(const std::vector<Vec3d>& trajectory_w, const std::vector<double>& s,
                         double target) {
  const auto it = std::lower_bound(s.begin(), s.end(), target);
  if (it == s.begin()) return trajectory_w.front();
  if (it == s.end()) return trajectory_w.back();
  const auto i = static_cast<std::size_t>(it - s.begin());
  const double len = s[i] - s[i - 1];
  const double a = len > 0.0 ? (target - s[i - 1]) / len : 0.0;
  return trajectory_w[i - 1] + a * (trajectory_w[i] - trajectory_w[i - 1]);
}

/// True when `p` is on the back side of (or on) every face of the list: inside a convex
/// object whose normals point outwards.
bool behind_all(const std::vector<const Face*>& faces, const Vec3d& p) {
  for (const Face* f : faces) {
    if ((p - f->origin).dot(f->normal) > 0.0) return false;
  }
  return !faces.empty();
}

/// True when `p` is on the front side of every room face (room normals point inwards).
bool inside_room(const std::vector<const Face*>& room_faces, const Vec3d& p) {
  for (const Face* f : room_faces) {
    if ((p - f->origin).dot(f->normal) <= 0.0) return false;
  }
  return true;
}

/// False when the station is inside a box (or, indoors, outside the room).
bool station_usable(const Scene& scene, const Vec3d& p) {
  std::map<int, std::vector<const Face*>> objects;
  std::vector<const Face*> room;
  for (const Face& f : scene.faces()) {
    if (f.object_id >= 0) {
      objects[f.object_id].push_back(&f);
    } else {
      room.push_back(&f);
    }
  }
  for (const auto& object : objects) {
    if (behind_all(object.second, p)) return false;
  }
  return scene.profile() != SceneProfile::kIndoor || inside_room(room, p);
}

}  // namespace

StatusOr<std::vector<SurveyStation>> survey_stations(const Scene& scene,
                                                     const std::vector<Vec3d>& trajectory_w,
                                                     const MapOptions& options) {
  if (trajectory_w.empty()) return absl::InvalidArgumentError("survey_stations: empty trajectory");
  const std::vector<double> s = cumulative_length(trajectory_w);
  const double length = s.back();
  int n = options.num_stations;
  if (options.station_spacing_m > 0.0) {
    n = std::max(1, static_cast<int>(std::lround(length / options.station_spacing_m)));
  }
  if (n < 1 || n > 100000) {
    return absl::InvalidArgumentError(fmt::format("survey_stations: {} stations (expected 1 to 100000)", n));
  }
  std::vector<SurveyStation> stations(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    const double target = (k + 0.5) / n * length;
    SurveyStation& station = stations[static_cast<std::size_t>(k)];
    station.position_w = position_at_length(trajectory_w, s, target);
    station.position_w.z() = options.station_height_m;
    station.used = station_usable(scene, station.position_w);
  }
  return stations;
}

std::vector<Vec3d> thin_path(const std::vector<Vec3d>& path, double step) {
  std::vector<Vec3d> out;
  for (const Vec3d& p : path) {
    if (out.empty() || (p - out.back()).norm() >= step) out.push_back(p);
  }
  if (!path.empty() && (path.back() - out.back()).norm() > 0.0) out.push_back(path.back());
  return out;
}

double distance_to_path(const std::vector<Vec3d>& path, const Vec3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const Vec3d& q : path) best = std::min(best, (q - p).squaredNorm());
  return std::sqrt(best);
}

double tile_spacing(const MapOptions& options, double distance_m, double height_m) {
  const double s_near = options.spacing_near_m;
  const double s_far = std::max(options.spacing_far_m, s_near);
  if (options.far_above_z_m > 0.0 && height_m > options.far_above_z_m) return s_far;
  if (options.near_distance_m <= 0.0) return s_near;
  return std::clamp(s_near * distance_m / options.near_distance_m, s_near, s_far);
}

double model_intensity(const MapOptions& options, double albedo, double cos_incidence) {
  switch (options.intensity_model) {
    case IntensityModel::kAlbedo:
      return albedo;
    case IntensityModel::kAlbedoCos:
      return albedo * std::sqrt(std::clamp(cos_incidence, 0.0, 1.0));
    case IntensityModel::kAffineGamma:
      return options.intensity_gain * std::pow(std::max(albedo, 0.0), options.intensity_gamma) +
             options.intensity_offset;
  }
  return albedo;
}

}  // namespace mrvs::sim
