#include "mrvs/localise/localiser.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <unordered_map>
#include <variant>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>

#include "appearance.h"
#include "correlative_search.h"
#include "layer_balance.h"
#include "likelihood_grid.h"
#include "map_surface.h"
#include "mrvs/core/hash.h"
#include "mrvs/geometry/angles.h"
#include "point_to_plane.h"
#include "visibility.h"

namespace mrvs::localise {

using localisation::Request;
using localisation::Result;
using LStatus = localisation::Status;

struct Localiser::Impl {
  std::shared_ptr<const map::VoxelMap> map;
  LocaliserOptions options;
  const std::vector<map::MapPoint>* coarse = nullptr;  ///< the coarsest level's points
  std::vector<Eigen::Vector3f> coarse_points;
  Eigen::AlignedBox3d bounds;                 ///< of the map's points, map-local
  std::optional<LikelihoodPyramid> map_grid;  ///< the whole map's, when it fits max_grid_cells
  MapSurface surface;
  double setup_s = 0.0;
};

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

Result failure(LStatus status, std::string detail) {
  Result r;
  r.status = status;
  r.detail = std::move(detail);
  return r;
}

/// The request's problems, or empty.
std::string check_request(const Request& q, const LocaliserOptions& o) {
  if (static_cast<int>(q.points.size()) < o.min_points) {
    return fmt::format("{} submap points, at least {} needed", q.points.size(), o.min_points);
  }
  for (std::size_t i = 0; i < q.points.size(); ++i) {
    if (!q.points[i].allFinite()) return fmt::format("submap point {} is not finite", i);
  }
  if (!q.gravity_o.allFinite() || std::abs(q.gravity_o.norm() - 1.0) > 0.1) {
    return "gravity must be a unit vector";
  }
  if (!q.anchor_o.allFinite()) return "the anchor is not finite";
  if (q.prior &&
      (!q.prior->centre_m.allFinite() || !(q.prior->radius_m > 0.0) || !std::isfinite(q.prior->radius_m))) {
    return "the prior region needs a finite centre and a radius > 0";
  }
  return {};
}

/// One point per cell of `cell` (the mean of the cell's points), then at most max_points of
/// them, evenly spread over the list; deterministic. brightness (one per point, 0: none; or
/// empty): when `thinned_brightness` is given, it gets each kept cell's mean brightness (0: none).
std::vector<Eigen::Vector3d> thin(const std::vector<Eigen::Vector3d>& points, double cell, int max_points,
                                  const std::vector<std::uint8_t>& brightness = {},
                                  std::vector<float>* thinned_brightness = nullptr) {
  struct Cell {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
    double brightness_sum = 0.0;
    int brightness_count = 0;
  };
  std::unordered_map<std::uint64_t, Cell> cells;
  std::vector<std::uint64_t> order;
  const bool bright = brightness.size() == points.size();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d& p = points[i];
    const Eigen::Vector3i c = (p / cell).array().floor().cast<int>();
    const std::uint64_t key = mix64((static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.x())) << 42) ^
                                    (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.y())) << 21) ^
                                    static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.z())));
    auto [it, fresh] = cells.try_emplace(key);
    if (fresh) order.push_back(key);
    it->second.sum += p;
    ++it->second.count;
    if (bright && brightness[i] > 0) {
      it->second.brightness_sum += brightness[i];
      ++it->second.brightness_count;
    }
  }
  std::vector<Eigen::Vector3d> out;
  const std::size_t n = order.size();
  const std::size_t m = std::min<std::size_t>(n, static_cast<std::size_t>(max_points));
  out.reserve(m);
  if (thinned_brightness) thinned_brightness->assign(m, 0.0f);
  for (std::size_t i = 0; i < m; ++i) {
    const Cell& c = cells[order[i * n / m]];
    out.push_back(c.sum / c.count);
    if (thinned_brightness && c.brightness_count > 0)
      (*thinned_brightness)[i] = static_cast<float>(c.brightness_sum / c.brightness_count);
  }
  return out;
}

/// Rotation taking the odometry frame's gravity to -z (the map's).
Eigen::Matrix3d gravity_rotation(const Eigen::Vector3d& g_o) {
  return Eigen::Quaterniond::FromTwoVectors(g_o.normalized(), -Eigen::Vector3d::UnitZ()).toRotationMatrix();
}

