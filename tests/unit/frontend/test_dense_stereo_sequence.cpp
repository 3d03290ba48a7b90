// Dense stereo against the scene on a generated realistic indoor sequence (V1_01 from 40 s for
// 8 s, EuRoC rig, written once per build tree): the points of 8 frames 1 s apart, moved into
// the world with the ground truth T_w_b * T_b_c0, lie on the prior map (the survey of the same
// scene: 1 cm spacing near the trajectory, 2 cm beyond, 3 mm noise, holes and unmapped objects
// as the preset makes them). A 3 % wrong baseline must fail the same check.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iterator>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "mrvs/config/calibration.h"
#include "mrvs/core/stats.h"
#include "mrvs/edge/dense_stereo.h"
#include "mrvs/eval/trajectory_eval.h"
#include "mrvs/io/dataset.h"
#include "mrvs/sim/calibration_error.h"
#include "mrvs/sim/map_io.h"
#include "mrvs/test/generated_sequence.h"

namespace mrvs::edge {
namespace {

/// Distance to the nearest map point, exact up to `cell_m` (a hash of cells of that size,
/// searched over the 27 cells around the query); `cell_m` when no point is that close.
class NearestMapPoint {
 public:
  NearestMapPoint(const std::vector<sim::MapPoint>& points, double cell_m) : cell_(cell_m) {
    for (const sim::MapPoint& p : points) cells_[key(cell_of(p.position))].push_back(p.position);
  }

  double distance(const Eigen::Vector3f& q) const {
    const Eigen::Vector3i c = cell_of(q);
    double best2 = cell_ * cell_;
    for (int dx = -1; dx <= 1; ++dx) {
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = cells_.find(key(c + Eigen::Vector3i(dx, dy, dz)));
          if (it == cells_.end()) continue;
          for (const Eigen::Vector3f& p : it->second)
            best2 = std::min(best2, static_cast<double>((p - q).squaredNorm()));
        }
      }
    }
    return std::sqrt(best2);
  }

 private:
  Eigen::Vector3i cell_of(const Eigen::Vector3f& p) const {
    return (p.cast<double>() / cell_).array().floor().cast<int>();
  }
  static std::int64_t key(const Eigen::Vector3i& c) {
    return (static_cast<std::int64_t>(c.x() & 0x1FFFFF) << 42) |
           (static_cast<std::int64_t>(c.y() & 0x1FFFFF) << 21) | static_cast<std::int64_t>(c.z() & 0x1FFFFF);
  }
  double cell_;
  std::unordered_map<std::int64_t, std::vector<Eigen::Vector3f>> cells_;
};

/// Distances above this are "not on the map" (far outliers, unmapped objects, holes).
constexpr double kCapM = 0.10;

struct Sequence {
  std::string error;  ///< non-empty when the sequence could not be prepared
  config::StereoRigCalibration rig;
  std::vector<std::array<cv::Mat, 2>> images;  ///< the test frames
  std::vector<SE3d> T_w_c0;                    ///< their ground-truth left-camera poses
  std::unique_ptr<NearestMapPoint> map;
};

