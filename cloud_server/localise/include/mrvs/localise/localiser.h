#pragma once
// The cloud's localisation service (design/localisation.md): where does the edge's odometry
// frame lie in this map? From the edge's submap (points in its odometry frame, gravity known)
// and an optional prior region:
//   1. coarse: branch-and-bound over (x, y, z, yaw) on a likelihood grid of the map's coarsest
//      level, exact on the grid's lattice, keeping the best few mutually distinct poses;
//   2. fine: 4-DoF point-to-plane ICP of each against a finer level (with normals);
//   3. verify: fitness (share of the submap on the map's surface), ambiguity (best against the
//      distinct other pose told least well from it: the evidence only that pose has over the
//      evidence only the best has, counting submap points on vertical surfaces under one pose
//      and not the other, and lines of sight one pose leaves clear and the other blocks), and
//      the covariance from the fine stage's information matrix, inflated (registration
//      covariances are optimistic).
// Read-only after create(): localise() is thread-safe and runs on the calling thread.
#include <memory>
#include <string>

#include "mrvs/config/options.h"
#include "mrvs/core/status.h"
#include "mrvs/localisation/types.h"
#include "mrvs/map/voxel_map.h"

namespace mrvs::localise {

struct LocaliserOptions : config::OptionsEquality<LocaliserOptions> {
  int min_points = 100;              ///< fewer submap points: bad request
  double coarse_resolution_m = 0.1;  ///< the coarse grid's cell, m
  int coarse_max_points = 500;       ///< submap points scored by the coarse search
  /// Largest share of the coarse search's points on the dominant horizontal layer (the floor;
  /// balance_layer): a view mostly of floor keeps its few points on walls in the search. 1: no cap.
  double coarse_layer_share = 1.0;
  double yaw_step_deg = 0.0;             ///< 0: the cell seen from the submap's far points
  int branch_levels = 5;                 ///< pyramid levels of the branch and bound
  double coarse_min_score = 0.15;        ///< a pose scoring less is no hypothesis, [0, 1]
  double coarse_relative_score = 0.6;    ///< ... nor one scoring less than this times the best, [0, 1]
  long long max_grid_cells = 50000000;   ///< larger search regions are refused (send a prior region)
  long long max_search_nodes = 1500000;  ///< the coarse search gives up (ambiguous) after this many windows
  int hypotheses = 6;                    ///< distinct coarse poses refined
  double coarse_distinct_m =
      0.25;                    ///< coarse poses closer than this (and turned less than distinct_deg) are one
  double distinct_m = 0.5;     ///< refined poses closer than this ...
  double distinct_deg = 10.0;  ///< ... and turned less than this are one (the ambiguity's alternatives)
  double fine_resolution_m = 0.03;  ///< the map level the fine stage registers to, m
  double fine_voxel_m = 0.05;       ///< the submap is thinned to one point per this cell, m
  int fine_max_points = 2000;
  int fine_iterations = 40;             ///< at most (fewer once converged)
  int fine_ramp_iterations = 10;        ///< the correspondence distance shrinks over these ...
  double fine_start_distance_m = 0.3;   ///< ... from this, m ...
  double fine_end_distance_m = 0.1;     ///< ... to this, kept until converged, m
  double huber_m = 0.03;                ///< point-to-plane residuals beyond are down-weighted, m
  int normal_knn = 12;                  ///< map points in a normal's fit
  double normal_max_rms_m = 0.01;       ///< rougher neighbourhoods have no normal, m
  double inlier_m = 0.05;               ///< submap points this close to the map are on it, m
  double min_fitness = 0.5;             ///< less: outside the map
  double max_ambiguity = 0.8;           ///< more: ambiguous
  double min_discordance = 0.03;        ///< less evidence only the best pose has: ambiguous
  int sight_lines = 600;                ///< lines of sight checked against the map per pose
  double sight_start_m = 0.2;           ///< ... from this far after their viewpoint ...
  double sight_margin_m = 0.15;         ///< ... to this far before their point, m ...
  double sight_margin_fraction = 0.15;  ///< ... plus this share of the line (lines grazing a surface)
  double blocked_weight = 1.0;  ///< a pose's score (structure share) drops by this times its blocked share
  /// A pose's score rises by this times the rank correlation of the submap's brightness with
  /// the map's intensity at its inliers (Wolcott & Eustice, IROS 2014: a camera in a LiDAR
  /// reflectivity map); 0: geometry only.
  double appearance_weight = 0.0;
  int appearance_min_points = 50;  ///< fewer inliers with a brightness: no appearance term
  /// A best pose whose appearance correlation is below this is no answer (ambiguous, no guess):
  /// the texture says the right pose was not among the hypotheses. -1: never.
  double appearance_min = -1.0;
  /// The correlations of two poses tell them apart only beyond this many standard errors.
  double appearance_margin_sd = 2.0;
  /// The fine stage's pose is slid along its weakest horizontal direction by up to this (both
  /// ways) to where the appearance correlates best, when that beats where it stopped by the
  /// margin (a submap of one wall and the floor slides along the wall); 0: never.
  double appearance_slide_m = 0.0;
  double appearance_slide_step_m = 0.02;   ///< ... in these steps
  int appearance_slide_coarse_stride = 1;  ///< first every this many steps, then the steps around the best
  double covariance_inflation = 25.0;      ///< variance factor on the information matrix's inverse
  double max_sigma_m = 0.1;                ///< a less certain translation: too little structure, m
  double max_sigma_deg = 1.0;              ///< a less certain yaw: too little structure, deg

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("min_points", min_points, in_range(10, 100000), "submap points a request needs");
    v("coarse_resolution_m", coarse_resolution_m, in_range(0.01, 10.0), "coarse grid cell, m");
    v("coarse_max_points", coarse_max_points, in_range(10, 100000), "submap points of the coarse search");
    v("coarse_layer_share", coarse_layer_share, in_range(0.05, 1.0),
      "largest share of the coarse points on the dominant horizontal layer (1: no cap)");
    v("yaw_step_deg", yaw_step_deg, in_range(0.0, 45.0), "coarse yaw step, deg (0: from the cell and range)");
    v("branch_levels", branch_levels, in_range(1, 12), "branch-and-bound pyramid levels");
    v("coarse_min_score", coarse_min_score, in_range(0.0, 1.0), "least coarse score of a hypothesis");
    v("coarse_relative_score", coarse_relative_score, in_range(0.0, 1.0),
      "least coarse score of a hypothesis relative to the best");
    v("max_grid_cells", max_grid_cells, in_range(1000LL, 2000000000LL), "largest search grid, cells");
    v("max_search_nodes", max_search_nodes, in_range(0LL, 1000000000LL),
      "coarse windows scored at most (0: no limit); beyond: ambiguous");
    v("hypotheses", hypotheses, in_range(1, 64), "distinct coarse poses refined");
    v("coarse_distinct_m", coarse_distinct_m, in_range(0.0, 1000.0),
      "coarse poses this close (and turned less) are one hypothesis, m");
    v("distinct_m", distinct_m, in_range(0.0, 1000.0),
      "refined poses this close (and turned less) are one, m");
    v("distinct_deg", distinct_deg, in_range(0.0, 180.0), "poses turned less (and this close) are one, deg");
    v("fine_resolution_m", fine_resolution_m, in_range(0.001, 10.0), "map level of the fine stage, m");
    v("fine_voxel_m", fine_voxel_m, in_range(0.001, 10.0), "submap thinning cell of the fine stage, m");
    v("fine_max_points", fine_max_points, in_range(10, 1000000), "submap points of the fine stage");
    v("fine_iterations", fine_iterations, in_range(1, 1000), "most fine stage iterations");
    v("fine_ramp_iterations", fine_ramp_iterations, in_range(0, 1000),
      "iterations over which the correspondence distance shrinks");
    v("fine_start_distance_m", fine_start_distance_m, in_range(0.001, 100.0),
      "first correspondence distance, m");
    v("fine_end_distance_m", fine_end_distance_m, in_range(0.001, 100.0), "last correspondence distance, m");
    v("huber_m", huber_m, in_range(0.0001, 100.0), "Huber threshold of the residuals, m");
    v("normal_knn", normal_knn, in_range(3, 1000), "map points per normal fit");
    v("normal_max_rms_m", normal_max_rms_m, in_range(0.0, 10.0), "roughest plane given a normal, m");
    v("inlier_m", inlier_m, in_range(0.001, 100.0), "distance of a submap point on the map, m");
    v("min_fitness", min_fitness, in_range(0.0, 1.0), "least fitness of an answer");
    v("max_ambiguity", max_ambiguity, in_range(0.0, 1.0), "largest ambiguity of an answer");
    v("min_discordance", min_discordance, in_range(0.0, 1.0),
      "least evidence (share of the submap) only the best pose has over another distinct one");
    v("sight_lines", sight_lines, in_range(0, 100000),
      "lines of sight checked per pose (0: no free-space check)");
    v("sight_start_m", sight_start_m, in_range(0.0, 100.0),
      "free-space check starts this far from the viewpoint, m");
    v("sight_margin_m", sight_margin_m, in_range(0.0, 100.0), "... and ends this far before the point, m");
    v("sight_margin_fraction", sight_margin_fraction, in_range(0.0, 1.0),
      "... plus this share of the line's length (grazing lines)");
    v("blocked_weight", blocked_weight, in_range(0.0, 100.0), "score drop per blocked share");
    v("appearance_weight", appearance_weight, in_range(0.0, 100.0),
      "score rise per brightness-intensity rank correlation (0: geometry only)");
    v("appearance_min_points", appearance_min_points, in_range(3, 100000),
      "least inliers with a brightness for the appearance term");
    v("appearance_min", appearance_min, in_range(-1.0, 1.0),
      "least appearance correlation of an answer's pose (-1: none)");
    v("appearance_margin_sd", appearance_margin_sd, in_range(0.0, 100.0),
      "correlation differences within this many standard errors tell nothing");
    v("appearance_slide_m", appearance_slide_m, in_range(0.0, 10.0),
      "largest slide of a pose along its weakest horizontal direction by the appearance, m (0: none)");
    v("appearance_slide_step_m", appearance_slide_step_m, in_range(0.001, 1.0), "... in these steps, m");
    v("appearance_slide_coarse_stride", appearance_slide_coarse_stride, in_range(1, 100),
      "the slide tries every this many steps first, then the steps around the best");
    v("covariance_inflation", covariance_inflation, in_range(1.0, 1e6), "variance factor of the covariance");
    v("max_sigma_m", max_sigma_m, in_range(0.0001, 100.0), "largest translation sd of an answer, m");
    v("max_sigma_deg", max_sigma_deg, in_range(0.001, 180.0), "largest yaw sd of an answer, deg");
  }
};