double horizontal_reach(const std::vector<Eigen::Vector3d>& points) {
  std::vector<double> r;
  r.reserve(points.size());
  for (const Eigen::Vector3d& p : points) r.push_back(p.head<2>().norm());
  if (r.empty()) return 0.0;
  const std::size_t k = (r.size() * 95) / 100;
  std::nth_element(r.begin(), r.begin() + static_cast<std::ptrdiff_t>(std::min(k, r.size() - 1)), r.end());
  return r[std::min(k, r.size() - 1)];
}

struct Prepared {
  Eigen::Matrix3d R_g = Eigen::Matrix3d::Identity();  ///< odometry frame -> gravity-aligned
  std::vector<Eigen::Vector3d> coarse, fine;          ///< gravity-aligned, relative to the anchor
  std::vector<float> fine_brightness;                 ///< per fine point, 0: none
  /// Every k-th fine point, at most kSlidePoints, and its brightness: what the appearance slide
  /// searches on (seed-1 set: registration median 312 -> 224 ms against all fine points; the
  /// correlation's standard error stays below 0.04); the chosen pose is evaluated on all.
  std::vector<Eigen::Vector3d> slide;
  std::vector<float> slide_brightness;
  std::vector<SightLine> sight;  ///< a sample of the points with a viewpoint
  double reach_m = 0.0;          ///< horizontal, 95th percentile
  double height_m = 0.0;         ///< largest |z|
};

/// At most max_lines points with their viewpoints, evenly spread over the request's runs.
std::vector<SightLine> sight_lines(const Request& q, const Eigen::Matrix3d& R_g, int max_lines) {
  std::vector<SightLine> all;
  std::size_t next = 0;
  for (const localisation::Viewpoint& v : q.viewpoints) {
    const Eigen::Vector3d from = R_g * v.position.cast<double>();
    for (std::uint32_t k = 0; k < v.count && next < q.points.size(); ++k, ++next) {
      all.push_back({from, R_g * q.points[next].cast<double>()});
    }
  }
  if (all.size() <= static_cast<std::size_t>(max_lines)) return all;
  std::vector<SightLine> out;
  for (int i = 0; i < max_lines; ++i)
    out.push_back(all[static_cast<std::size_t>(i) * all.size() / max_lines]);
  return out;
}

Prepared prepare(const Request& q, const LocaliserOptions& o) {
  Prepared p;
  p.R_g = gravity_rotation(q.gravity_o);
  std::vector<Eigen::Vector3d> aligned;
  aligned.reserve(q.points.size());
  for (const Eigen::Vector3f& x : q.points) aligned.push_back(p.R_g * x.cast<double>());
  p.coarse = balance_layer(thin(aligned, o.coarse_resolution_m, std::numeric_limits<int>::max()),
                           o.coarse_max_points, o.coarse_layer_share)
                 .points;
  p.fine = thin(aligned, o.fine_voxel_m, o.fine_max_points, q.brightness, &p.fine_brightness);
  constexpr std::size_t kSlidePoints = 700;
  const std::size_t stride = std::max<std::size_t>(1, (p.fine.size() + kSlidePoints - 1) / kSlidePoints);
  for (std::size_t i = 0; i < p.fine.size(); i += stride) {
    p.slide.push_back(p.fine[i]);
    p.slide_brightness.push_back(p.fine_brightness[i]);
  }
  p.sight = sight_lines(q, p.R_g, o.sight_lines);
  p.reach_m = horizontal_reach(p.coarse);
  for (const Eigen::Vector3d& x : p.coarse) p.height_m = std::max(p.height_m, std::abs(x.z()));
  return p;
}

/// Where the anchor is searched and the grid that scores it (map-local).
struct Region {
  Eigen::AlignedBox3d anchors;
  Eigen::AlignedBox3d grid;
  std::optional<double> radius_m;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
};

