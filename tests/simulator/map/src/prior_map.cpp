// Surface-mode prior-map sampling (simulator.md section 5).
//
// Pipeline: (1) split every in-map face into tiles of about tile_size_m and give each tile
// its spacing from the distance of its centre to the trajectory; (2) per tile, draw one
// jittered sample per cell and keep it when a station sees it (parallel over tiles, each
// tile writes only its own list); (3) choose holes (sequential, by a seeded order);
// (4) write points at prefix-sum offsets (parallel, disjoint ranges). Randomness is keyed
// by (face, tile, cell), so the output does not depend on the thread count.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "mrvs/geometry/angles.h"
#include "mrvs/geometry/so3.h"
#include "mrvs/sim/prior_map.h"
#include "mrvs/sim/rng.h"

namespace mrvs::sim {
namespace {

constexpr std::int64_t kMaxSamples = 200'000'000;
/// The shadow ray ends this far in front of the sample (along the face normal).
constexpr double kShadowEpsilonM = 1e-3;

/// A face with unit axes.
struct FaceFrame {
  Vec3d origin = Vec3d::Zero();
  Vec3d axis_u = Vec3d::UnitX();
  Vec3d axis_v = Vec3d::UnitY();
  Vec3d normal = Vec3d::UnitZ();

  Vec3d point(double u, double v) const { return origin + u * axis_u + v * axis_v; }
};

/// One sampling tile of a face: a rectangle [u0, u0 + size_u] x [v0, v0 + size_v] (metres)
/// covered by nu x nv cells of one jittered sample each.
struct Tile {
  int face = -1;
  int index = 0;  ///< ty * tiles_u + tx within the face
  double u0 = 0.0;
  double v0 = 0.0;
  double size_u = 0.0;
  double size_v = 0.0;
  int nu = 1;
  int nv = 1;

