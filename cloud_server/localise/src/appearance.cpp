#include "appearance.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <optional>

namespace mrvs::localise {
namespace {

/// Ranks 1..n, ties sharing their mean rank.
std::vector<double> ranks(const std::vector<double>& x) {
  std::vector<std::size_t> order(x.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return x[a] < x[b]; });
  std::vector<double> r(x.size());
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    while (j + 1 < order.size() && x[order[j + 1]] == x[order[i]]) ++j;
    const double mean_rank = 0.5 * static_cast<double>(i + j) + 1.0;
    for (std::size_t k = i; k <= j; ++k) r[order[k]] = mean_rank;
    i = j + 1;
  }
  return r;
}

}  // namespace

double rank_correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const std::size_t n = std::min(a.size(), b.size());
  if (n < 3 || a.size() != b.size()) return 0.0;
  const std::vector<double> ra = ranks(a), rb = ranks(b);
  const double mean = 0.5 * static_cast<double>(n + 1);
  double sab = 0.0, saa = 0.0, sbb = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    sab += (ra[i] - mean) * (rb[i] - mean);
    saa += (ra[i] - mean) * (ra[i] - mean);
    sbb += (rb[i] - mean) * (rb[i] - mean);
  }
  if (saa <= 0.0 || sbb <= 0.0) return 0.0;
  return sab / std::sqrt(saa * sbb);
}

Appearance appearance(const MapSurface& surface, const FineResult& fine,
                      const std::vector<float>& brightness) {
  std::vector<double> seen, mapped;
  const std::size_t n = std::min(fine.matched.size(), brightness.size());
  for (std::size_t i = 0; i < n; ++i) {
    if (fine.matched[i] < 0 || !(brightness[i] > 0.0f)) continue;
    const float intensity = surface.intensity(static_cast<std::uint32_t>(fine.matched[i]));
    if (!std::isfinite(intensity)) continue;
    seen.push_back(brightness[i]);
    mapped.push_back(intensity);
  }
  Appearance a;
  a.points = static_cast<int>(seen.size());
  a.correlation = rank_correlation(seen, mapped);
  return a;
}

namespace {

/// The pose slid by s, when it keeps the fit and has enough inliers with a brightness.
struct SlideProbe {
  double s = 0.0;
  FineResult fine;
  Appearance appearance;
};

std::optional<SlideProbe> probe(const MapSurface& surface, const std::vector<Eigen::Vector3d>& points,
                                const std::vector<float>& brightness, double yaw,
                                const Eigen::Vector3d& anchor, const Eigen::Vector3d& direction, double s,
                                const FineOptions& fine, const SlideOptions& o, double start_fitness) {
  FineResult f = refine_pose(surface, points, yaw, anchor + s * direction, fine);
  if (f.fitness < o.min_fitness_ratio * start_fitness) return std::nullopt;
  const Appearance a = appearance(surface, f, brightness);
  if (a.points < o.min_points) return std::nullopt;
  return SlideProbe{s, std::move(f), a};
}

}  // namespace

Slide slide_by_appearance(const MapSurface& surface, const std::vector<Eigen::Vector3d>& points,
                          const std::vector<float>& brightness, double yaw, const Eigen::Vector3d& anchor,
                          const Eigen::Vector3d& direction, FineOptions fine, const SlideOptions& o) {
  fine.iterations = 0;
  Slide out;
  out.fine = refine_pose(surface, points, yaw, anchor, fine);
  out.start = out.appearance = appearance(surface, out.fine, brightness);
  if (out.start.points < o.min_points || !(o.step_m > 0.0) || !(o.range_m > 0.0)) return out;
  const double start_fitness = out.fine.fitness;
  const int steps = static_cast<int>(std::floor(o.range_m / o.step_m + 1e-9));
  // Coarse to fine: every coarse_stride-th step over the range, then the steps around the best.
  std::optional<SlideProbe> best;
  const auto consider = [&](int k) {
    if (k == 0 || std::abs(k) > steps) return;
    auto p = probe(surface, points, brightness, yaw, anchor, direction, k * o.step_m, fine, o, start_fitness);
    if (p && (!best || p->appearance.correlation > best->appearance.correlation)) best = std::move(p);
  };
  const int stride = std::max(1, std::min(o.coarse_stride, steps));
  for (int k = -steps; k <= steps; k += stride) consider(k);
  if ((2 * steps) % stride != 0) consider(steps);  // the range's far edge, which the stride skipped
  if (!best) return out;
  const int centre = static_cast<int>(std::lround(best->s / o.step_m));
  for (int k = centre - stride + 1; k < centre + stride; ++k)
    if (k != centre) consider(k);
  const double margin = o.margin_sd * std::sqrt(1.0 / best->appearance.points + 1.0 / out.start.points);
  if (best->appearance.correlation > out.start.correlation + margin) {
    out.offset_m = best->s;
    out.fine = std::move(best->fine);
    out.appearance = best->appearance;
  }
  out.unbracketed = out.offset_m != 0.0 && std::abs(std::abs(out.offset_m) - steps * o.step_m) < 1e-9;
  return out;
}

}  // namespace mrvs::localise
