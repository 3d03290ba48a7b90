#include "likelihood_grid.h"

#include <algorithm>
#include <cmath>

namespace mrvs::localise {

LikelihoodPyramid LikelihoodPyramid::build(const std::vector<Eigen::Vector3f>& points,
                                           const Eigen::AlignedBox3d& box, double resolution, int levels,
                                           double sigma_cells) {
  LikelihoodPyramid g;
  g.origin_ = box.min();
  g.resolution_ = resolution;
  g.size_ = (box.sizes() / resolution).array().ceil().cast<int>().cwiseMax(1);
  // Below the grid, 2^(levels-1) cells of zeros: a window starting there is stored, and a cell
  // clamped into the grid reads 0 on every level, as does one clamped into the zero layer
  // above it (clamped_linear).
  g.pad_ = 1 << (std::max(levels, 1) - 1);
  g.padded_ = g.size_ + Eigen::Vector3i::Constant(g.pad_ + 1);
  const std::size_t n = static_cast<std::size_t>(g.padded_.prod());
  g.levels_.assign(static_cast<std::size_t>(std::max(levels, 1)), {});
  std::vector<std::uint8_t>& base = g.levels_[0];
  base.assign(n, 0);
  // The likelihood stencil: value by squared cell offset, out to 2 sigma.
  const int r = std::max(1, static_cast<int>(std::ceil(2.0 * sigma_cells)));
  std::vector<std::uint8_t> by_d2(static_cast<std::size_t>(3 * r * r + 1), 0);
  for (std::size_t d2 = 0; d2 < by_d2.size(); ++d2) {
    const double v = 255.0 * std::exp(-0.5 * static_cast<double>(d2) / (sigma_cells * sigma_cells));
    by_d2[d2] = d2 <= static_cast<std::size_t>(r * r) ? static_cast<std::uint8_t>(std::lround(v)) : 0;
  }
  std::vector<std::uint8_t> occupied(n, 0);
  for (const Eigen::Vector3f& p : points) {
    const Eigen::Vector3i c = g.cell_of(p.cast<double>());
    if ((c.array() < 0).any() || (c.array() >= g.size_.array()).any()) continue;
    std::uint8_t& o = occupied[g.index(c + Eigen::Vector3i::Constant(g.pad_))];
    if (o != 0) continue;
    o = 1;
    ++g.occupied_;
    for (int dz = -r; dz <= r; ++dz) {
      for (int dy = -r; dy <= r; ++dy) {
        for (int dx = -r; dx <= r; ++dx) {
          const Eigen::Vector3i q = c + Eigen::Vector3i(dx, dy, dz);
          if ((q.array() < 0).any() || (q.array() >= g.size_.array()).any()) continue;
          const std::uint8_t v = by_d2[static_cast<std::size_t>(dx * dx + dy * dy + dz * dz)];
          std::uint8_t& b = base[g.index(q + Eigen::Vector3i::Constant(g.pad_))];
          b = std::max(b, v);
        }
      }
    }
  }
  for (int h = 1; h < levels; ++h) g.build_level(h);
  return g;
}

void LikelihoodPyramid::build_level(int h) {
  // Level h at padded cell q = max of level h-1 at q and q + s (s = 2^(h-1)) on each axis, done
  // one axis at a time: [q, q + 2^h) = [q, q + s) u [q + s, q + 2s).
  const int s = 1 << (h - 1);
  std::vector<std::uint8_t> cur = levels_[static_cast<std::size_t>(h - 1)];
  std::vector<std::uint8_t> next(cur.size(), 0);
  for (int axis = 0; axis < 3; ++axis) {
    for (int z = 0; z < padded_.z(); ++z) {
      for (int y = 0; y < padded_.y(); ++y) {
        for (int x = 0; x < padded_.x(); ++x) {
          const Eigen::Vector3i q(x, y, z);
          Eigen::Vector3i q2 = q;
          q2[axis] += s;
          const std::uint8_t a = cur[index(q)];
          next[index(q)] = q2[axis] < padded_[axis] ? std::max(a, cur[index(q2)]) : a;
        }
      }
    }
    cur.swap(next);
  }
  levels_[static_cast<std::size_t>(h)] = std::move(cur);
}

std::size_t LikelihoodPyramid::memory_bytes() const {
  std::size_t b = 0;
  for (const auto& l : levels_) b += l.size();
  return b;
}

}  // namespace mrvs::localise