  double cell_u() const { return size_u / nu; }
  double cell_v() const { return size_v / nv; }
  double cell_area() const { return cell_u() * cell_v(); }
  std::int64_t cells() const { return static_cast<std::int64_t>(nu) * nv; }
};

/// A sample that a station sees: its cell in the tile and the index of the station.
struct KeptCell {
  std::int32_t cell = 0;
  std::int32_t station = 0;
};

std::vector<FaceFrame> face_frames(const Scene& scene) {
  std::vector<FaceFrame> frames;
  frames.reserve(scene.faces().size());
  for (const Face& f : scene.faces()) {
    FaceFrame fr;
    fr.origin = f.origin;
    fr.axis_u = f.axis_u.normalized();
    fr.axis_v = f.axis_v.normalized();
    fr.normal = f.normal.normalized();
    frames.push_back(fr);
  }
  return frames;
}

/// Tiles along one side of a face.
std::int64_t tiles_along(double size, double tile_size) {
  return std::max<std::int64_t>(1, std::llround(size / tile_size));
}

/// Tiles of every in-map face with their spacing and cell counts.
/// Scanner model: the spacing the densest station's angular lattice gives at a tile centre,
/// r * step / sqrt(cos(incidence)) (the same area per return), clamped to
/// [scan_min_spacing_m, spacing_far_m]; spacing_far_m when no station faces it in range.
double scanner_spacing(const MapOptions& o, const FaceFrame& fr, const Vec3d& centre,
                       const std::vector<SurveyStation>& stations) {
  double best = o.spacing_far_m;
  for (const SurveyStation& s : stations) {
    const Vec3d to_station = s.position_w - centre;
    const double r = to_station.norm();
    const double cos_incidence = fr.normal.dot(to_station) / std::max(r, 1e-12);
    if (!s.used || cos_incidence <= 0.0 || (o.station_max_range_m > 0.0 && r > o.station_max_range_m))
      continue;
    best = std::min(best, 1e-3 * o.scan_step_mrad * r / std::sqrt(std::max(cos_incidence, 0.1)));
  }
  return std::clamp(best, std::min(o.scan_min_spacing_m, o.spacing_far_m), o.spacing_far_m);
}

StatusOr<std::vector<Tile>> make_tiles(const Scene& scene, const std::vector<FaceFrame>& frames,
                                       const MapOptions& options, const std::vector<Vec3d>& trajectory_w,
                                       const std::vector<SurveyStation>& stations) {
  const std::vector<Face>& faces = scene.faces();
  std::int64_t count = 0;
  for (const Face& f : faces) {
    if (f.in_map && f.size_u > 0.0 && f.size_v > 0.0) {
      count += tiles_along(f.size_u, options.tile_size_m) * tiles_along(f.size_v, options.tile_size_m);
    }
  }
  if (count > kMaxSamples) {
    return absl::ResourceExhaustedError(fmt::format(
        "sample_prior_map: {} tiles exceed the limit of {}; increase tile_size_m", count, kMaxSamples));
  }
  std::vector<Tile> tiles;
  tiles.reserve(static_cast<std::size_t>(count));
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const Face& f = faces[i];
    if (!f.in_map || !(f.size_u > 0.0) || !(f.size_v > 0.0)) continue;
    const auto ntu = static_cast<int>(tiles_along(f.size_u, options.tile_size_m));
    const auto ntv = static_cast<int>(tiles_along(f.size_v, options.tile_size_m));
    for (int ty = 0; ty < ntv; ++ty) {
      for (int tx = 0; tx < ntu; ++tx) {
        Tile t;
        t.face = static_cast<int>(i);
        t.index = ty * ntu + tx;
        t.size_u = f.size_u / ntu;
        t.size_v = f.size_v / ntv;
        t.u0 = tx * t.size_u;
        t.v0 = ty * t.size_v;
        tiles.push_back(t);
      }
    }
  }
  const std::vector<Vec3d> thinned = thin_path(trajectory_w, 0.25 * options.tile_size_m);
  const auto n = static_cast<std::int64_t>(tiles.size());
#pragma omp parallel for schedule(static)
  for (std::int64_t k = 0; k < n; ++k) {
    Tile& t = tiles[static_cast<std::size_t>(k)];
    const Vec3d centre =
        frames[static_cast<std::size_t>(t.face)].point(t.u0 + 0.5 * t.size_u, t.v0 + 0.5 * t.size_v);
    const FaceFrame& fr = frames[static_cast<std::size_t>(t.face)];
    const double spacing = options.model == MapModel::kScanner
                               ? scanner_spacing(options, fr, centre, stations)
                               : tile_spacing(options, distance_to_path(thinned, centre), centre.z());
    t.nu = static_cast<int>(std::max(1L, std::lround(t.size_u / spacing)));
    t.nv = static_cast<int>(std::max(1L, std::lround(t.size_v / spacing)));
  }
  return tiles;
}

/// Jittered sample of `cell` of `tile`: (u, v) on the face, metres (Stream::kMapSampling).
Eigen::Vector2d cell_sample(const Tile& t, std::int32_t cell, const CounterRng& jitter) {
  const int cu = cell % t.nu;
  const int cv = cell / t.nu;
  const auto face = static_cast<std::uint64_t>(t.face);
  const auto tile = static_cast<std::uint64_t>(t.index);
  const std::uint64_t key = 2 * static_cast<std::uint64_t>(cell);
  return {t.u0 + (cu + jitter.uniform(face, tile, key)) * t.cell_u(),
          t.v0 + (cv + jitter.uniform(face, tile, key + 1)) * t.cell_v()};
}

/// True when the station at `station` sees the point `p` of the face with unit normal `n`
/// (within range and unblocked). The shadow ray ends kShadowEpsilonM in front of the face,
/// so the face itself never blocks it while a face in contact (a box standing on the floor)
/// still does.
bool station_sees(const Scene& scene, const Vec3d& station, const Vec3d& p, const Vec3d& n,
                  double max_range) {
  if (max_range > 0.0 && (station - p).norm() > max_range) return false;
  const Vec3d target = p + kShadowEpsilonM * n;
  return !scene.occluded(station.cast<float>(), target.cast<float>(), Visibility::kSurvey);
}

/// Per face: the usable stations on the front side of the face.
std::vector<std::vector<int>> facing_stations(const Scene& scene, const std::vector<FaceFrame>& frames,
                                              const std::vector<SurveyStation>& stations) {
  std::vector<std::vector<int>> facing(frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) {
    if (!scene.faces()[i].in_map) continue;
    for (std::size_t s = 0; s < stations.size(); ++s) {
      if (stations[s].used && (stations[s].position_w - frames[i].origin).dot(frames[i].normal) > 0.0) {
        facing[i].push_back(static_cast<int>(s));
      }
    }
  }
  return facing;
}

/// The stations worth trying for a tile, nearest to its centre first.
std::vector<int> tile_station_order(const Tile& t, const FaceFrame& fr, const std::vector<int>& facing,
                                    const std::vector<SurveyStation>& stations, double max_range) {
  const Vec3d centre = fr.point(t.u0 + 0.5 * t.size_u, t.v0 + 0.5 * t.size_v);
  const double half_diagonal = 0.5 * std::hypot(t.size_u, t.size_v);
  std::vector<std::pair<double, int>> by_distance;
  for (int s : facing) {
    const double d = (stations[static_cast<std::size_t>(s)].position_w - centre).norm();
    if (max_range > 0.0 && d > max_range + half_diagonal) continue;
    by_distance.emplace_back(d, s);
  }
  std::sort(by_distance.begin(), by_distance.end());
  std::vector<int> order;
  order.reserve(by_distance.size());
  for (const auto& entry : by_distance) order.push_back(entry.second);
  return order;
}

/// Scanner model: true when station `s` at `station` gets a return from p (incidence
/// dropout, drawn per sample and station; nothing below scan_min_elevation_deg).
bool scanner_returns(const MapOptions& o, const Vec3d& station, const Vec3d& p, const Vec3d& n,
                     const CounterRng& jitter, const Tile& t, std::int32_t cell, int s) {
  const Vec3d d = p - station;
  const double r = d.norm();
  if (!(r > 0.0) || d.z() < r * std::sin(o.scan_min_elevation_deg * kPi / 180.0)) return false;
  const double cos_incidence = std::abs(n.dot(d)) / r;
  const double start = std::cos(o.dropout_start_deg * kPi / 180.0),
               full = std::cos(o.dropout_full_deg * kPi / 180.0);
  if (cos_incidence >= start) return true;
  const double keep = start > full ? (cos_incidence - full) / (start - full) : 0.0;
  const auto tile_station =
      (static_cast<std::uint64_t>(t.index) << 20) ^ static_cast<std::uint64_t>(s) ^ (1ULL << 62);
  return jitter.uniform(static_cast<std::uint64_t>(t.face), tile_station, static_cast<std::uint64_t>(cell)) <
         keep;
}

/// Draws every cell of one tile and keeps the samples some station sees (the nearest that
/// does; with the scanner model, the nearest that also gets a return).
std::vector<KeptCell> scan_tile(const Scene& scene, const Tile& t, const FaceFrame& fr,
                                const std::vector<int>& station_order,
                                const std::vector<SurveyStation>& stations, const MapOptions& o,
                                const CounterRng& jitter) {
  std::vector<KeptCell> kept;
  if (station_order.empty()) return kept;
  const bool scanner = o.model == MapModel::kScanner;
  const auto cells = static_cast<std::int32_t>(t.cells());
  for (std::int32_t c = 0; c < cells; ++c) {
    const Eigen::Vector2d uv = cell_sample(t, c, jitter);
    const Vec3d p = fr.point(uv.x(), uv.y());
    for (int s : station_order) {
      const Vec3d& station = stations[static_cast<std::size_t>(s)].position_w;
      if (scanner && !scanner_returns(o, station, p, fr.normal, jitter, t, c, s)) continue;
      if (station_sees(scene, station, p, fr.normal, o.station_max_range_m)) {
        kept.push_back({c, s});
        break;
      }
    }
  }
  return kept;
}

/// Kept samples of every tile (parallel over tiles; each writes only its own list).
std::vector<std::vector<KeptCell>> scan_tiles(const Scene& scene, const std::vector<FaceFrame>& frames,
                                              const std::vector<Tile>& tiles,
                                              const std::vector<SurveyStation>& stations,
                                              const MapOptions& options, std::uint64_t seed) {
  const std::vector<std::vector<int>> facing = facing_stations(scene, frames, stations);
  const CounterRng jitter(seed, Stream::kMapSampling);
  std::vector<std::vector<KeptCell>> kept(tiles.size());
  const auto n = static_cast<std::int64_t>(tiles.size());
#pragma omp parallel for schedule(dynamic, 4)
  for (std::int64_t k = 0; k < n; ++k) {
    const Tile& t = tiles[static_cast<std::size_t>(k)];
    const FaceFrame& fr = frames[static_cast<std::size_t>(t.face)];
    const std::vector<int> order = tile_station_order(t, fr, facing[static_cast<std::size_t>(t.face)],
                                                      stations, options.station_max_range_m);
    kept[static_cast<std::size_t>(k)] = scan_tile(scene, t, fr, order, stations, options, jitter);
  }
  return kept;
}

/// Per tile: true when a hole removes it. Units (tiles, or whole faces) are visited in a
/// seeded random order (Stream::kMapHoles); a unit is removed when the removed visible area
/// stays within holes_fraction x the total visible area, so the share is met from below to
/// within about one small unit.
std::vector<char> choose_holes(const std::vector<Tile>& tiles, const std::vector<double>& visible_area,
                               const MapOptions& options, std::uint64_t seed) {
  std::vector<char> removed(tiles.size(), 0);
  if (options.holes_fraction <= 0.0) return removed;
  const bool by_face = options.holes_mode == HoleMode::kFaces;
  // unit id -> tiles; for faces the unit is the face index, for tiles the tile index.
  std::vector<std::vector<std::size_t>> unit_tiles;
  std::vector<std::uint64_t> unit_key;
  const CounterRng rng(seed, Stream::kMapHoles);
  for (std::size_t k = 0; k < tiles.size(); ++k) {
    const auto face = static_cast<std::uint64_t>(tiles[k].face);
    if (!by_face || k == 0 || tiles[k].face != tiles[k - 1].face) {
      unit_tiles.emplace_back();
      unit_key.push_back(by_face ? rng.bits(face, 0, 1)
                                 : rng.bits(face, static_cast<std::uint64_t>(tiles[k].index)));
    }
    unit_tiles.back().push_back(k);
  }
  std::vector<std::size_t> order(unit_tiles.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return std::make_pair(unit_key[a], a) < std::make_pair(unit_key[b], b);
  });
  const double target =
      options.holes_fraction * std::accumulate(visible_area.begin(), visible_area.end(), 0.0);
  double area_removed = 0.0;
  for (std::size_t u : order) {
    double area = 0.0;
    for (std::size_t k : unit_tiles[u]) area += visible_area[k];
    if (area <= 0.0 || area_removed + area > target * (1.0 + 1e-12)) continue;
    area_removed += area;
    for (std::size_t k : unit_tiles[u]) removed[k] = 1;
  }
  return removed;
}

