#include "vio_test_world.h"

#include <map>
#include <random>
#include <tuple>

#include <gtest/gtest.h>

#include "mrvs/config/options.h"
#include "mrvs/eval/trajectory_eval.h"
#include "mrvs/io/trajectory_io.h"
#include "mrvs/map/map_builder.h"
#include "mrvs/map/query_engine.h"
#include "mrvs/test/shared_data.h"

namespace mrvs::edge::test {
namespace {

struct Landmarks {
  std::vector<Vec3d> p_w;
};

/// Every observation of landmark j at frame k, or nullopt when not seen in cam0.
std::optional<FeatureObservation> observe(const sim::World& w, std::size_t k, const Vec3d& p_w, double noise,
                                          std::mt19937_64* rng) {
  std::normal_distribution<double> n(0.0, noise);
  FeatureObservation o;
  for (int c = 0; c < 2; ++c) {
    const auto& cam = w.calibration.cameras[static_cast<std::size_t>(c)];
    const SE3d T_c_w = (w.frame_pose(k) * cam.T_b_c).inverse();
    const auto uv = cam.model->project(T_c_w * p_w, nullptr, 0.3);
    if (!uv || !cam.model->in_image(*uv, 10.0)) {
      if (c == 0) return std::nullopt;
      continue;
    }
    const Vec2d noisy = *uv + Vec2d(n(*rng), n(*rng));
    const auto xn = cam.model->undistort(noisy);
    if (!xn.ok()) {
      if (c == 0) return std::nullopt;
      continue;
    }
    if (c == 0) {
      o.uv_left = noisy, o.xn_left = *xn;
    } else {
      o.stereo = true, o.uv_right = noisy, o.xn_right = *xn;
    }
  }
  return o;
}

/// Frames with at most max_features tracks: alive tracks go on, new ones fill up (spread by
/// a random order of the landmarks).
std::vector<FeatureFrame> make_frames(const sim::World& w, const Landmarks& lm, const SyntheticOptions& o) {
  std::mt19937_64 rng(static_cast<std::uint64_t>(o.seed));
  std::vector<std::size_t> order(lm.p_w.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), rng);
  std::map<std::size_t, FeatureId> alive;    // landmark -> track id
  std::map<FeatureId, Vec2d> offset, slide;  // per track: accumulated drift, its steady slide
  std::normal_distribution<double> walk(0.0, 1.0);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  FeatureId next_id = 1;
  std::vector<FeatureFrame> frames;
  for (std::size_t k = 0; k < w.grid.camera_stamp_ns.size(); ++k) {
    FeatureFrame f;
    f.t_ns = w.grid.camera_stamp_ns[k];
    std::map<std::size_t, FeatureId> now;
    for (const auto& [j, id] : alive) {
      auto obs = observe(w, k, lm.p_w[j], o.pixel_noise, &rng);
      if (!obs) continue;
      obs->id = id;
      // (Eigen vectors are not zeroed by std::map::operator[]: insert zeros explicitly.)
      Vec2d& off = offset.try_emplace(id, Vec2d::Zero()).first->second;
      off += o.drift_px * Vec2d(walk(rng), walk(rng)) + slide.try_emplace(id, Vec2d::Zero()).first->second;
      obs->uv_left += off;
      const auto xn = w.calibration.cameras[0].model->undistort(obs->uv_left);
      if (!xn.ok()) continue;
      obs->xn_left = *xn;
      f.features.push_back(*obs);
      now[j] = id;
    }
    for (std::size_t j : order) {
      if (static_cast<int>(f.features.size()) >= o.max_features) break;
      if (now.count(j) != 0) continue;
      auto obs = observe(w, k, lm.p_w[j], o.pixel_noise, &rng);
      if (!obs) continue;
      obs->id = next_id++;
      if (u01(rng) < o.sliding_fraction) {
        const double a = 2.0 * M_PI * u01(rng);
        slide[obs->id] = o.sliding_px * Vec2d(std::cos(a), std::sin(a));
      }
      f.features.push_back(*obs);
      now[j] = obs->id;
    }
    alive = std::move(now);
    frames.push_back(std::move(f));
  }
  return frames;
}

std::unique_ptr<SyntheticSequence> build(const SyntheticOptions& o) {
  sim::GeneratorRequest r;
  r.trajectory = mrvs::test::euroc_groundtruth_file(o.trajectory);
  r.preset = o.preset;
  r.options = sim::default_options(sim::SceneProfile::kIndoor);
  EXPECT_TRUE(sim::apply_preset(o.preset, sim::SceneProfile::kIndoor, r.options).ok());
  r.options.trajectory.window_start_s = o.start_s;
  r.options.trajectory.window_duration_s = o.duration_s;
  r.options.map.spacing_near_m = r.options.map.spacing_far_m = o.map_spacing_m;
  auto world = sim::build_world(r);
  EXPECT_TRUE(world.ok()) << world.status();
  if (!world.ok()) return nullptr;
  auto seq = std::make_unique<SyntheticSequence>();
  seq->options = o;
  seq->world = std::move(*world);
  Landmarks lm;
  // About 10 000 landmarks, whatever the survey density.
  const std::size_t step = std::max<std::size_t>(1, seq->world.map.clean_points.size() / 10000);
  for (std::size_t i = 0; i < seq->world.map.clean_points.size(); i += step) {
    lm.p_w.push_back(seq->world.map.clean_points[i].position.cast<double>());
  }
  seq->frames = make_frames(seq->world, lm, o);
  for (const auto& s : seq->world.imu) seq->imu.push_back(s.measured);
  seq->groundtruth = io::to_trajectory(seq->world.states);
  return seq;
}

}  // namespace

