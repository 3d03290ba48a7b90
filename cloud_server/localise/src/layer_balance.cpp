#include "layer_balance.h"

#include <algorithm>
#include <cmath>
#include <map>

namespace mrvs::localise {
namespace {

int bin_of(const Eigen::Vector3d& p) { return static_cast<int>(std::floor(p.z() / kLayerBinM)); }

/// First bin of the kLayerBins-bin window with the most points.
int dominant_window(const std::vector<Eigen::Vector3d>& points) {
  std::map<int, std::size_t> hist;
  for (const Eigen::Vector3d& p : points) ++hist[bin_of(p)];
  int best = 0;
  std::size_t best_count = 0;
  for (const auto& [first, count] : hist) {
    std::size_t sum = 0;
    for (int k = 0; k < kLayerBins; ++k) {
      const auto it = hist.find(first + k);
      if (it != hist.end()) sum += it->second;
    }
    if (sum > best_count) best = first, best_count = sum;
  }
  return best;
}

void spread(const std::vector<Eigen::Vector3d>& from, std::size_t m, std::vector<Eigen::Vector3d>* out) {
  m = std::min(m, from.size());
  for (std::size_t i = 0; i < m; ++i) out->push_back(from[i * from.size() / m]);
}

}  // namespace

LayerBalance balance_layer(const std::vector<Eigen::Vector3d>& points, int max_points,
                           double max_layer_share) {
  LayerBalance b;
  const std::size_t max_n = static_cast<std::size_t>(std::max(max_points, 0));
  if (points.empty()) return b;
  const int first = dominant_window(points);
  std::vector<Eigen::Vector3d> layer, rest;
  for (const Eigen::Vector3d& p : points) {
    const int k = bin_of(p) - first;
    (k >= 0 && k < kLayerBins ? layer : rest).push_back(p);
  }
  b.layer_points = layer.size();
  const double share = static_cast<double>(layer.size()) / static_cast<double>(points.size());
  if (max_layer_share >= 1.0 || share <= max_layer_share) {
    spread(points, max_n, &b.points);
    return b;
  }
  b.capped = true;
  constexpr double kEps = 1e-9;  // products that should be whole numbers are not quite
  const auto rest_n =
      std::min(rest.size(), static_cast<std::size_t>(std::floor((1.0 - max_layer_share) * max_n + kEps)));
  const auto want = static_cast<std::size_t>(
      std::ceil(max_layer_share / (1.0 - max_layer_share) * static_cast<double>(rest_n) - kEps));
  const std::size_t layer_n = std::min(std::max(want, kMinLayerPoints), max_n - rest_n);
  spread(rest, rest_n, &b.points);
  spread(layer, layer_n, &b.points);
  return b;
}

}  // namespace mrvs::localise
