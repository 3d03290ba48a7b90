#include "localise_scene.h"

#include <cmath>
#include <random>
#include <unordered_set>

#include "mrvs/core/hash.h"
#include "mrvs/voxel/voxel_key.h"

namespace mrvs::localise::test {
namespace {

/// Samples of the rectangle c + u a + v b, |u| <= 1, |v| <= 1.
void sample_face(const Eigen::Vector3d& c, const Eigen::Vector3d& a, const Eigen::Vector3d& b, double spacing,
                 std::vector<Eigen::Vector3d>* out) {
  const int nu = std::max(1, static_cast<int>(std::ceil(2 * a.norm() / spacing)));
  const int nv = std::max(1, static_cast<int>(std::ceil(2 * b.norm() / spacing)));
  for (int i = 0; i <= nu; ++i) {
    for (int j = 0; j <= nv; ++j) out->push_back(c + (2.0 * i / nu - 1.0) * a + (2.0 * j / nv - 1.0) * b);
  }
}

void sample_box(const Box& box, double spacing, bool inside, std::vector<Eigen::Vector3d>* out) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(box.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = -1; side <= 1; side += 2) {
      if (!inside && axis == 2 && side < 0) continue;  // a box's bottom is on the floor
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      n[axis] = side * box.half[axis];
      Eigen::Vector3d a = Eigen::Vector3d::Zero(), b = Eigen::Vector3d::Zero();
      a[(axis + 1) % 3] = box.half[(axis + 1) % 3];
      b[(axis + 2) % 3] = box.half[(axis + 2) % 3];
      sample_face(box.centre + R * n, R * a, R * b, spacing, out);
    }
  }
}

}  // namespace

std::vector<Eigen::Vector3d> Scene::sample(double spacing) const {
  std::vector<Eigen::Vector3d> out;
  sample_box({0.5 * (room_min + room_max), 0.5 * (room_max - room_min), 0.0}, spacing, true, &out);
  for (const Box& b : boxes) sample_box(b, spacing, false, &out);
  return out;
}

Scene cluttered_room(int boxes, std::uint64_t seed) {
  Scene s;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < boxes; ++i) {
    Box b;
    b.half = Eigen::Vector3d(0.2 + 0.4 * u(rng), 0.2 + 0.4 * u(rng), 0.2 + 0.6 * u(rng));
    b.centre = Eigen::Vector3d(1.0 + 6.0 * u(rng), 1.0 + 4.0 * u(rng), b.half.z());
    b.yaw = u(rng) < 0.3 ? (u(rng) - 0.5) : 0.0;
    s.boxes.push_back(b);
  }
  return s;
}

float blob_albedo(const Eigen::Vector3d& p) {
  constexpr double kCell = 0.15;
  const Eigen::Vector3d g = p / kCell;
  const Eigen::Vector3d f = g.array() - g.array().floor();
  const Eigen::Vector3i c = g.array().floor().cast<int>();
  auto lattice = [&](int dx, int dy, int dz) {
    const std::uint64_t key =
        mix64((static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.x() + dx)) << 42) ^
              (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.y() + dy)) << 21) ^
              static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.z() + dz)));
    return static_cast<double>(key >> 11) / static_cast<double>(1ULL << 53);
  };
  double v = 0.0;
  for (int k = 0; k < 8; ++k) {
    const int dx = k & 1, dy = (k >> 1) & 1, dz = (k >> 2) & 1;
    v += lattice(dx, dy, dz) * (dx ? f.x() : 1 - f.x()) * (dy ? f.y() : 1 - f.y()) * (dz ? f.z() : 1 - f.z());
  }
  return static_cast<float>(0.1 + 0.8 * v);
}

std::shared_ptr<map::VoxelMap> voxelise(const std::vector<Eigen::Vector3d>& points,
                                        const std::vector<double>& resolutions, const Eigen::Vector3d& origin,
                                        float (*albedo)(const Eigen::Vector3d&)) {
  auto m = std::make_shared<map::VoxelMap>();
  m->origin = origin;
  for (double r : resolutions) {
    map::MapLevel level;
    level.resolution = r;
    std::unordered_set<std::uint64_t> seen;
    for (const Eigen::Vector3d& p : points) {
      const Eigen::Vector3f local = (p - origin).cast<float>();
      const auto v = map::voxel_of(local, r);
      if (!v) continue;
      if (!seen.insert(voxel::pack(*v)).second) continue;
      level.points.push_back({local, albedo ? albedo(p) : 0.5f, 0.0f});
    }
    m->levels.push_back(std::move(level));
  }
  m->raw_point_count = points.size();
  return m;
}

localisation::Request submap_request(const std::vector<Eigen::Vector3d>& samples,
                                     const Eigen::Vector3d& viewpoint, double range, int max_points,
                                     double sigma, const SE3d& T_o_m, std::uint64_t seed) {
  std::vector<Eigen::Vector3d> near;
  for (const Eigen::Vector3d& p : samples) {
    if ((p - viewpoint).norm() <= range) near.push_back(p);
  }
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0.0, sigma);
  localisation::Request q;
  q.seq = 1;
  q.anchor_o = T_o_m * viewpoint;
  const std::size_t step =
      std::max<std::size_t>(1, near.size() / static_cast<std::size_t>(std::max(max_points, 1)));
  for (std::size_t i = 0; i < near.size(); i += step) {
    const Eigen::Vector3d noisy = near[i] + Eigen::Vector3d(n(rng), n(rng), n(rng));
    q.points.push_back((T_o_m * noisy - q.anchor_o).cast<float>());
  }
  return q;
}

void add_brightness(localisation::Request* q, const SE3d& T_o_m, float (*albedo)(const Eigen::Vector3d&),
                    std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 3.0);
  const SE3d T_m_o = T_o_m.inverse();
  q->brightness.clear();
  for (const Eigen::Vector3f& x : q->points) {
    const Eigen::Vector3d p_m = T_m_o * (x.cast<double>() + q->anchor_o);
    const double b = 20.0 + 200.0 * std::pow(albedo(p_m), 0.6) + noise(rng);
    q->brightness.push_back(static_cast<std::uint8_t>(std::clamp(std::lround(b), 1L, 255L)));
  }
}

SE3d yaw_pose(double yaw, const Eigen::Vector3d& t) {
  return SE3d(Quatd(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ())), t);
}

}  // namespace mrvs::localise::test
