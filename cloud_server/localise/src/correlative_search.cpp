#include "correlative_search.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "mrvs/geometry/angles.h"

namespace mrvs::localise {
namespace {

struct Candidate {
  int yaw = 0;
  Eigen::Vector3i cell = Eigen::Vector3i::Zero();  ///< lowest anchor cell of the window
  int level = 0;                                   ///< window of 2^level cells per axis
  int score = 0;                                   ///< sum of the level's values (upper bound)
  bool exact = true;                               ///< false: a looser bound (scoring stopped early)
};

/// The points of one yaw step as cell offsets from the anchor's cell, the same as offsets in
/// the grid's arrays, and their bounding box.
struct RotatedPoints {
  double yaw = 0.0;
  std::vector<Eigen::Vector3i> offsets;
  std::vector<std::ptrdiff_t> linear;
  Eigen::Vector3i lo = Eigen::Vector3i::Zero(), hi = Eigen::Vector3i::Zero();
};

class Search {
 public:
  Search(const LikelihoodPyramid& grid, const SearchWindow& window, const SearchOptions& options,
         std::vector<RotatedPoints> rotated)
      : grid_(grid), window_(window), options_(options), rotated_(std::move(rotated)) {
    min_sum_ = static_cast<int>(std::ceil(options.min_score * 255.0 * static_cast<double>(num_points())));
  }

  void run() {
    std::vector<Candidate> roots;
    const int top = grid_.levels() - 1;
    const int step = 1 << top;
    for (int k = 0; k < static_cast<int>(rotated_.size()); ++k) {
      for (int z = window_.anchor_min.z(); z <= window_.anchor_max.z(); z += step) {
        for (int y = window_.anchor_min.y(); y <= window_.anchor_max.y(); y += step) {
          for (int x = window_.anchor_min.x(); x <= window_.anchor_max.x(); x += step) {
            roots.push_back(scored({k, Eigen::Vector3i(x, y, z), top, 0}, threshold()));
          }
        }
      }
    }
    descend(roots);
  }

  std::vector<Hypothesis> take() { return std::move(kept_); }
  long long nodes() const { return nodes_; }
  bool complete() const { return complete_; }

 private:
  std::size_t num_points() const { return rotated_.empty() ? 0 : rotated_.front().offsets.size(); }

  /// The window's bound: the sum of the level's values at its points, stopped (with a looser,
  /// still valid, bound) once it cannot beat `limit` even with 255 at every point left.
  Candidate scored(Candidate c, int limit) {
    std::array<Candidate, 8> one{c};
    score_windows(one.data(), 1, c.level, nullptr, limit);
    return one[0];
  }

  /// The window's (up to 8) children inside the search window, scored in one pass over the
  /// points and stopped much sooner than alone: a child's value at a point is at most its
  /// parent's (the parent's level max-pools over the child's cells), so what a child can still
  /// gain is what the parent's values at the points left add up to, not 255 each. An expanded
  /// parent was scored in full (a stopped one is pruned), so its score is that sum.
  std::vector<Candidate> scored_children(const Candidate& parent, int limit) {
    const int half = 1 << (parent.level - 1);
    std::array<Candidate, 8> children{};
    std::size_t k = 0;
    for (int i = 0; i < 8; ++i) {
      const Eigen::Vector3i cell = parent.cell + Eigen::Vector3i(i & 1, (i >> 1) & 1, (i >> 2) & 1) * half;
      if ((cell.array() > window_.anchor_max.array()).any()) continue;
      children[k++] = {parent.yaw, cell, parent.level - 1, 0};
    }
    score_windows(children.data(), k, parent.level - 1, parent.exact ? &parent : nullptr, limit);
    return {children.begin(), children.begin() + static_cast<std::ptrdiff_t>(k)};
  }