/// Every `stride`-th frame of the first `frames` of the sequence.
Status load(Sequence* s, int frames, int stride) {
  sim::GeneratorRequest request =
      mrvs::test::indoor_sequence_request("V1_01_easy.txt", 40.0, 8.0, "realistic");
  sim::SimulatorOptions dense = sim::default_options(sim::SceneProfile::kIndoor);
  MRVS_RETURN_IF_ERROR(sim::apply_preset("realistic", sim::SceneProfile::kIndoor, dense));
  request.options.map = dense.map;  // the survey at the simulator's own density
  // The matcher against the map: nobody walking through the view (people are not in the map;
  // the localiser's submap leaves them out, test_map_localiser.cpp).
  request.options.people.count = 0;
  MRVS_ASSIGN_OR_RETURN(const std::filesystem::path dir,
                        mrvs::test::generated_sequence("dense_stereo_v101_40s_8s_realistic", request));
  io::DatasetOptions options;
  options.path = dir;
  MRVS_ASSIGN_OR_RETURN(std::unique_ptr<io::DatasetReader> reader, io::open_euroc_dataset(options));
  // The matcher is under test, not the calibration: the rig that rendered the images and
  // the ground truth at their true capture time (the preset's calibration error is undone).
  s->rig = reader->calibration();
  const std::filesystem::path truth = dir / "sim0/true_calibration";
  for (int c = 0; c < 2; ++c) {
    MRVS_ASSIGN_OR_RETURN(s->rig.cameras[static_cast<std::size_t>(c)],
                          config::load_euroc_camera_yaml(truth / fmt::format("cam{}/sensor.yaml", c)));
  }
  MRVS_ASSIGN_OR_RETURN(const double td_ms, sim::read_true_time_offset_ms(truth));
  const auto& gt = reader->groundtruth();
  for (int k = 0; k < frames && k < static_cast<int>(reader->stereo_frames().size()); k += stride) {
    const io::StereoFrame& f = reader->stereo_frames()[static_cast<std::size_t>(k)];
    const TimestampNs t = f.t_ns + static_cast<TimestampNs>(std::llround(td_ms * 1e6));
    const auto it = std::lower_bound(gt.begin(), gt.end(), t,
                                     [](const io::GroundTruthState& g, TimestampNs x) { return g.t_ns < x; });
    if (it == gt.begin() || it == gt.end()) return absl::NotFoundError("no ground truth around a frame");
    const auto before = std::prev(it);
    const double alpha = static_cast<double>(t - before->t_ns) / static_cast<double>(it->t_ns - before->t_ns);
    MRVS_ASSIGN_OR_RETURN(cv::Mat left, reader->load_image(0, f.left));
    MRVS_ASSIGN_OR_RETURN(cv::Mat right, reader->load_image(1, f.right));
    s->images.push_back({left, right});
    s->T_w_c0.push_back(eval::interpolate_pose(before->T_w_b, it->T_w_b, alpha) * s->rig.cameras[0].T_b_c);
  }
  MRVS_ASSIGN_OR_RETURN(const std::vector<sim::MapPoint> map,
                        sim::read_ply_xyzi(dir / "mav0/pointcloud0/data.ply"));
  s->map = std::make_unique<NearestMapPoint>(map, kCapM);
  return absl::OkStatus();
}

const Sequence& sequence() {
  static const Sequence s = [] {
    Sequence out;
    if (Status st = load(&out, 160, 20); !st.ok()) out.error = std::string(st.message());
    return out;
  }();
  return s;
}

/// Distances of the points of every test frame to the map, with their depths.
struct Errors {
  std::vector<double> distance;  ///< m, capped at kCapM
  std::vector<double> depth;     ///< z in cam0, m
  std::vector<int> per_frame;    ///< points per frame
  double ms_per_pair = 0.0;
};

Errors evaluate(const Sequence& s, const DenseStereoOptions& options,
                const config::StereoRigCalibration& rig) {
  Errors e;
  auto stereo = DenseStereo::create(options, rig);
  EXPECT_TRUE(stereo.ok()) << stereo.status();
  if (!stereo.ok()) return e;
  for (std::size_t k = 0; k < s.images.size(); ++k) {
    const auto t0 = std::chrono::steady_clock::now();
    auto points = stereo->points(s.images[k][0], s.images[k][1]);
    e.ms_per_pair += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    EXPECT_TRUE(points.ok()) << points.status();
    if (!points.ok()) return e;
    const Eigen::Matrix3f R = s.T_w_c0[k].rotation_matrix().cast<float>();
    const Eigen::Vector3f t = s.T_w_c0[k].translation().cast<float>();
    for (const Eigen::Vector3f& p : *points) {
      e.distance.push_back(s.map->distance(R * p + t));
      e.depth.push_back(p.z());
    }
    e.per_frame.push_back(static_cast<int>(points->size()));
  }
  e.ms_per_pair /= static_cast<double>(std::max<std::size_t>(1, s.images.size()));
  return e;
}

/// Quantile q of the distances of the points with depth in [lo, hi).
double quantile_in(const Errors& e, double q, double lo, double hi) {
  std::vector<double> d;
  for (std::size_t i = 0; i < e.distance.size(); ++i) {
    if (e.depth[i] >= lo && e.depth[i] < hi) d.push_back(e.distance[i]);
  }
  return quantile(d, q);
}

