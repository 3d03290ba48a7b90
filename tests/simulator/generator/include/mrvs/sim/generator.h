#pragma once
// The dataset generator: trajectory -> IMU -> scene -> prior map -> stereo images, written
// as a EuRoC ASL folder (simulator.md section 1) that the project's EuRoC reader takes
// unchanged, plus sim0/ with the extra truth. The folder appears complete or not at all.
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "mrvs/config/calibration.h"
#include "mrvs/core/status.h"
#include "mrvs/io/types.h"
#include "mrvs/sim/car_route.h"
#include "mrvs/sim/gnss_sim.h"
#include "mrvs/sim/prior_map.h"
#include "mrvs/sim/rig.h"
#include "mrvs/sim/scene.h"
#include "mrvs/sim/simulator_options.h"
#include "mrvs/sim/spline_trajectory.h"
#include "mrvs/sim/stereo_renderer.h"
#include "mrvs/sim/time_grid.h"

namespace mrvs::sim {

struct GeneratorRequest {
  SceneProfile profile = SceneProfile::kIndoor;
  /// Indoor: the trajectory to follow (TUM txt or EuRoC ground-truth CSV). Outdoor: must be
  /// empty (the car route is synthesised from options.route).
  std::filesystem::path trajectory;
  std::filesystem::path out;  ///< the sequence folder to create (contains mav0/)
  bool overwrite = false;     ///< replace an existing output folder
  std::string preset = "easy";
  SimulatorOptions options;
};

/// Progress of the long stages ("render": frames done of total).
struct GeneratorProgress {
  std::string stage;
  std::int64_t done = 0;
  std::int64_t total = 0;
};
using ProgressCallback = std::function<void(const GeneratorProgress&)>;

struct GeneratorReport {
  std::filesystem::path out;
  std::int64_t frames = 0;
  std::int64_t imu_samples = 0;
  std::int64_t map_points = 0;
  std::int64_t gnss_fixes = 0;  ///< 0 when gnss.enabled is off
  TimestampNs t_begin_ns = 0;
  TimestampNs t_end_ns = 0;
  double seconds_total = 0.0;
  double seconds_render = 0.0;  ///< rendering and PNG writing
  double seconds_map = 0.0;     ///< scene, map sampling and PLY writing
};

/// Everything a sequence is made of, in memory: what generate_dataset writes, and what
/// tests use to check the files against (the same scene, map and poses).
struct World {
  Rig rig;                                   ///< the rig written to mav0/*/sensor.yaml
  Rig true_rig;                              ///< the rig that renders (calib_error; else = rig)
  double time_offset_ms = 0.0;               ///< true camera-IMU offset t_d (calib_error adds a draw)
  config::StereoRigCalibration calibration;  ///< render truth: true_rig
  std::optional<SplineTrajectory> spline;    ///< the ground-truth motion
  std::string source;                        ///< where the motion came from
  std::optional<CarRoute> route;             ///< outdoor: the synthesised car route
  TimeGrid grid;
  std::vector<ImuSimSample> imu;             ///< one per IMU stamp
  std::vector<io::GroundTruthState> states;  ///< one per IMU stamp (sign-continuous q)
  std::vector<Vec3d> body_positions;         ///< at every camera frame, world
  std::vector<Vec3d> keep_clear;             ///< body and camera centres, world
  std::optional<Scene> scene;
  PriorMap map;
  std::vector<GnssSimFix> gnss;  ///< GNSS fixes with their truth; empty when gnss.enabled is off
  Illumination light;            ///< render.dim_area: centred on a drawn point of the trajectory
  std::vector<Walker> people;    ///< people.count walkers crossing the view

  /// T_w_b at camera frame k (its true, IMU-clock time).
  const SE3d& frame_pose(std::size_t k) const { return states[grid.camera_imu_index[k]].T_w_b; }
};

/// Builds the world of `request` (no files written).
StatusOr<World> build_world(const GeneratorRequest& request, const ProgressCallback& progress = {});

/// Generates the dataset. Errors name the input or output at fault; on any error nothing is
/// left at request.out (and an existing folder there is untouched).
StatusOr<GeneratorReport> generate_dataset(const GeneratorRequest& request,
                                           const ProgressCallback& progress = {});

/// The request a generated sequence was made with, read back from its sim0/request.yaml and
/// sim0/config.yaml (out = `sequence`): build_world() of it rebuilds the same world (scene,
/// map, poses). Errors name the missing or malformed file.
StatusOr<GeneratorRequest> load_generator_request(const std::filesystem::path& sequence);

/// "mrvs dataset_simulator <version>".
std::string generator_version();

}  // namespace mrvs::sim