const SyntheticSequence* synthetic_sequence(const SyntheticOptions& o) {
  static std::map<
      std::tuple<std::string, double, double, std::string, double, int, int, double, double, double>,
      std::unique_ptr<SyntheticSequence>>
      cache;
  const auto key = std::make_tuple(o.trajectory, o.start_s, o.duration_s, o.preset, o.pixel_noise,
                                   o.max_features, o.seed, o.drift_px, o.sliding_fraction, o.sliding_px);
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(key, build(o)).first;
  return it->second.get();
}

struct LocalMapService::Impl {
  std::shared_ptr<const map::VoxelMap> map;
  std::optional<map::QueryEngine> engine;
};

std::unique_ptr<LocalMapService> LocalMapService::create(const SyntheticSequence& seq, bool refine) {
  map::RawCloud cloud;
  for (const auto& p : seq.world.map.points) {
    cloud.positions.push_back(p.position.cast<double>());
    cloud.intensities.push_back(p.intensity);
  }
  map::MapBuilderOptions builder;
  auto vm = map::build_voxel_map(cloud, builder);
  EXPECT_TRUE(vm.ok()) << vm.status();
  if (!vm.ok()) return nullptr;
  auto out = std::make_unique<LocalMapService>();
  out->impl_ = std::make_shared<Impl>();
  out->impl_->map = std::make_shared<const map::VoxelMap>(std::move(*vm));
  map::QueryOptions q;
  q.refine_plane_intersection = refine;
  auto engine = map::QueryEngine::create(out->impl_->map, q);
  EXPECT_TRUE(engine.ok()) << engine.status();
  if (!engine.ok()) return nullptr;
  out->impl_->engine.emplace(std::move(*engine));
  return out;
}

std::optional<MapDescription> LocalMapService::description() {
  if (!announced) return std::nullopt;
  return MapDescription{impl_->map->origin, impl_->map->resolutions(), 1};
}

MapReply LocalMapService::query(const std::vector<voxel::RayQuery>& batch, TimestampNs, DurationNs timeout,
                                bool want_normals) {
  MapReply reply;
  ++queries;
  rays += static_cast<int>(batch.size());
  if (!answer) {
    reply.rtt_ns = timeout;
    reply.failure = "outage";
    return reply;
  }
  reply.answered = true;
  for (const voxel::RayQuery& r : batch) {
    const map::QueryResult q = impl_->engine->query(r);
    voxel::RayHit hit{q.status == map::QueryStatus::kHit, q.point};
    if (hit.hit && want_normals) {
      if (const auto n = impl_->engine->surface_normal(q.level, q.point)) hit.normal = *n;
    }
    reply.hits.push_back(hit);
  }
  return reply;
}

EstimatorOptions euroc_estimator_options() {
  auto o = config::load_options_file<EstimatorOptions>(std::filesystem::path(MRVS_CONFIG_DIR) / "euroc.yaml",
                                                       "estimator");
  EXPECT_TRUE(o.ok()) << o.status();
  EstimatorOptions out = o.ok() ? *o : EstimatorOptions{};
  // The paper's protocol (the ablation gt_noisy): these tests compare trajectories in the map
  // frame from the first frame on; the cloud's localisation has tests of its own.
  out.alignment.source = "gt_noisy";
  return out;
}

io::Trajectory run_estimator(const SyntheticSequence& seq, const EstimatorOptions& options, int* skipped,
                             MapService* map, std::vector<FrameOutput>* outputs) {
  io::Trajectory out;
  auto vio = VioEstimator::create(options, seq.world.calibration, seq.groundtruth);
  EXPECT_TRUE(vio.ok()) << vio.status();
  if (!vio.ok()) return out;
  vio->set_map_service(map);
  std::size_t next = 0;
  int skip = 0;
  for (const FeatureFrame& f : seq.frames) {
    while (next < seq.imu.size()) {
      EXPECT_TRUE(vio->feed_imu(seq.imu[next]).ok());
      if (seq.imu[next++].t_ns >= f.t_ns) break;
    }
    auto r = vio->feed_frame(f);
    if (!r.ok()) {
      ++skip;
      continue;
    }
    if (r->T_w_b) out.push_back({r->t_imu_ns, *r->T_w_b});
    if (outputs != nullptr) outputs->push_back(*r);
  }
  if (skipped != nullptr) *skipped = skip;
  return out;
}

double ate_rmse(const SyntheticSequence& seq, const io::Trajectory& estimate, bool se3_aligned) {
  auto assoc = eval::associate(estimate, seq.groundtruth, eval::AssociationOptions{});
  if (!assoc.ok()) return 1e9;
  eval::Alignment identity;
  auto alignment =
      se3_aligned ? eval::align(*assoc, eval::AlignmentMethod::kSE3) : StatusOr<eval::Alignment>(identity);
  if (!alignment.ok()) return 1e9;
  auto ate = eval::compute_ate(*assoc, *alignment);
  return ate.ok() ? ate->position_m.rmse : 1e9;
}

}  // namespace mrvs::edge::test
