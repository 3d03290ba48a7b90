#pragma once
// The coarse stage's score grid (design/localisation.md; the idea of Hess et al., ICRA 2016,
// in 3-D): a dense grid over a box of the map where each cell holds how close it is to the
// map's surface, 255 * exp(-d^2 / (2 sigma^2)) for the distance d from the cell to the nearest
// occupied cell, and a pyramid of max-pooled copies: level h holds, at cell c, the largest base
// value over the cells [c, c + 2^h) on every axis. A set of points offset by any translation
// in such a window scores at most the pyramid's sum, which is what branch and bound prunes with.
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace mrvs::localise {

class LikelihoodPyramid {
 public:
  /// The grid over `box` (map-local, m) in cells of `resolution`, from the `points` inside it
  /// (others are ignored), with `levels` >= 1 pyramid levels; sigma_cells: the likelihood's
  /// width in cells.
  static LikelihoodPyramid build(const std::vector<Eigen::Vector3f>& points, const Eigen::AlignedBox3d& box,
                                 double resolution, int levels, double sigma_cells);

  /// Level h's value at base cell c (any integer cell: outside the grid's reach is 0).
  std::uint8_t value(int level, const Eigen::Vector3i& c) const {
    const Eigen::Vector3i q = c + Eigen::Vector3i::Constant(pad_);
    if ((q.array() < 0).any() || (q.array() >= padded_.array()).any()) return 0;
    return levels_[static_cast<std::size_t>(level)][index(q)];
  }
  /// Base cell holding map-local position p.
  Eigen::Vector3i cell_of(const Eigen::Vector3d& p) const {
    return ((p - origin_) / resolution_).array().floor().cast<int>();
  }
  /// Map-local position of the min corner of base cell c.
  Eigen::Vector3d corner(const Eigen::Vector3i& c) const { return origin_ + resolution_ * c.cast<double>(); }

  /// Level h's values as one array over the padded grid: base cell c is at
  /// linear(c + Vector3i::Constant(pad())); for hot loops that check the bounds once per window.
  const std::uint8_t* data(int level) const { return levels_[static_cast<std::size_t>(level)].data(); }
  std::ptrdiff_t linear(const Eigen::Vector3i& q) const {
    return (static_cast<std::ptrdiff_t>(q.z()) * padded_.y() + q.y()) * padded_.x() + q.x();
  }
  /// linear() of base cell c clamped into the padded grid, per axis: a cell outside the grid
  /// reads 0 on every level, as value() does (below, level h's 2^h cells from the padding's
  /// first lie in the padding; above, the zero layer's window holds only itself).
  std::ptrdiff_t clamped_linear(const Eigen::Vector3i& c) const {
    const Eigen::Vector3i q =
        (c + Eigen::Vector3i::Constant(pad_)).cwiseMax(0).cwiseMin(padded_ - Eigen::Vector3i::Ones());
    return linear(q);
  }
  /// Whether every base cell of the box [lo, hi] is stored (padded cells included).
  bool covers(const Eigen::Vector3i& lo, const Eigen::Vector3i& hi) const {
    const Eigen::Vector3i a = lo + Eigen::Vector3i::Constant(pad_), b = hi + Eigen::Vector3i::Constant(pad_);
    return (a.array() >= 0).all() && (b.array() < padded_.array()).all();
  }
  int pad() const { return pad_; }

  int levels() const { return static_cast<int>(levels_.size()); }
  const Eigen::Vector3i& size() const { return size_; }
  double resolution() const { return resolution_; }
  std::size_t occupied_cells() const { return occupied_; }
  std::size_t memory_bytes() const;

 private:
  std::size_t index(const Eigen::Vector3i& q) const {
    return (static_cast<std::size_t>(q.z()) * static_cast<std::size_t>(padded_.y()) +
            static_cast<std::size_t>(q.y())) *
               static_cast<std::size_t>(padded_.x()) +
           static_cast<std::size_t>(q.x());
  }
  void build_level(int h);

  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();  ///< min corner of base cell (0, 0, 0), map-local
  double resolution_ = 1.0;
  Eigen::Vector3i size_ = Eigen::Vector3i::Zero();    ///< base cells per axis
  int pad_ = 0;                                       ///< cells below 0 kept per axis: 2^(levels-1)
  Eigen::Vector3i padded_ = Eigen::Vector3i::Zero();  ///< size_ + pad_ + a zero layer above
  std::vector<std::vector<std::uint8_t>> levels_;
  std::size_t occupied_ = 0;
};

}  // namespace mrvs::localise