std::variant<Region, Result> search_region(const Localiser::Impl& m, const Request& q, const Prepared& p) {
  const LocaliserOptions& o = m.options;
  const double res = o.coarse_resolution_m;
  Region r;
  r.anchors = Eigen::AlignedBox3d(m.bounds.min() - Eigen::Vector3d::Constant(res),
                                  m.bounds.max() + Eigen::Vector3d::Constant(res));
  if (q.prior) {
    r.centre = q.prior->centre_m - m.map->origin;
    r.radius_m = q.prior->radius_m;
    const Eigen::Vector3d half = Eigen::Vector3d::Constant(q.prior->radius_m);
    r.anchors = r.anchors.intersection(Eigen::AlignedBox3d(r.centre - half, r.centre + half));
    if (r.anchors.isEmpty()) {
      return failure(LStatus::kOutsideMap,
                     fmt::format("the prior region ({:.1f} m around [{:.1f} {:.1f} {:.1f}]) "
                                 "does not overlap the map",
                                 q.prior->radius_m, q.prior->centre_m.x(), q.prior->centre_m.y(),
                                 q.prior->centre_m.z()));
    }
  }
  const Eigen::Vector3d reach(p.reach_m + 2 * res, p.reach_m + 2 * res, p.height_m + 2 * res);
  r.grid = Eigen::AlignedBox3d(r.anchors.min() - reach, r.anchors.max() + reach)
               .intersection(Eigen::AlignedBox3d(m.bounds.min() - Eigen::Vector3d::Constant(2 * res),
                                                 m.bounds.max() + Eigen::Vector3d::Constant(2 * res)));
  const double cells = (r.grid.sizes() / res).array().ceil().prod();
  if (cells > static_cast<double>(o.max_grid_cells)) {
    return failure(LStatus::kBadRequest,
                   fmt::format("the search region needs {:.0f} grid cells, more than localise.max_grid_cells "
                               "({}): send a prior region (e.g. from GNSS)",
                               cells, o.max_grid_cells));
  }
  return r;
}

/// The coarse search's options: hypotheses kept apart by coarse_distinct_m (finer than the
/// ambiguity's distinct_m, so that a local minimum's neighbour is refined too).
SearchOptions search_options(const LocaliserOptions& o) {
  SearchOptions so;
  so.max_hypotheses = o.hypotheses;
  so.min_score = o.coarse_min_score;
  so.relative_score = o.coarse_relative_score;
  so.distinct_m = o.coarse_distinct_m;
  so.distinct_rad = o.distinct_deg * kDegToRad;
  so.max_nodes = o.max_search_nodes;
  return so;
}

/// Refined poses this close converged to the same place.
constexpr double kSameM = 0.1;
constexpr double kSameRad = 2.0 * kDegToRad;

FineOptions fine_options(const LocaliserOptions& o) {
  FineOptions fo;
  fo.iterations = o.fine_iterations;
  fo.ramp_iterations = o.fine_ramp_iterations;
  fo.start_distance_m = o.fine_start_distance_m;
  fo.end_distance_m = o.fine_end_distance_m;
  fo.huber_m = o.huber_m;
  fo.inlier_m = o.inlier_m;
  fo.voxel_m = o.fine_resolution_m;
  return fo;
}

struct Refined {
  Hypothesis pose;  ///< refined yaw and anchor; score = coarse score
  FineResult fine;
  double blocked = 0.0;                     ///< share of the lines of sight through the map's surfaces
  std::vector<std::uint8_t> blocked_lines;  ///< per line of sight: 1 through a surface
  Appearance appearance;                    ///< the submap's brightness against the map's intensity
  double slid_m = 0.0;                      ///< moved from the fine stage's pose by the appearance
  bool slide_unbracketed = false;           ///< the appearance rises past the slide's range (Slide)
  /// What tells placements apart: the inliers on vertical surfaces (a floor fits anywhere at
  /// the right height) less blocked_weight times the share of the lines of sight the pose
  /// makes pass through a surface, plus appearance_weight times the appearance correlation
  /// (with appearance_min_points). Additive, so that the best score also has the most evidence
  /// of its own against any other pose (strongest_rival's ratio stays at most 1).
  double score = 0.0;
};

/// Where the geometry holds a horizontal direction least (the smallest eigenvalue of the fine
/// stage's x-y information): a submap of one wall and the floor slides along the wall.
std::optional<Eigen::Vector3d> weakest_horizontal(const FineResult& f) {
  const Eigen::Matrix2d H = f.information.topLeftCorner<2, 2>();
  if (!H.allFinite() || H.isZero()) return std::nullopt;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(H);
  const Eigen::Vector2d v = eig.eigenvectors().col(0);
  return Eigen::Vector3d(v.x(), v.y(), 0.0).normalized();
}