  /// Scores k windows of one yaw at `level` (their cells within 2^level of the first's), with
  /// `parent` (the window one level up holding them all, scored in full) bounding what is left,
  /// or 255 per point without one. Where the grid stores every point's cell the values are read
  /// at the points' linear offsets; elsewhere (most windows: a submap spans metres) at their
  /// cells clamped into the grid, which read 0 outside (LikelihoodPyramid::clamped_linear).
  void score_windows(Candidate* w, std::size_t k, int level, const Candidate* parent, int limit) {
    const RotatedPoints& rp = rotated_[static_cast<std::size_t>(w[0].yaw)];
    Eigen::Vector3i lo = w[0].cell, hi = w[0].cell;
    for (std::size_t j = 0; j < k; ++j) {
      lo = lo.cwiseMin(w[j].cell);
      hi = hi.cwiseMax(w[j].cell);
    }
    if (parent) lo = lo.cwiseMin(parent->cell);
    const Eigen::Vector3i pad = Eigen::Vector3i::Constant(grid_.pad());
    if (grid_.covers(lo + rp.lo, hi + rp.hi)) {
      std::array<const std::uint8_t*, 9> base{};
      for (std::size_t j = 0; j < k; ++j) base[j] = grid_.data(level) + grid_.linear(w[j].cell + pad);
      if (parent) base[8] = grid_.data(parent->level) + grid_.linear(parent->cell + pad);
      score_pass(w, k, parent, limit, [&](std::size_t i, std::size_t j) { return base[j][rp.linear[i]]; });
    } else {
      std::array<const std::uint8_t*, 9> values{};
      std::array<Eigen::Vector3i, 9> cell{};
      for (std::size_t j = 0; j < k; ++j) {
        values[j] = grid_.data(level);
        cell[j] = w[j].cell;
      }
      if (parent) {
        values[8] = grid_.data(parent->level);
        cell[8] = parent->cell;
      }
      score_pass(w, k, parent, limit, [&](std::size_t i, std::size_t j) {
        return values[j][grid_.clamped_linear(cell[j] + rp.offsets[i])];
      });
    }
    nodes_ += static_cast<long long>(k);
  }

  /// The pass itself: read(i, j) is window j's value at point i (j = 8: the parent's).
  template <typename Read>
  void score_pass(Candidate* w, std::size_t k, const Candidate* parent, int limit, Read read) {
    constexpr std::size_t kBlock = 16;  // points between checks whether a window can still win
    std::array<int, 8> sum{};
    std::array<std::size_t, 8> active{};
    for (std::size_t j = 0; j < k; ++j) active[j] = j;
    std::size_t live = k;
    const std::size_t n = num_points();
    int rest = parent ? parent->score : 255 * static_cast<int>(n);  // the most the points left can add
    for (std::size_t start = 0; start < n && live > 0; start += kBlock) {
      const std::size_t end = std::min(n, start + kBlock);
      for (std::size_t i = start; i < end; ++i) {
        rest -= parent ? read(i, 8) : 255;
        for (std::size_t a = 0; a < live; ++a) sum[active[a]] += read(i, active[a]);
      }
      if (end == n) break;
      for (std::size_t a = 0; a < live;) {
        const std::size_t j = active[a];
        if (sum[j] + rest > limit) {
          ++a;
          continue;
        }
        sum[j] += rest;  // cannot beat the limit: pruned either way, with this looser bound
        w[j].exact = false;
        active[a] = active[--live];
      }
    }
    for (std::size_t j = 0; j < k; ++j) w[j].score = sum[j];
  }

  /// What a window must beat to matter: the last kept hypothesis once the list is full.
  int threshold() const {
    const double n = 255.0 * static_cast<double>(num_points());
    const int relative =
        kept_.empty() ? 0 : static_cast<int>(std::floor(options_.relative_score * kept_.front().score * n));
    if (static_cast<int>(kept_.size()) < options_.max_hypotheses) return std::max(min_sum_, relative);
    return std::max({min_sum_, relative, static_cast<int>(std::floor(kept_.back().score * n))});
  }

