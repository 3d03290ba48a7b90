#include "mrvs/sim/people.h"

#include <algorithm>
#include <cmath>

#include "mrvs/sim/rng.h"

namespace mrvs::sim {
namespace {

constexpr float kCell = 0.04f;  ///< value-noise cell, m

/// Value noise in [0, 1) at (x, y) in cells: bilinear between hashed lattice values.
float value_noise(std::uint64_t seed, int face, float x, float y) {
  const float fx = std::floor(x), fy = std::floor(y);
  const float tx = x - fx, ty = y - fy;
  const auto ix = static_cast<std::int64_t>(fx), iy = static_cast<std::int64_t>(fy);
  const CounterRng rng(seed, Stream::kPeople);
  auto lattice = [&](std::int64_t i, std::int64_t j) {
    return static_cast<float>(rng.uniform(static_cast<std::uint64_t>(face), static_cast<std::uint64_t>(i),
                                          static_cast<std::uint64_t>(j)));
  };
  const float top = lattice(ix, iy) * (1.0f - tx) + lattice(ix + 1, iy) * tx;
  const float bottom = lattice(ix, iy + 1) * (1.0f - tx) + lattice(ix + 1, iy + 1) * tx;
  return top * (1.0f - ty) + bottom * ty;
}

}  // namespace

Vec3d Walker::centre(TimestampNs t_ns, Eigen::Vector2d* heading) const {
  const double length = (b - a).norm();
  const Eigen::Vector2d dir = length > 0.0 ? Eigen::Vector2d((b - a) / length) : Eigen::Vector2d::UnitX();
  double s =
      length > 0.0 ? std::fmod(speed_mps * 1e-9 * static_cast<double>(t_ns - at_a_ns), 2.0 * length) : 0.0;
  if (s < 0.0) s += 2.0 * length;
  const bool back = s > length;  // ping-pong: a -> b, then b -> a
  const Eigen::Vector2d xy = back ? Eigen::Vector2d(b - (s - length) * dir) : Eigen::Vector2d(a + s * dir);
  if (heading != nullptr) *heading = back ? Eigen::Vector2d(-dir) : dir;
  return Vec3d(xy.x(), xy.y(), floor_z + 0.5 * height_m);
}

std::vector<PersonBox> people_at(const std::vector<Walker>& walkers, TimestampNs t_ns) {
  std::vector<PersonBox> boxes;
  boxes.reserve(walkers.size());
  for (std::size_t i = 0; i < walkers.size(); ++i) {
    const Walker& w = walkers[i];
    Eigen::Vector2d heading;
    PersonBox box;
    box.centre_w = w.centre(t_ns, &heading).cast<float>();
    // Rows of R_p_w: the person's x (heading), y (left) and z (up) in the world.
    box.R_p_w.row(0) =
        Eigen::Vector3f(static_cast<float>(heading.x()), static_cast<float>(heading.y()), 0.0f);
    box.R_p_w.row(1) =
        Eigen::Vector3f(static_cast<float>(-heading.y()), static_cast<float>(heading.x()), 0.0f);
    box.R_p_w.row(2) = Eigen::Vector3f::UnitZ();
    box.half = 0.5f * Eigen::Vector3f(static_cast<float>(w.depth_m), static_cast<float>(w.width_m),
                                      static_cast<float>(w.height_m));
    box.texture_seed = w.texture_seed;
    box.index = static_cast<int>(i);
    boxes.push_back(box);
  }
  return boxes;
}

std::optional<float> PersonBox::intersect(const Eigen::Vector3f& origin, const Eigen::Vector3f& d,
                                          float max_t) const {
  // Cheap reject first: the ray's xy line passes farther from the upright axis than the
  // box's horizontal half-diagonal (the box lies within that vertical cylinder).
  const float wx = centre_w.x() - origin.x(), wy = centre_w.y() - origin.y();
  const float cross = d.x() * wy - d.y() * wx, dxy2 = d.x() * d.x() + d.y() * d.y();
  if (cross * cross > (half.x() * half.x() + half.y() * half.y()) * dxy2) return std::nullopt;
  const Eigen::Vector3f o = R_p_w * (origin - centre_w);
  const Eigen::Vector3f v = R_p_w * d;
  float t_near = 0.0f, t_far = max_t;
  for (int k = 0; k < 3; ++k) {
    if (std::abs(v[k]) < 1e-12f) {
      if (std::abs(o[k]) > half[k]) return std::nullopt;
      continue;
    }
    float t0 = (-half[k] - o[k]) / v[k], t1 = (half[k] - o[k]) / v[k];
    if (t0 > t1) std::swap(t0, t1);
    t_near = std::max(t_near, t0);
    t_far = std::min(t_far, t1);
    if (t_near > t_far) return std::nullopt;
  }
  if (t_near <= 0.0f) return std::nullopt;  // inside, or behind
  return t_near;
}

float PersonBox::albedo(const Eigen::Vector3f& p_w) const {
  const Eigen::Vector3f p = R_p_w * (p_w - centre_w);
  // Which face: the axis where the point is nearest the box's surface.
  const Eigen::Vector3f gap = half - p.cwiseAbs();
  int axis = 0;
  gap.minCoeff(&axis);
  const int face = 2 * axis + (p[axis] > 0.0f ? 1 : 0);
  const float u = axis == 0 ? p.y() : p.x(), v = axis == 2 ? p.y() : p.z();
  const float height = p.z() + half.z();  // above the feet, m
  const CounterRng rng(texture_seed, Stream::kPeople);
  // Trousers, shirt and head: each its own base albedo.
  const std::uint64_t part = height < 0.85f ? 0 : (height < 2.0f * half.z() - 0.25f ? 1 : 2);
  const float base = static_cast<float>(rng.uniform(0.15, 0.8, 1000 + part));
  const float pattern = value_noise(texture_seed, face, u / kCell, v / kCell);
  return std::clamp(base * (0.55f + 0.9f * pattern), 0.03f, 0.97f);
}

}  // namespace mrvs::sim