/// Everything the point writer needs besides the tile.
struct EmitContext {
  const Scene* scene = nullptr;
  const std::vector<FaceFrame>* frames = nullptr;
  const std::vector<SurveyStation>* stations = nullptr;
  const MapOptions* options = nullptr;
  CounterRng jitter{0, Stream::kMapSampling};
  CounterRng noise{0, Stream::kMapNoise};
  SE3d T_map_world;
};

/// Writes the points of one tile to out[0..kept.size()) and clean[0..kept.size()).
void emit_tile(const EmitContext& ctx, const Tile& t, const std::vector<KeptCell>& kept, MapPoint* out,
               MapPoint* clean) {
  const FaceFrame& fr = (*ctx.frames)[static_cast<std::size_t>(t.face)];
  const MapOptions& o = *ctx.options;
  const auto face = static_cast<std::uint64_t>(t.face);
  const auto tile = static_cast<std::uint64_t>(t.index);
  for (std::size_t i = 0; i < kept.size(); ++i) {
    const Eigen::Vector2d uv = cell_sample(t, kept[i].cell, ctx.jitter);
    const Vec3d p = fr.point(uv.x(), uv.y());
    const Vec3d to_station = (*ctx.stations)[static_cast<std::size_t>(kept[i].station)].position_w - p;
    const double cos_incidence = std::abs(fr.normal.dot(to_station)) / std::max(to_station.norm(), 1e-12);
    const double albedo =
        ctx.scene->albedo(t.face, static_cast<float>(uv.x()), static_cast<float>(uv.y()), 0.0f);
    const double intensity = model_intensity(o, albedo, cos_incidence);
    const std::uint64_t key = 4 * static_cast<std::uint64_t>(kept[i].cell);
    auto draw = [&](double sigma, std::uint64_t k) {
      return sigma > 0.0 ? sigma * ctx.noise.normal(face, tile, k) : 0.0;
    };
    const double range = to_station.norm();
    const Vec3d noisy = o.model == MapModel::kScanner
                            ? Vec3d(p - to_station / std::max(range, 1e-12) *
                                            draw(o.range_noise_m + o.range_noise_per_m * range, key))
                            : Vec3d(p + fr.normal * draw(o.noise_normal_sigma_m, key) +
                                    fr.axis_u * draw(o.noise_tangent_sigma_m, key + 1) +
                                    fr.axis_v * draw(o.noise_tangent_sigma_m, key + 2));
    const double noisy_intensity = intensity + draw(o.intensity_noise_sigma, key + 3);
    clean[i].position = p.cast<float>();
    clean[i].intensity = static_cast<float>(std::clamp(intensity, 0.0, 1.0));
    clean[i].face = t.face;
    out[i].position = (ctx.T_map_world * noisy).cast<float>();
    out[i].intensity = static_cast<float>(std::clamp(noisy_intensity, 0.0, 1.0));
    out[i].face = t.face;
  }
}