  void descend(std::vector<Candidate>& candidates) {
    std::sort(candidates.begin(), candidates.end(),
              [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
    for (const Candidate& c : candidates) {
      if (c.score <= threshold()) break;  // sorted: no later one can do better
      if (options_.max_nodes > 0 && nodes_ >= options_.max_nodes) {
        complete_ = false;
        return;
      }
      if (c.level == 0) {
        // A leaf's score is the pose's: a bound from a stopped scoring is made exact first.
        const Candidate exact = c.exact ? c : scored({c.yaw, c.cell, 0, 0}, std::numeric_limits<int>::min());
        if (exact.score > threshold()) leaf(exact);
        continue;
      }
      std::vector<Candidate> children = scored_children(c, threshold());
      descend(children);
    }
  }

  void leaf(const Candidate& c) {
    Hypothesis h;
    h.yaw = rotated_[static_cast<std::size_t>(c.yaw)].yaw;
    h.anchor = grid_.corner(c.cell) + Eigen::Vector3d::Constant(0.5 * grid_.resolution());
    if (window_.radius_m && (h.anchor - window_.centre).norm() > *window_.radius_m) return;
    h.score = static_cast<double>(c.score) / (255.0 * static_cast<double>(num_points()));
    for (Hypothesis& k : kept_) {
      if (!same_pose(k, h, options_)) continue;
      if (h.score > k.score) k = h;
      sort_kept();
      return;
    }
    kept_.push_back(h);
    sort_kept();
    if (static_cast<int>(kept_.size()) > options_.max_hypotheses) kept_.pop_back();
    const double floor_score = options_.relative_score * kept_.front().score;
    while (kept_.size() > 1 && kept_.back().score < floor_score) kept_.pop_back();
  }

  void sort_kept() {
    std::sort(kept_.begin(), kept_.end(),
              [](const Hypothesis& a, const Hypothesis& b) { return a.score > b.score; });
  }

  const LikelihoodPyramid& grid_;
  const SearchWindow& window_;
  const SearchOptions& options_;
  std::vector<RotatedPoints> rotated_;
  std::vector<Hypothesis> kept_;
  int min_sum_ = 0;
  long long nodes_ = 0;
  bool complete_ = true;
};

}  // namespace

double yaw_difference(double a, double b) {
  const double d = std::remainder(a - b, 2.0 * kPi);
  return std::abs(d);
}

bool same_pose(const Hypothesis& a, const Hypothesis& b, const SearchOptions& options) {
  return (a.anchor - b.anchor).norm() < options.distinct_m &&
         yaw_difference(a.yaw, b.yaw) < options.distinct_rad;
}

std::vector<Hypothesis> correlative_search(const LikelihoodPyramid& grid,
                                           const std::vector<Eigen::Vector3d>& points,
                                           const SearchWindow& window, const SearchOptions& options,
                                           SearchStats* stats) {
  if (points.empty() || (window.anchor_min.array() > window.anchor_max.array()).any()) return {};
  const int yaws = std::max(1, static_cast<int>(std::ceil(2.0 * kPi / window.yaw_step_rad)));
  std::vector<RotatedPoints> rotated(static_cast<std::size_t>(yaws));
  // The anchor sits at the centre of its cell: a point's cell is floor(p / r + 0.5) cells away.
  const double inv = 1.0 / grid.resolution();
  for (int k = 0; k < yaws; ++k) {
    RotatedPoints& rp = rotated[static_cast<std::size_t>(k)];
    rp.yaw = 2.0 * kPi * k / yaws;
    const Eigen::Matrix3d R = Eigen::AngleAxisd(rp.yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    rp.offsets.reserve(points.size());
    for (const Eigen::Vector3d& p : points) {
      rp.offsets.push_back(((R * p) * inv + Eigen::Vector3d::Constant(0.5)).array().floor().cast<int>());
      rp.linear.push_back(grid.linear(rp.offsets.back()));
    }
    rp.lo = rp.hi = rp.offsets.front();
    for (const Eigen::Vector3i& o : rp.offsets) {
      rp.lo = rp.lo.cwiseMin(o);
      rp.hi = rp.hi.cwiseMax(o);
    }
  }
  Search search(grid, window, options, std::move(rotated));
  search.run();
  if (stats) {
    stats->nodes = search.nodes();
    stats->yaws = yaws;
    stats->complete = search.complete();
  }
  return search.take();
}

}  // namespace mrvs::localise