/// The fine stage's pose slid along its weakest horizontal direction to where the appearance
/// fits best (appearance_slide_m; slide_by_appearance), when that beats where it stopped.
FineResult slide(const Localiser::Impl& m, const Prepared& p, FineResult f, double* slid_m,
                 bool* unbracketed) {
  const LocaliserOptions& o = m.options;
  *slid_m = 0.0;
  *unbracketed = false;
  const std::optional<Eigen::Vector3d> d = weakest_horizontal(f);
  if (o.appearance_weight <= 0.0 || o.appearance_slide_m <= 0.0 || !d) return f;
  SlideOptions so;
  so.range_m = o.appearance_slide_m;
  so.step_m = o.appearance_slide_step_m;
  so.coarse_stride = o.appearance_slide_coarse_stride;
  so.margin_sd = o.appearance_margin_sd;
  so.min_points = o.appearance_min_points;
  const Slide s =
      slide_by_appearance(m.surface, p.slide, p.slide_brightness, f.yaw, f.anchor, *d, fine_options(o), so);
  if (s.offset_m == 0.0) return f;
  if (s.unbracketed) {  // the pose lies beyond the range: not where the fine stage put it
    *unbracketed = true;
    return f;
  }
  *slid_m = s.offset_m;
  FineOptions at = fine_options(o);
  at.iterations = 0;
  return refine_pose(m.surface, p.fine, f.yaw, f.anchor + s.offset_m * *d, at);
}

Refined refine_one(const Localiser::Impl& m, const Prepared& p, const LikelihoodPyramid& grid,
                   const Hypothesis& h) {
  const LocaliserOptions& o = m.options;
  Refined r;
  r.fine = slide(m, p, refine_pose(m.surface, p.fine, h.yaw, h.anchor, fine_options(o)), &r.slid_m,
                 &r.slide_unbracketed);
  r.pose = {r.fine.yaw, r.fine.anchor, h.score};
  r.blocked_lines = blocked_lines(grid, p.sight, r.pose.yaw, r.pose.anchor, o.sight_start_m, o.sight_margin_m,
                                  o.sight_margin_fraction);
  r.blocked = p.sight.empty()
                  ? 0.0
                  : static_cast<double>(std::count(r.blocked_lines.begin(), r.blocked_lines.end(), 1)) /
                        static_cast<double>(p.sight.size());
  r.appearance = appearance(m.surface, r.fine, p.fine_brightness);
  r.score = r.fine.structure - o.blocked_weight * r.blocked;
  if (r.appearance.points >= o.appearance_min_points)
    r.score += o.appearance_weight * r.appearance.correlation;
  return r;
}

std::vector<Refined> refine_all(const Localiser::Impl& m, const Prepared& p, const LikelihoodPyramid& grid,
                                const std::vector<Hypothesis>& coarse) {
  SearchOptions converged;
  converged.distinct_m = kSameM;
  converged.distinct_rad = kSameRad;
  std::vector<Refined> out;
  for (const Hypothesis& h : coarse) {
    Refined r = refine_one(m, p, grid, h);
    const auto same = std::find_if(out.begin(), out.end(),
                                   [&](const Refined& x) { return same_pose(x.pose, r.pose, converged); });
    if (same == out.end()) {
      out.push_back(r);
    } else if (r.score > same->score) {
      *same = r;
    }
  }
  std::sort(out.begin(), out.end(), [](const Refined& a, const Refined& b) { return a.score > b.score; });
  return out;
}

/// The answer's covariance (6x6 [rho; phi]) from the fine stage; nullopt when singular.
std::optional<Mat6d> covariance(const FineResult& f, double inflation) {
  const Eigen::FullPivLU<Eigen::Matrix4d> lu(f.information);
  if (f.information.isZero() || !lu.isInvertible()) return std::nullopt;
  const double s2 = std::max(f.rmse_m * f.rmse_m, 1e-8);
  const Eigen::Matrix4d c4 = inflation * s2 * lu.inverse();
  if (!c4.allFinite()) return std::nullopt;
  Mat6d c = Mat6d::Zero();
  const int map6[4] = {0, 1, 2, 5};
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) c(map6[i], map6[j]) = c4(i, j);
  }
  return c;
}