std::string describe(const Errors& e) {
  const double far = static_cast<double>(
      std::count_if(e.distance.begin(), e.distance.end(), [](double d) { return d >= kCapM; }));
  return fmt::format(
      "{} points ({} frames, min {}), distance to the map: median {:.1f} mm, p90 {:.1f} mm, {:.1f} % beyond "
      "{:.0f} "
      "cm; within 3 m: median {:.1f} mm, p90 {:.1f} mm; median by depth 0-1.5 / 1.5-3 / 3+ m: {:.1f} / "
      "{:.1f} / "
      "{:.1f} mm; {:.1f} ms per pair",
      e.distance.size(), e.per_frame.size(),
      e.per_frame.empty() ? 0 : *std::min_element(e.per_frame.begin(), e.per_frame.end()),
      1e3 * quantile(e.distance, 0.5), 1e3 * quantile(e.distance, 0.9), 100.0 * far / e.distance.size(),
      100 * kCapM, 1e3 * quantile_in(e, 0.5, 0.0, 3.0), 1e3 * quantile_in(e, 0.9, 0.0, 3.0),
      1e3 * quantile_in(e, 0.5, 0.0, 1.5), 1e3 * quantile_in(e, 0.5, 1.5, 3.0),
      1e3 * quantile_in(e, 0.5, 3.0, 1e9), e.ms_per_pair);
}

/// The sequence's calibration with cam1 moved along the baseline: |p_c0_c1| scaled by `scale`.
config::StereoRigCalibration with_baseline_scaled(const config::StereoRigCalibration& rig, double scale) {
  config::StereoRigCalibration out = rig;
  const SE3d T_c0_c1 = rig.T_c0_c1();
  out.cameras[1].T_b_c = rig.cameras[0].T_b_c * SE3d(T_c0_c1.quaternion(), scale * T_c0_c1.translation());
  return out;
}

// Bounds from stereo geometry: a disparity error of delta level px moves a point at depth z
// by z^2 delta / (f b) along its ray, and f b = 25.2 px m at downsample 2 (f 229 px, b 0.11 m).
// The frames see surfaces at 1-4 m (median about 2.3 m), where a tenth of a pixel is 0.4-6 cm.
// The distance to the nearest map point also holds the map's own floor (1-2 cm spacing, 3 mm
// noise: about 5 mm for an exact point). Points within 3 m with a median under 2 cm mean the
// matcher is at a tenth of a pixel or better (measured: 14 mm, p90 45 mm); a 3 % wrong
// baseline (7 cm at 2.3 m) fails it (measured: 59 mm).
constexpr double kMedianWithin3m = 0.020;
constexpr double kP90Within3m = 0.060;
constexpr double kMedianAll = 0.025;
constexpr double kP90All = 0.070;
constexpr double kOffMapShare = 0.05;  ///< points farther than kCapM: holes, unmapped boxes, mismatches
constexpr int kMinPointsPerFrame = 1000;

double off_map_share(const Errors& e) {
  const auto n = std::count_if(e.distance.begin(), e.distance.end(), [](double d) { return d >= kCapM; });
  return static_cast<double>(n) / static_cast<double>(std::max<std::size_t>(1, e.distance.size()));
}

TEST(DenseStereoSequence, PointsOfTheDefaultOptionsLieOnThePriorMap) {
  const Sequence& s = sequence();
  ASSERT_EQ(s.error, "");
  ASSERT_EQ(s.images.size(), 8u);
  const Errors e = evaluate(s, DenseStereoOptions{}, s.rig);
  ASSERT_EQ(e.per_frame.size(), s.images.size());
  std::printf("defaults: %s\n", describe(e).c_str());
  for (std::size_t k = 0; k < e.per_frame.size(); ++k)
    EXPECT_GE(e.per_frame[k], kMinPointsPerFrame) << "frame " << k;
  EXPECT_LT(quantile_in(e, 0.5, 0.0, 3.0), kMedianWithin3m);
  EXPECT_LT(quantile_in(e, 0.9, 0.0, 3.0), kP90Within3m);
  EXPECT_LT(quantile(e.distance, 0.5), kMedianAll);
  EXPECT_LT(quantile(e.distance, 0.9), kP90All);
  EXPECT_LT(off_map_share(e), kOffMapShare);
  const DenseStereoOptions o;
  for (double z : e.depth) ASSERT_TRUE(z >= o.min_depth_m && z <= o.max_depth_m) << z;
}

// The check above can fail: the same frames with a calibration whose baseline is 3 % long
// (every depth 3 % too far) break its median bound.
TEST(DenseStereoSequence, AThreePercentWrongBaselineFailsTheMapCheck) {
  const Sequence& s = sequence();
  ASSERT_EQ(s.error, "");
  const Errors e = evaluate(s, DenseStereoOptions{}, with_baseline_scaled(s.rig, 1.03));
  std::printf("baseline x 1.03: %s\n", describe(e).c_str());
  EXPECT_GT(quantile_in(e, 0.5, 0.0, 3.0), 1.5 * kMedianWithin3m);
  EXPECT_GT(quantile(e.distance, 0.5), 1.5 * kMedianAll);
}

}  // namespace
}  // namespace mrvs::edge
