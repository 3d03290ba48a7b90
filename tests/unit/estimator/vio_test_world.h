#pragma once
// Estimator tests on generated data without images: the simulator's trajectory, IMU and
// scene points; features are the scene points projected into both cameras with the true
// poses plus pixel noise (no tracking errors), so the filter alone is under test.
#include <memory>
#include <string>
#include <vector>

#include "mrvs/edge/feature_observation.h"
#include "mrvs/edge/map_service.h"
#include "mrvs/edge/vio_estimator.h"
#include "mrvs/sim/generator.h"

namespace mrvs::edge::test {

struct SyntheticOptions {
  std::string trajectory = "V1_01_easy.txt";  ///< in tests/data/euroc_groundtruth
  double start_s = 0.0;                       ///< window start (0: the static beginning)
  double duration_s = 20.0;
  std::string preset = "easy";
  double pixel_noise = 0.5;  ///< px, per observation
  int max_features = 200;
  int seed = 3;
  double drift_px = 0.0;          ///< per frame random walk of each track's left pixel (KLT drift)
  double sliding_fraction = 0.0;  ///< tracks whose left pixel slides steadily (bad tracks)
  double sliding_px = 0.2;        ///< their slide per frame, px
  double map_spacing_m = 0.1;     ///< survey point spacing (0.015: a map fine enough to query)
};

struct SyntheticSequence {
  SyntheticOptions options;
  sim::World world;
  std::vector<FeatureFrame> frames;
  std::vector<io::ImuSample> imu;  ///< noisy, as written to imu0/data.csv
  io::Trajectory groundtruth;      ///< IMU poses at every IMU stamp
};

/// The cloud's map of a sequence in process: the voxel map of its survey points (indoor
/// levels) and a query engine, behind the estimator's MapService. `answer` false simulates an
/// outage (every query times out), `announced` false a cloud never heard from.
class LocalMapService : public MapService {
 public:
  static std::unique_ptr<LocalMapService> create(const SyntheticSequence& seq, bool refine = true);
  std::optional<MapDescription> description() override;
  MapReply query(const std::vector<voxel::RayQuery>& rays, TimestampNs stamp_ns, DurationNs timeout,
                 bool want_normals) override;
  bool answer = true;
  bool announced = true;
  int queries = 0;
  int rays = 0;

 private:
  struct Impl;
  std::shared_ptr<Impl> impl_;
};

/// Built once per option set within a test binary.
const SyntheticSequence* synthetic_sequence(const SyntheticOptions& options);

/// The estimator options of config/euroc.yaml, with the paper's alignment (gt_noisy).
EstimatorOptions euroc_estimator_options();

/// Runs the estimator over the sequence (with `map` when given); the IMU poses it returned
/// (map frame), and each frame's output when `outputs` is given.
io::Trajectory run_estimator(const SyntheticSequence& seq, const EstimatorOptions& options,
                             int* skipped = nullptr, MapService* map = nullptr,
                             std::vector<FrameOutput>* outputs = nullptr);

/// ATE RMSE (m) of `estimate` against the sequence's ground truth: SE(3)-aligned, or not
/// aligned at all.
double ate_rmse(const SyntheticSequence& seq, const io::Trajectory& estimate, bool se3_aligned);

}  // namespace mrvs::edge::test