/// What tells the best pose from another: the evidence only one of them has. Per submap point
/// its structure weight under the one less under the other (a wall point that lands on a wall
/// under both tells nothing, however much it adds to both scores), and per line of sight one
/// pose leaves clear and the other blocks, blocked_weight; each as a share of its count.
struct Discord {
  double best_only = 0.0;
  double other_only = 0.0;
};

/// The appearance's share of the discord: a correlation difference beyond margin_sd standard
/// errors (about 1 / sqrt(n) each), times the weight; none when either pose has too few points.
void appearance_discord(const Refined& best, const Refined& other, const LocaliserOptions& o, Discord* d) {
  const Appearance& a = best.appearance;
  const Appearance& b = other.appearance;
  if (o.appearance_weight <= 0.0 || a.points < o.appearance_min_points || b.points < o.appearance_min_points)
    return;
  const double margin = o.appearance_margin_sd * std::sqrt(1.0 / a.points + 1.0 / b.points);
  const double diff = a.correlation - b.correlation;
  d->best_only += o.appearance_weight * std::max(0.0, diff - margin);
  d->other_only += o.appearance_weight * std::max(0.0, -diff - margin);
}

Discord discord(const Refined& best, const Refined& other, const LocaliserOptions& o) {
  const double line_weight = o.blocked_weight;
  Discord d;
  const std::vector<float>& eb = best.fine.evidence;
  const std::vector<float>& eo = other.fine.evidence;
  const std::size_t n = std::min(eb.size(), eo.size());
  for (std::size_t i = 0; i < n; ++i) {
    d.best_only += std::max(0.0f, eb[i] - eo[i]);
    d.other_only += std::max(0.0f, eo[i] - eb[i]);
  }
  if (n > 0) {
    d.best_only /= static_cast<double>(n);
    d.other_only /= static_cast<double>(n);
  }
  const std::size_t lines = std::min(best.blocked_lines.size(), other.blocked_lines.size());
  int best_clear = 0, other_clear = 0;
  for (std::size_t i = 0; i < lines; ++i) {
    best_clear += !best.blocked_lines[i] && other.blocked_lines[i];
    other_clear += best.blocked_lines[i] && !other.blocked_lines[i];
  }
  if (lines > 0) {
    d.best_only += line_weight * best_clear / static_cast<double>(lines);
    d.other_only += line_weight * other_clear / static_cast<double>(lines);
  }
  appearance_discord(best, other, o, &d);
  return d;
}

/// The distinct pose (farther than distinct_m or turned more than distinct_deg) the evidence
/// tells least well from the best, and the ambiguity: its exclusive evidence over the best's,
/// (other_only + floor) / (best_only + floor), at most 1; 1 when the best has less exclusive
/// evidence than min_discordance (nothing tells the two apart). index 0: no such pose.
struct Rival {
  std::size_t index = 0;
  double ambiguity = 0.0;
};

Rival strongest_rival(const std::vector<Refined>& refined, const LocaliserOptions& o) {
  constexpr double kFloor = 0.005;
  SearchOptions distinct;
  distinct.distinct_m = o.distinct_m;
  distinct.distinct_rad = o.distinct_deg * kDegToRad;
  Rival rival;
  for (std::size_t k = 1; k < refined.size(); ++k) {
    if (same_pose(refined[k].pose, refined.front().pose, distinct)) continue;
    const Discord d = discord(refined.front(), refined[k], o);
    const double a = d.best_only < o.min_discordance
                         ? 1.0
                         : std::min(1.0, (d.other_only + kFloor) / (d.best_only + kFloor));
    if (rival.index == 0 || a > rival.ambiguity) rival = {k, a};
  }
  return rival;
}

