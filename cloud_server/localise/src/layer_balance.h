#pragma once
// The coarse search's points with the dominant horizontal layer (the floor) capped: a view that
// is mostly floor otherwise scores the same at every placement on the floor, and its few points
// on walls and furniture, which alone tell the placements apart, drown in it (design/localisation.md).
#include <vector>

#include <Eigen/Core>

namespace mrvs::localise {

struct LayerBalance {
  std::vector<Eigen::Vector3d> points;  ///< the kept points: the others first, then the layer's
  std::size_t layer_points = 0;         ///< of the input, in the dominant layer
  bool capped = false;                  ///< the layer held more than its share
};

/// Height band of the dominant layer: the kLayerBins consecutive kLayerBinM bins of z with the
/// most points.
constexpr double kLayerBinM = 0.05;
constexpr int kLayerBins = 3;
/// The layer keeps at least this many points (they fix the height).
constexpr std::size_t kMinLayerPoints = 50;

/// At most max_points of `points` (gravity-aligned: z up), evenly spread over each list. When
/// the dominant layer holds more than max_layer_share of them, the others are kept first (up to
/// (1 - share) * max_points) and the layer gets share / (1 - share) times as many (at least
/// kMinLayerPoints). max_layer_share >= 1: no cap, plain even spread.
LayerBalance balance_layer(const std::vector<Eigen::Vector3d>& points, int max_points,
                           double max_layer_share);

}  // namespace mrvs::localise