Status check_inputs(const std::vector<Vec3d>& trajectory_w, const MapOptions& options) {
  if (trajectory_w.empty()) return absl::InvalidArgumentError("sample_prior_map: empty trajectory");
  for (const Vec3d& p : trajectory_w) {
    if (!p.allFinite()) return absl::InvalidArgumentError("sample_prior_map: non-finite trajectory position");
  }
  const Status valid = config::validate_options(options, "map");
  if (!valid.ok()) {
    return absl::InvalidArgumentError(
        fmt::format("sample_prior_map: invalid options: {}", std::string(valid.message())));
  }
  if (options.spacing_far_m < options.spacing_near_m) {
    return absl::InvalidArgumentError(fmt::format("sample_prior_map: spacing_far_m {} < spacing_near_m {}",
                                                  options.spacing_far_m, options.spacing_near_m));
  }
  return absl::OkStatus();
}

Status check_size(const std::vector<Tile>& tiles) {
  std::int64_t samples = 0;
  for (const Tile& t : tiles) samples += t.cells();
  if (samples > kMaxSamples) {
    return absl::ResourceExhaustedError(fmt::format(
        "sample_prior_map: {} samples exceed the limit of {}; increase the spacing", samples, kMaxSamples));
  }
  return absl::OkStatus();
}

