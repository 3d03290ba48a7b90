// Outdoor street canyon layout (simulator.md 3.3): corridors along the legs, arcs at the
// turns, sidewalks and buildings placed by rejection sampling.
#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "layout.h"
#include "mrvs/geometry/angles.h"
#include "mrvs/sim/rng.h"
#include "street.h"

namespace mrvs::sim {

using Vec2d = Eigen::Vector2d;

namespace {

constexpr double kThinStep = 1.0;  ///< route samples closer than this are dropped, metres
constexpr double kAxisToleranceDeg = 2.0;
constexpr double kMinLegLength = 5.0;
constexpr double kMergeDistance = 1.0;  ///< collinear legs whose lines differ less are merged

/// 0: not axis-aligned; 1: +x, 2: -x, 3: +y, 4: -y.
int classify_step(const Vec2d& d) {
  const double tol = std::tan(kAxisToleranceDeg * kPi / 180.0);
  if (std::abs(d.y()) <= tol * std::abs(d.x())) return d.x() > 0 ? 1 : 2;
  if (std::abs(d.x()) <= tol * std::abs(d.y())) return d.y() > 0 ? 3 : 4;
  return 0;
}

struct Run {
  int cls;
  std::size_t first;
  std::size_t last;
  double length;
};

std::vector<Run> axis_runs(const std::vector<Vec2d>& pts) {
  std::vector<Run> runs;
  for (std::size_t k = 0; k + 1 < pts.size(); ++k) {
    const Vec2d d = pts[k + 1] - pts[k];
    const int cls = classify_step(d);
    if (!runs.empty() && runs.back().cls == cls && runs.back().last == k) {
      runs.back().last = k + 1;
      runs.back().length += d.norm();
    } else {
      runs.push_back(Run{cls, k, k + 1, d.norm()});
    }
  }
  return runs;
}

StreetLeg leg_from_run(const std::vector<Vec2d>& pts, const Run& run) {
  const int axis = (run.cls - 1) / 2;
  const int other = 1 - axis;
  std::vector<double> cross;
  for (std::size_t i = run.first; i <= run.last; ++i) cross.push_back(pts[i][other]);
  std::nth_element(cross.begin(), cross.begin() + cross.size() / 2, cross.end());
  const double line = cross[cross.size() / 2];
  StreetLeg leg;
  leg.start = pts[run.first];
  leg.end = pts[run.last];
  leg.start[other] = line;
  leg.end[other] = line;
  return leg;
}

int leg_axis(const StreetLeg& l) {
  const Vec2d d = l.end - l.start;
  return std::abs(d.x()) >= std::abs(d.y()) ? 0 : 1;
}

}  // namespace

StatusOr<std::vector<StreetLeg>> infer_street_legs(const std::vector<Vec3d>& route) {
  std::vector<Vec2d> pts;
  for (const Vec3d& p : route) {
    if (!p.allFinite()) return absl::InvalidArgumentError("a route sample is not finite");
    if (pts.empty() || (p.head<2>() - pts.back()).norm() >= kThinStep) pts.push_back(p.head<2>());
  }
  std::vector<StreetLeg> legs;
  std::vector<int> classes;
  for (const Run& run : axis_runs(pts)) {
    if (run.cls == 0 || run.length < kMinLegLength) continue;
    const StreetLeg leg = leg_from_run(pts, run);
    const int other = 1 - (run.cls - 1) / 2;
    if (!classes.empty() && classes.back() == run.cls &&
        std::abs(legs.back().end[other] - leg.start[other]) <= kMergeDistance) {
      legs.back().end = leg.end;
      legs.back().end[other] = legs.back().start[other];
      continue;
    }
    legs.push_back(leg);
    classes.push_back(run.cls);
  }
  if (legs.empty()) {
    return absl::InvalidArgumentError(
        fmt::format("no straight axis-aligned leg of >= {} m found in the {} route samples; the outdoor "
                    "profile needs a car "
                    "route of x/y-aligned legs (or call make_street_scene with explicit legs)",
                    kMinLegLength, route.size()));
  }
  for (std::size_t i = 0; i + 1 < legs.size(); ++i) {
    if ((classes[i] - 1) / 2 == (classes[i + 1] - 1) / 2) {
      return absl::InvalidArgumentError(
          fmt::format("route legs {} and {} are parallel; consecutive legs must be perpendicular", i, i + 1));
    }
  }
  return legs;
}

namespace detail {
namespace {

/// Axis-aligned 2-D rectangle.
using Rect = Eigen::AlignedBox2d;

Rect corridor_rect(const StreetCorridor& c, double s0, double s1, double q0, double q1) {
  Rect r;
  r.extend(c.point(s0, q0));
  r.extend(c.point(s1, q1));
  return r;
}

bool overlaps(const Rect& a, const Rect& b) {
  constexpr double kTol = 1e-6;
  return a.min().x() < b.max().x() - kTol && b.min().x() < a.max().x() - kTol &&
         a.min().y() < b.max().y() - kTol && b.min().y() < a.max().y() - kTol;
}

double rect_distance(const Rect& r, const Vec2d& p) {
  const Vec2d d = (r.min() - p).cwiseMax(p - r.max()).cwiseMax(0.0);
  return d.norm();
}

SceneBox box_from_rect(const Rect& r, double height, BoxKind kind) {
  SceneBox b;
  b.kind = kind;
  b.centre = Vec3d(r.center().x(), r.center().y(), 0.5 * height);
  b.half = Vec3d(0.5 * r.sizes().x(), 0.5 * r.sizes().y(), 0.5 * height);
  finalize_box(b);
  return b;
}

Rect box_rect(const SceneBox& b) {
  return Rect(b.centre.head<2>() - b.half.head<2>(), b.centre.head<2>() + b.half.head<2>());
}

/// Everything the placement rules look at.
struct Context {
  std::vector<StreetCorridor> corridors;
  std::vector<Rect> asphalt;     ///< per corridor
  std::vector<Vec2d> samples;    ///< route (keep-clear, legs and arcs), xy
  std::vector<int> inner_side;   ///< per corner i (between legs i and i+1): +1 left turn, -1 right
  std::vector<double> corner_s;  ///< per corner: its along coordinate, on leg i (hi) and leg i+1 (lo)
  std::vector<double> corner_s_next;
};

Status validate_legs(const std::vector<StreetLeg>& legs) {
  if (legs.empty()) return absl::InvalidArgumentError("the outdoor scene needs at least one street leg");
  for (std::size_t i = 0; i < legs.size(); ++i) {
    const Vec2d d = legs[i].end - legs[i].start;
    const int axis = leg_axis(legs[i]);
    if (!d.allFinite() || std::abs(d[axis]) < 1.0 ||
        std::abs(d[1 - axis]) > 1e-6 * std::abs(d[axis]) + 1e-9) {
      return absl::InvalidArgumentError(
          fmt::format("street leg {} ({}, {}) -> ({}, {}) is not an axis-aligned segment of >= 1 m", i,
                      legs[i].start.x(), legs[i].start.y(), legs[i].end.x(), legs[i].end.y()));
    }
    if (i > 0 && leg_axis(legs[i - 1]) == axis) {
      return absl::InvalidArgumentError(fmt::format(
          "street legs {} and {} are parallel; consecutive legs must be perpendicular", i - 1, i));
    }
  }
  return absl::OkStatus();
}

StreetCorridor corridor_of(const StreetLeg& leg) {
  StreetCorridor c;
  c.axis = leg_axis(leg);
  c.sign = leg.end[c.axis] >= leg.start[c.axis] ? 1 : -1;
  c.line = leg.start[1 - c.axis];
  c.s_lo = c.sign * leg.start[c.axis];
  c.s_hi = c.sign * leg.end[c.axis];
  return c;
}

/// Corners, arcs, corridors with their asphalt extents and the dense route samples.
void build_streets(const std::vector<StreetLeg>& legs, const std::vector<Vec3d>& keep_clear, Context& ctx,
                   StreetLayout& out) {
  const std::size_t n = legs.size();
  for (const StreetLeg& l : legs) ctx.corridors.push_back(corridor_of(l));
  for (std::size_t i = 0; i + 1 < n; ++i) {
    StreetCorridor& a = ctx.corridors[i];
    StreetCorridor& b = ctx.corridors[i + 1];
    Vec2d k;
    k[a.axis] = b.line;
    k[b.axis] = a.line;
    const Vec2d ha = a.point(1.0, 0.0) - a.point(0.0, 0.0);
    const Vec2d hb = b.point(1.0, 0.0) - b.point(0.0, 0.0);
    ctx.inner_side.push_back(ha.x() * hb.y() - ha.y() * hb.x() > 0 ? 1 : -1);
    ctx.corner_s.push_back(a.along(k));
    ctx.corner_s_next.push_back(b.along(k));
    const Vec2d va = legs[i].end - k;
    const Vec2d vb = legs[i + 1].start - k;
    const double r = 0.5 * (va.norm() + vb.norm());
    if (va.norm() >= 0.5 && vb.norm() >= 0.5) {
      StreetArc arc;
      arc.radius = r;
      arc.centre = k + r * (va.normalized() + vb.normalized());
      arc.dir_a = -vb.normalized();
      arc.dir_b = -va.normalized();
      out.arcs.push_back(arc);
      for (int j = 0; j <= 90; ++j) {
        const double t = 0.5 * kPi * j / 90.0;
        ctx.samples.push_back(arc.centre + r * (std::cos(t) * arc.dir_a + std::sin(t) * arc.dir_b));
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    StreetCorridor& c = ctx.corridors[i];
    for (double s = c.s_lo; s <= c.s_hi; s += 1.0) ctx.samples.push_back(c.point(s, 0.0));
    ctx.samples.push_back(c.point(c.s_hi, 0.0));
    c.corner_lo = i > 0;
    c.corner_hi = i + 1 < n;
    c.s_lo = c.corner_lo ? ctx.corner_s_next[i - 1] - kRoadHalfWidth : c.s_lo - kStreetExtension;
    c.s_hi = c.corner_hi ? ctx.corner_s[i] + kRoadHalfWidth : c.s_hi + kStreetExtension;
    ctx.asphalt.push_back(corridor_rect(c, c.s_lo, c.s_hi, -kRoadHalfWidth, kRoadHalfWidth));
  }
  for (const Vec3d& p : keep_clear) ctx.samples.push_back(p.head<2>());
}

/// Along-range of the sidewalk (buildings = false) or the lots (true) on `side` of leg i.
std::pair<double, double> side_range(const Context& ctx, std::size_t i, int side, bool buildings) {
  const StreetCorridor& c = ctx.corridors[i];
  const double corridor = kRoadHalfWidth + kSidewalkWidth;
  double lo = c.s_lo;
  double hi = c.s_hi;
  if (c.corner_lo) {
    const double sc = ctx.corner_s_next[i - 1];
    const bool inner = ctx.inner_side[i - 1] == side;
    lo = inner ? sc + corridor : (buildings ? sc - corridor : sc - kRoadHalfWidth);
  }
  if (c.corner_hi) {
    const double sc = ctx.corner_s[i];
    const bool inner = ctx.inner_side[i] == side;
    hi = inner ? sc - corridor : (buildings ? sc + kOuterCornerReach : sc + corridor);
  }
  return {lo, hi};
}

double min_sample_distance(const Context& ctx, const Rect& r) {
  double best = std::numeric_limits<double>::infinity();
  for (const Vec2d& p : ctx.samples) best = std::min(best, rect_distance(r, p));
  return best;
}

void place_sidewalks(Context& ctx, StreetLayout& out) {
  constexpr double kPiece = 12.0;
  std::vector<Rect> placed;
  for (std::size_t i = 0; i < ctx.corridors.size(); ++i) {
    for (const int side : {1, -1}) {
      const auto [lo, hi] = side_range(ctx, i, side, false);
      const int pieces = static_cast<int>(std::ceil((hi - lo) / kPiece - 1e-9));
      for (int k = 0; k < pieces; ++k) {
        const double s0 = lo + (hi - lo) * k / pieces;
        const double s1 = lo + (hi - lo) * (k + 1) / pieces;
        const double q0 = side > 0 ? kRoadHalfWidth : -kRoadHalfWidth - kSidewalkWidth;
        const Rect r = corridor_rect(ctx.corridors[i], s0, s1, q0, q0 + kSidewalkWidth);
        bool ok = min_sample_distance(ctx, r) >= kSidewalkClearance;
        for (const Rect& a : ctx.asphalt) ok = ok && !overlaps(r, a);
        for (const Rect& p : placed) ok = ok && !overlaps(r, p);
        if (!ok) continue;
        placed.push_back(r);
        out.boxes.push_back(box_from_rect(r, kSidewalkHeight, BoxKind::kSidewalk));
      }
    }
  }
}

bool lot_ok(const Context& ctx, const Rect& r, const StreetLayout& out) {
  if (min_sample_distance(ctx, r) < kBuildingClearance) return false;
  for (std::size_t i = 0; i < ctx.corridors.size(); ++i) {
    Rect corridor = ctx.asphalt[i];
    corridor.min().array() -= kSidewalkWidth;
    corridor.max().array() += kSidewalkWidth;
    if (overlaps(r, corridor)) return false;
  }
  for (const SceneBox& b : out.boxes) {
    if (overlaps(r, box_rect(b))) return false;
  }
  return true;
}

void place_buildings(const SceneOptions& o, const std::vector<Vec3d>& keep_clear, Context& ctx,
                     SequenceRng& rng, StreetLayout& out) {
  const double corridor = kRoadHalfWidth + kSidewalkWidth;
  for (std::size_t i = 0; i < ctx.corridors.size(); ++i) {
    for (const int side : {1, -1}) {
      const auto [lo, hi] = side_range(ctx, i, side, true);
      double s = lo;
      while (hi - s >= 10.0) {
        const double width = std::min(rng.uniform(10.0, 35.0), hi - s);
        const double gap = rng.uniform(0.0, 6.0);
        const double setback = rng.uniform(0.0, 5.0);
        const double depth = rng.uniform(10.0, 25.0);
        const double height = rng.uniform(8.0, 45.0);
        const double q0 = corridor + setback;
        const Rect r = side > 0 ? corridor_rect(ctx.corridors[i], s, s + width, q0, q0 + depth)
                                : corridor_rect(ctx.corridors[i], s, s + width, -q0 - depth, -q0);
        s += width + gap;
        if (!lot_ok(ctx, r, out)) continue;
        const SceneBox b = box_from_rect(r, height, BoxKind::kBuilding);
        if (!keeps_clear(b, keep_clear, o.clearance_m)) continue;
        out.buildings.push_back(static_cast<int>(out.boxes.size()));
        out.boxes.push_back(b);
      }
    }
  }
}

}  // namespace

StatusOr<StreetLayout> layout_street(const SceneOptions& o, const std::vector<StreetLeg>& legs,
                                     const std::vector<Vec3d>& keep_clear, std::uint64_t seed) {
  MRVS_RETURN_IF_ERROR(validate_legs(legs));
  StreetLayout out;
  out.legs = legs;
  Context ctx;
  build_streets(legs, keep_clear, ctx, out);
  place_sidewalks(ctx, out);
  SequenceRng rng(seed, Stream::kScene);
  place_buildings(o, keep_clear, ctx, rng, out);
  MRVS_RETURN_IF_ERROR(assign_object_flags(o, out.buildings, out.boxes, seed));
  Rect ground;
  for (const Rect& a : ctx.asphalt) ground.extend(a);
  for (const SceneBox& b : out.boxes) ground.extend(box_rect(b));
  ground.min().array() -= kGroundMargin;
  ground.max().array() += kGroundMargin;
  for (int a = 0; a < 2; ++a) {
    ground.min()[a] = static_cast<float>(ground.min()[a]);
    ground.max()[a] = static_cast<float>(ground.max()[a]);
  }
  out.ground = ground;
  out.corridors = ctx.corridors;
  return out;
}

}  // namespace detail
}  // namespace mrvs::sim
