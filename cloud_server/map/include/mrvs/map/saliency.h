#pragma once
// Photometric saliency of raw map points (paper section III-A, eq. S_photo; algorithm.md
// 1.1 / 1.3):
//
//   S(p_i) = max over p_j in N_i of |I_i - I_j| / ||p_i - p_j|| * (1 + alpha |n_i . (p_j - p_i)| / ||p_j -
//   p_i||)
//
// N_i: the K nearest other points of p_i (the search asks for K + 1 points, p_i itself
// included; any neighbour closer than min_neighbour_distance_m, p_i or a duplicate, is
// skipped). n_i: the unit normal of the same K + 1 points, the eigenvector of the smallest
// eigenvalue of their covariance (PCL's computeMeanAndCovarianceMatrix + solvePlaneParameters,
// the computation pcl::NormalEstimation does; done here on the neighbourhood already found so
// the search runs once per point). A degenerate neighbourhood (non-finite normal) gets no
// normal term. A point without a usable neighbour has S = 0.
//
// Units: intensity units per metre. Parallel (OpenMP) and deterministic: every point's value
// depends only on the cloud, never on the thread count or schedule.
#include <vector>

#include <Eigen/Core>

#include "mrvs/core/status.h"

namespace mrvs::map {

struct SaliencyOptions {
  int knn = 16;                            ///< K: neighbours per point (the point itself excluded)
  double alpha = 1.0;                      ///< weight of the normal (depth-edge) term, >= 0
  double min_neighbour_distance_m = 1e-6;  ///< neighbours closer than this are skipped, metres
  int threads = 0;                         ///< OpenMP threads, 0 = OpenMP's default
};

/// Saliency of every point. `positions` are metres in a local frame (float is enough once the
/// map origin is subtracted); `intensities` has one value per position. Errors: size
/// mismatch, no point, knn < 1, alpha < 0 or not finite, a non-finite position.
StatusOr<std::vector<float>> compute_saliency(const std::vector<Eigen::Vector3f>& positions,
                                              const std::vector<float>& intensities,
                                              const SaliencyOptions& options);

}  // namespace mrvs::map