Result verdict(const Localiser::Impl& m, const Request& q, const Prepared& p,
               const std::vector<Refined>& refined) {
  const LocaliserOptions& o = m.options;
  const Refined& best = refined.front();
  Result r;
  r.hypotheses = static_cast<int>(refined.size());
  r.fitness = best.fine.fitness;
  r.blocked = best.blocked;
  r.rmse_m = best.fine.rmse_m;
  // The alternative: the best refined pose distinct from the best one (a neighbour within
  // distinct_m is the same place, a local minimum of the fine stage).
  const Rival rival = strongest_rival(refined, o);
  const auto alt = rival.index > 0 ? refined.begin() + rival.index : refined.end();
  r.ambiguity = rival.ambiguity;
  const Eigen::Matrix3d R = Eigen::AngleAxisd(best.pose.yaw, Eigen::Vector3d::UnitZ()) * p.R_g;
  const Eigen::Vector3d anchor_m = best.pose.anchor + m.map->origin;
  r.T_m_o = SE3d(Quatd(R).normalized(), anchor_m - R * q.anchor_o);
  if (best.fine.fitness < o.min_fitness) {
    r.status = LStatus::kOutsideMap;
    r.detail = fmt::format("the best pose puts {:.0f} % of the submap on the map's surfaces, {:.0f} % needed",
                           100 * best.fine.fitness, 100 * o.min_fitness);
    return r;
  }
  const std::optional<Mat6d> cov = covariance(best.fine, o.covariance_inflation);
  const double sigma_m =
      cov ? std::sqrt(cov->topLeftCorner<3, 3>().eigenvalues().real().maxCoeff()) : INFINITY;
  const double sigma_deg = cov ? std::sqrt((*cov)(5, 5)) * kRadToDeg : INFINITY;
  if (cov) r.covariance = *cov;
  if (!(sigma_m <= o.max_sigma_m) || !(sigma_deg <= o.max_sigma_deg)) {
    r.status = LStatus::kTooLittleStructure;
    r.detail = fmt::format("the submap leaves the pose uncertain: {:.3f} m, {:.2f} deg (limits {} m, {} deg)",
                           sigma_m, sigma_deg, o.max_sigma_m, o.max_sigma_deg);
    return r;
  }
  if (best.slide_unbracketed) {  // no best guess either (hypotheses 0): the pose is known to be off
    r.status = LStatus::kAmbiguous;
    r.hypotheses = 0;
    r.detail = fmt::format(
        "the appearance rises past {:.2f} m along the direction the geometry holds least: the pose lies "
        "farther "
        "along it",
        o.appearance_slide_m);
    return r;
  }
  if (o.appearance_weight > 0.0 && best.appearance.points >= o.appearance_min_points &&
      best.appearance.correlation < o.appearance_min) {  // no best guess either: the pose is likely wrong
    r.status = LStatus::kAmbiguous;
    r.hypotheses = 0;
    r.detail = fmt::format(
        "the best pose's appearance {:.2f} ({} points) is below localise.appearance_min {:.2f}: the submap's "
        "texture does not match the map there, the right pose was likely not among the {} refined",
        best.appearance.correlation, best.appearance.points, o.appearance_min, refined.size());
    return r;
  }
  if (r.ambiguity > o.max_ambiguity) {
    r.status = LStatus::kAmbiguous;
    r.detail = fmt::format(
        "another pose {:.2f} m / {:.1f} deg away is told apart too weakly (ambiguity {:.2f}; structure "
        "{:.2f} vs {:.2f}, lines of sight blocked: {:.0f} % vs {:.0f} %, appearance {:.2f} vs {:.2f})",
        (alt->pose.anchor - best.pose.anchor).norm(),
        yaw_difference(alt->pose.yaw, best.pose.yaw) * kRadToDeg, r.ambiguity, alt->fine.structure,
        best.fine.structure, 100 * alt->blocked, 100 * best.blocked, alt->appearance.correlation,
        best.appearance.correlation);
    return r;
  }
  r.status = LStatus::kOk;
  r.detail = fmt::format(
      "fitness {:.2f}, rmse {:.3f} m, ambiguity {:.2f}, sd {:.3f} m / {:.2f} deg, {:.0f} % of the "
      "lines of sight blocked, appearance {:.2f} ({} points), slid {:.2f} m",
      r.fitness, r.rmse_m, r.ambiguity, sigma_m, sigma_deg, 100 * best.blocked, best.appearance.correlation,
      best.appearance.points, best.slid_m);
  return r;
}

/// The pyramid levels for an anchor box: enough that the top level's windows are few.
int pyramid_levels(const Eigen::AlignedBox3d& anchors, const LocaliserOptions& o) {
  const double extent_cells = (anchors.sizes() / o.coarse_resolution_m).maxCoeff();
  return std::clamp(1 + static_cast<int>(std::ceil(std::log2(std::max(extent_cells, 1.0)))), 1,
                    o.branch_levels);
}

