#pragma once
// Shared inputs of the renderer tests, built once per test binary: the real EuRoC stereo
// rig, the real V1_01_easy ground truth, an indoor scene around it and a renderer.
#include <cstdint>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include "mrvs/config/calibration.h"
#include "mrvs/io/types.h"
#include "mrvs/sim/scene.h"
#include "mrvs/sim/stereo_renderer.h"

namespace mrvs::sim::test {

/// Seeds used by the tests.
inline constexpr std::uint64_t kSceneSeed = 7;
inline constexpr std::uint64_t kNoiseSeed = 11;

struct RenderTestWorld {
  config::StereoRigCalibration rig;          ///< EuRoC cam0 / cam1 (real sensor.yaml values)
  io::Trajectory trajectory;                 ///< V1_01_easy ground truth, 200 Hz, T_w_b
  std::unique_ptr<Scene> scene;              ///< indoor room around the trajectory
  std::unique_ptr<StereoRenderer> renderer;  ///< default RenderOptions
};

/// The world (built on first use); nullptr after a failure, which is reported with
/// ADD_FAILURE once.
const RenderTestWorld* world();

/// The EuRoC rig, loaded from the real sensor.yaml texts.
StatusOr<config::StereoRigCalibration> euroc_rig();

/// Ground-truth body pose index of V1_01 about `seconds` after the start (motion starts
/// after about 4.2 s).
std::size_t pose_index_at(const io::Trajectory& trajectory, double seconds);

/// True when the 2r+1 square around (u, v) lies inside `face` and has one face id.
bool uniform_face(const cv::Mat& face, int u, int v, int r);

/// `x` with 3 significant digits (for RecordProperty).
inline std::string num(double x) {
  std::ostringstream out;
  out.precision(3);
  out << x;
  return out.str();
}

}  // namespace mrvs::sim::test