class Localiser {
 public:
  /// Precomputes the fine level's normals and k-d tree. Error when fine_resolution_m is not a
  /// level of the map or the map is empty.
  static StatusOr<Localiser> create(std::shared_ptr<const map::VoxelMap> map,
                                    const LocaliserOptions& options);

  /// One attempt; every failure is a status of the result, never an error.
  localisation::Result localise(const localisation::Request& request) const;
  /// How well the request fits the map at a given T_m_o, without searching (diagnostics:
  /// e.g. at the true pose): fitness, rmse and the share of blocked lines of sight
  /// (ambiguity: 0, status kOk).
  localisation::Result evaluate(const localisation::Request& request, const SE3d& T_m_o) const;
  /// The fine stage alone (4-DoF point-to-plane, fine_iterations) started at T_m_o_start, no
  /// search and no verdict (comparisons of registration methods from one start): the refined
  /// T_m_o, its fitness, rmse and blocked share, the time; status kOk (kBadRequest for a
  /// malformed request).
  localisation::Result refine(const localisation::Request& request, const SE3d& T_m_o_start) const;

  const LocaliserOptions& options() const;
  /// Seconds spent in create() (normals, tree).
  double setup_s() const;

  struct Impl;  ///< the map's precomputed parts (localiser.cpp)

 private:
  std::shared_ptr<const Impl> impl_;
};

}  // namespace mrvs::localise