/// The coarse stage's grid (also the free-space check's): the whole map's, made once, when it
/// fits max_grid_cells (a prior region then only narrows the anchors searched); else made for
/// the request's region.
struct SearchGrid {
  Region region;
  std::optional<LikelihoodPyramid> built;
  const LikelihoodPyramid* shared = nullptr;  ///< the map's own (when nothing was built)
  const LikelihoodPyramid& get() const { return built ? *built : *shared; }
};

std::variant<SearchGrid, Result> search_grid(const Localiser::Impl& m, const Request& q, const Prepared& p) {
  const LocaliserOptions& o = m.options;
  auto region = search_region(m, q, p);
  if (auto* fail = std::get_if<Result>(&region)) return *fail;
  SearchGrid g;
  g.region = std::get<Region>(region);
  if (!m.map_grid) {
    g.built = LikelihoodPyramid::build(m.coarse_points, g.region.grid, o.coarse_resolution_m,
                                       pyramid_levels(g.region.anchors, o), 1.0);
  }
  if (!g.built) g.shared = &*m.map_grid;
  return g;
}

/// The coarse stage: the best distinct hypotheses (empty: none good enough).
std::vector<Hypothesis> coarse_search(const LocaliserOptions& o, const SearchGrid& g, const Prepared& p,
                                      SearchStats* stats) {
  const double res = o.coarse_resolution_m;
  SearchWindow w;
  w.anchor_min = g.get().cell_of(g.region.anchors.min());
  w.anchor_max = g.get().cell_of(g.region.anchors.max());
  w.radius_m = g.region.radius_m;
  w.centre = g.region.centre;
  w.yaw_step_rad =
      o.yaw_step_deg > 0
          ? o.yaw_step_deg * kDegToRad
          : std::clamp(std::acos(1.0 - 0.5 * res * res / std::max(p.reach_m * p.reach_m, res * res)),
                       0.2 * kDegToRad, 10.0 * kDegToRad);
  return correlative_search(g.get(), p.coarse, w, search_options(o), stats);
}

Result run(const Localiser::Impl& m, const Request& q) {
  const LocaliserOptions& o = m.options;
  if (std::string bad = check_request(q, o); !bad.empty()) return failure(LStatus::kBadRequest, bad);
  const Prepared p = prepare(q, o);
  if (static_cast<int>(p.coarse.size()) < 10) {
    return failure(LStatus::kTooLittleStructure,
                   fmt::format("the submap covers {} cells of {} m", p.coarse.size(), o.coarse_resolution_m));
  }
  auto grid = search_grid(m, q, p);
  if (auto* fail = std::get_if<Result>(&grid)) return *fail;
  const SearchGrid& g = std::get<SearchGrid>(grid);
  SearchStats stats;
  const std::vector<Hypothesis> coarse = coarse_search(o, g, p, &stats);
  if (!stats.complete) {
    // The best of what was searched is no answer: a better pose may lie in what was not.
    return failure(
        LStatus::kAmbiguous,
        fmt::format("the search stopped after {} windows (localise.max_search_nodes): too many poses fit "
                    "about equally",
                    stats.nodes));
  }
  if (coarse.empty()) {
    return failure(
        LStatus::kOutsideMap,
        fmt::format("no pose puts {:.0f} % of the submap near the map's surfaces", 100 * o.coarse_min_score));
  }
  return verdict(m, q, p, refine_all(m, p, g.get(), coarse));
}

}  // namespace

