#pragma once
// Everything dataset_simulator can be told, declared once (config Options structs): a
// profile (indoor EuRoC-like / outdoor KAIST-like) sets the rig and the defaults, a preset
// (easy / realistic) sets the realism knobs, then a YAML file and `--set key=value`
// overrides change single keys. The resolved options are printed and saved in sim0/.
#include <cstdint>
#include <string>
#include <vector>

#include "mrvs/config/options.h"
#include "mrvs/core/status.h"
#include "mrvs/sim/calibration_error.h"
#include "mrvs/sim/car_route.h"
#include "mrvs/sim/gnss_sim.h"
#include "mrvs/sim/imu_sim.h"
#include "mrvs/sim/map_options.h"
#include "mrvs/sim/render_options.h"
#include "mrvs/sim/scene.h"
#include "mrvs/sim/spline_trajectory.h"

namespace mrvs::sim {

/// SceneOptions with a visit() (scene.h stays free of the config library).
struct SceneKnobs : config::OptionsEquality<SceneKnobs> {
  SceneOptions value;

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("num_boxes", value.num_boxes, in_range(0, 200), "clutter boxes (indoor)");
    v("texel_size_m", value.texel_size_m, in_range(0.001, 0.1), "albedo bake resolution, m");
    v("clearance_m", value.clearance_m, in_range(0.0, 10.0), "min distance of boxes from the trajectory, m");
    v("room_margin_m", value.room_margin_m, in_range(0.0, 50.0), "room grows to the trajectory + margin, m");
    v("textureless_fraction", value.textureless_fraction, in_range(0.0, 1.0),
      "share of constant-albedo faces");
    v("unmapped_objects", value.unmapped_objects, in_range(0, 200), "boxes in the images but not in the map");
    v("removed_objects", value.removed_objects, in_range(0, 200), "boxes in the map but not in the images");
    v("rotated_fraction", value.rotated_fraction, in_range(0.0, 1.0), "share of boxes rotated about z");
  }
};

/// Moving people (people.h): `count` walkers, each crossing the view of cam0 at a drawn time
/// of the window, view_distance_m ahead of it, walking back and forth across it.
struct PeopleOptions : config::OptionsEquality<PeopleOptions> {
  int count = 0;                 ///< walkers (0: none)
  double speed_mps = 1.3;        ///< walking speed, m/s
  double height_m = 1.75;        ///< box height, m
  double width_m = 0.5;          ///< shoulder width, m
  double depth_m = 0.3;          ///< front to back, m
  double path_length_m = 5.0;    ///< back-and-forth path, m (clipped to the scene)
  double view_distance_m = 2.5;  ///< the path crosses cam0's view this far ahead, m
  double clearance_m = 0.5;      ///< never closer to the body or a camera (horizontally), m

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("count", count, in_range(0, 50), "walking people in the images, not in the map");
    v("speed_mps", speed_mps, in_range(0.1, 5.0), "walking speed, m/s");
    v("height_m", height_m, in_range(0.5, 2.5), "height, m");
    v("width_m", width_m, in_range(0.1, 2.0), "width, m");
    v("depth_m", depth_m, in_range(0.1, 2.0), "depth, m");
    v("path_length_m", path_length_m, in_range(1.0, 100.0), "back-and-forth path length, m");
    v("view_distance_m", view_distance_m, in_range(0.5, 100.0), "crosses cam0's view this far ahead, m");
    v("clearance_m", clearance_m, in_range(0.0, 10.0), "horizontal clearance from the body and cameras, m");
  }
};

struct SimulatorOptions : config::OptionsEquality<SimulatorOptions> {
  std::int64_t seed = 1;                ///< one seed for every random stream
  double time_offset_ms = 0.0;          ///< camera-IMU offset t_d: t_imu = t_cam + t_d, ms
  bool write_clean_map = false;         ///< also write sim0/pointcloud_clean.ply (no noise, no misalignment)
  TrajectoryOptions trajectory;         ///< window, static prefix, knot spacing
  CarRouteOptions route;                ///< outdoor only: the route the car drives
  ImuSimOptions imu;                    ///< IMU noise and biases
  SceneKnobs scene;                     ///< clutter and texture knobs
  RenderOptions render;                 ///< anti-aliasing and photometric knobs
  MapOptions map;                       ///< prior-map density, noise, holes, misalignment
  GnssSimOptions gnss;                  ///< GNSS fixes (outdoor default: on)
  CalibrationErrorOptions calib_error;  ///< the rendering rig differs from the written one
  PeopleOptions people;                 ///< walking people

  template <class V>
  void visit(V& v) {
    using namespace mrvs::config::constraints;
    v("seed", seed, at_least(std::int64_t{0}), "seed of every random stream");
    v("time_offset_ms", time_offset_ms, in_range(-1000.0, 1000.0),
      "camera-IMU offset t_d (t_imu = t_cam + t_d), ms");
    v("write_clean_map", write_clean_map, any(), "also write sim0/pointcloud_clean.ply");
    v.section("trajectory", trajectory, "time window and start handling");
    v.section("route", route, "outdoor car route");
    v.section("imu", imu, "IMU noise model");
    v.section("scene", scene, "scene layout and textures");
    v.section("render", render, "image formation");
    v.section("map", map, "survey LiDAR prior map");
    v.section("gnss", gnss, "GNSS position fixes of a roof antenna (mav0/gnss0)");
    v.section("calib_error", calib_error, "true rig vs the calibration written in sensor.yaml");
    v.section("people", people, "people walking through the images (not in the map)");
  }
};

/// "indoor" / "outdoor".
StatusOr<SceneProfile> parse_profile(const std::string& name);
std::string profile_name(SceneProfile profile);

/// Defaults of a profile: indoor = EuRoC rig noise and the Vicon-room survey, no GNSS;
/// outdoor = KAIST-like IMU, gravity 9.80766, the street survey, the test car route and
/// GNSS fixes at 1 Hz (gnss.enabled).
SimulatorOptions default_options(SceneProfile profile);

/// Names accepted by apply_preset.
std::vector<std::string> preset_names();
/// "easy": every realism knob off (no pixel noise, fixed exposure, exact map, no holes or
/// map changes, no blur, people or calibration error). "realistic": pixel noise (2 DN read +
/// shot), exposure walk, 3 % stereo gain mismatch, vignetting, 20 % textureless faces, 2
/// unmapped objects, 5 % map holes, map noise 3 mm / 1 mm. "hard": realistic plus what issue
/// 31 adds (motion blur over an auto-exposed exposure, a dim area, Kalibr-sized calibration
/// error, 3 walking people and, indoors, a terrestrial-scanner survey with a station every 3 m
/// of the path); it becomes "realistic" once the estimator copes with it. GNSS (when the
/// profile has it) stays on with its noise in all; "easy" has no GNSS outliers, the others 2 %
/// per fix. Error naming the accepted presets for another name.
Status apply_preset(const std::string& preset, SceneProfile profile, SimulatorOptions& options);

}  // namespace mrvs::sim