/// Steps (3) and (4): holes, then the points of the remaining tiles at prefix-sum offsets.
void emit_points(const EmitContext& ctx, const std::vector<Tile>& tiles,
                 const std::vector<std::vector<KeptCell>>& kept, std::uint64_t seed, PriorMap& map) {
  std::vector<double> visible_area(tiles.size());
  for (std::size_t k = 0; k < tiles.size(); ++k) {
    visible_area[k] = static_cast<double>(kept[k].size()) * tiles[k].cell_area();
    map.counts.in_map_area_m2 += tiles[k].size_u * tiles[k].size_v;
    map.counts.samples += tiles[k].cells();
    map.counts.visible += static_cast<std::int64_t>(kept[k].size());
    map.counts.visible_area_m2 += visible_area[k];
  }
  const std::vector<char> removed = choose_holes(tiles, visible_area, *ctx.options, seed);
  std::vector<std::size_t> offset(tiles.size() + 1, 0);
  for (std::size_t k = 0; k < tiles.size(); ++k) {
    offset[k + 1] = offset[k] + (removed[k] ? 0 : kept[k].size());
    if (removed[k]) {
      map.counts.hole_removed += static_cast<std::int64_t>(kept[k].size());
      map.counts.hole_area_m2 += visible_area[k];
    }
  }
  map.points.resize(offset.back());
  map.clean_points.resize(offset.back());
  const auto n = static_cast<std::int64_t>(tiles.size());
#pragma omp parallel for schedule(dynamic, 4)
  for (std::int64_t k = 0; k < n; ++k) {
    const auto i = static_cast<std::size_t>(k);
    if (removed[i]) continue;
    emit_tile(ctx, tiles[i], kept[i], map.points.data() + offset[i], map.clean_points.data() + offset[i]);
  }
  map.counts.tiles = static_cast<std::int64_t>(tiles.size());
  map.counts.points = static_cast<std::int64_t>(map.points.size());
}

}  // namespace