StatusOr<Localiser> Localiser::create(std::shared_ptr<const map::VoxelMap> map, const LocaliserOptions& o) {
  MRVS_RETURN_IF_ERROR(config::validate_options(o));
  if (!map || map->levels.empty() || map->point_count() == 0) {
    return absl::FailedPreconditionError("localisation: the map has no points");
  }
  const int fine = map->level_of(o.fine_resolution_m);
  if (fine < 0) {
    return absl::InvalidArgumentError(
        fmt::format("localise.fine_resolution_m {} is not a level of the map (levels: {} m)",
                    o.fine_resolution_m, fmt::join(map->resolutions(), ", ")));
  }
  const auto t0 = Clock::now();
  auto impl = std::make_shared<Impl>();
  impl->map = map;
  impl->options = o;
  for (const map::MapPoint& p : map->levels.back().points) {
    impl->coarse_points.push_back(p.position);
    impl->bounds.extend(p.position.cast<double>());
  }
  std::vector<Eigen::Vector3f> fine_points;
  std::vector<float> fine_intensity;
  fine_points.reserve(map->levels[static_cast<std::size_t>(fine)].points.size());
  for (const map::MapPoint& p : map->levels[static_cast<std::size_t>(fine)].points) {
    fine_points.push_back(p.position);
    fine_intensity.push_back(p.intensity);
  }
  impl->surface = MapSurface::build(std::move(fine_points), o.normal_knn, o.normal_max_rms_m, fine_intensity);
  const double res = o.coarse_resolution_m;
  const Eigen::AlignedBox3d whole(impl->bounds.min() - Eigen::Vector3d::Constant(2 * res),
                                  impl->bounds.max() + Eigen::Vector3d::Constant(2 * res));
  if ((whole.sizes() / res).array().ceil().prod() <= static_cast<double>(o.max_grid_cells)) {
    const Eigen::AlignedBox3d anchors(impl->bounds.min() - Eigen::Vector3d::Constant(res),
                                      impl->bounds.max() + Eigen::Vector3d::Constant(res));
    impl->map_grid =
        LikelihoodPyramid::build(impl->coarse_points, whole, res, pyramid_levels(anchors, o), 1.0);
  }
  impl->setup_s = ms_since(t0) * 1e-3;
  Localiser l;
  l.impl_ = std::move(impl);
  return l;
}

localisation::Result Localiser::localise(const Request& request) const {
  const auto t0 = Clock::now();
  Result r = run(*impl_, request);
  r.time_ms = ms_since(t0);
  return r;
}

namespace {

/// The fine stage alone from T_m_o (iterations 0: the fit at T_m_o as it is).
Result fine_from(const Localiser::Impl& m, const Request& q, const SE3d& T_m_o, int iterations) {
  const Prepared p = prepare(q, m.options);
  // T_m_o = [R_z(yaw) R_g | anchor_m - R anchor_o]: the yaw and the anchor's map-local position.
  const Eigen::Matrix3d R = T_m_o.rotation_matrix() * p.R_g.transpose();
  const double yaw = std::atan2(R(1, 0) - R(0, 1), R(0, 0) + R(1, 1));
  const Eigen::Vector3d anchor = T_m_o * q.anchor_o - m.map->origin;
  FineOptions fo = fine_options(m.options);
  fo.iterations = iterations;
  const FineResult f = refine_pose(m.surface, p.fine, yaw, anchor, fo);
  Result r;
  r.status = LStatus::kOk;
  const Eigen::Matrix3d R_f = Eigen::AngleAxisd(f.yaw, Eigen::Vector3d::UnitZ()) * p.R_g;
  r.T_m_o =
      iterations == 0 ? T_m_o : SE3d(Quatd(R_f).normalized(), f.anchor + m.map->origin - R_f * q.anchor_o);
  r.fitness = f.fitness;
  r.rmse_m = f.rmse_m;
  if (m.map_grid) {
    r.blocked = blocked_share(*m.map_grid, p.sight, f.yaw, f.anchor, m.options.sight_start_m,
                              m.options.sight_margin_m, m.options.sight_margin_fraction);
  }
  return r;
}

}  // namespace

localisation::Result Localiser::evaluate(const Request& q, const SE3d& T_m_o) const {
  return fine_from(*impl_, q, T_m_o, 0);
}

localisation::Result Localiser::refine(const Request& q, const SE3d& T_m_o_start) const {
  if (std::string bad = check_request(q, impl_->options); !bad.empty())
    return failure(LStatus::kBadRequest, bad);
  const auto t0 = Clock::now();
  Result r = fine_from(*impl_, q, T_m_o_start, impl_->options.fine_iterations);
  r.time_ms = ms_since(t0);
  return r;
}

const LocaliserOptions& Localiser::options() const { return impl_->options; }
double Localiser::setup_s() const { return impl_->setup_s; }

}  // namespace mrvs::localise