SE3d map_misalignment(const MapOptions& options, std::uint64_t seed) {
  if (options.misalignment_deg == 0.0 && options.misalignment_m == 0.0) return SE3d();
  const CounterRng rng(seed, Stream::kMisalignment);
  Vec3d axis(rng.normal(0), rng.normal(1), rng.normal(2));
  Vec3d direction(rng.normal(3), rng.normal(4), rng.normal(5));
  axis.normalize();
  direction.normalize();
  const Vec3d phi = axis * (options.misalignment_deg * kPi / 180.0);
  return SE3d(so3::exp_quat<double>(phi), direction * options.misalignment_m);
}

StatusOr<PriorMap> sample_prior_map(const Scene& scene, const std::vector<Vec3d>& trajectory_w,
                                    const MapOptions& options, std::uint64_t seed) {
  MRVS_RETURN_IF_ERROR(check_inputs(trajectory_w, options));
  PriorMap map;
  MRVS_ASSIGN_OR_RETURN(map.stations, survey_stations(scene, trajectory_w, options));
  for (const SurveyStation& s : map.stations) map.counts.stations_used += s.used ? 1 : 0;
  const std::vector<FaceFrame> frames = face_frames(scene);
  MRVS_ASSIGN_OR_RETURN(const std::vector<Tile> tiles,
                        make_tiles(scene, frames, options, trajectory_w, map.stations));
  MRVS_RETURN_IF_ERROR(check_size(tiles));
  const std::vector<std::vector<KeptCell>> kept =
      scan_tiles(scene, frames, tiles, map.stations, options, seed);

  map.T_map_world = map_misalignment(options, seed);
  EmitContext ctx;
  ctx.scene = &scene;
  ctx.frames = &frames;
  ctx.stations = &map.stations;
  ctx.options = &options;
  ctx.jitter = CounterRng(seed, Stream::kMapSampling);
  ctx.noise = CounterRng(seed, Stream::kMapNoise);
  ctx.T_map_world = map.T_map_world;
  emit_points(ctx, tiles, kept, seed, map);
  return map;
}

}  // namespace mrvs::sim
