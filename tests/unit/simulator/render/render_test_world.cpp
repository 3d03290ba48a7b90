#include "render_test_world.h"

#include <gtest/gtest.h>

#include "mrvs/config/calibration.h"
#include "mrvs/io/trajectory_io.h"
#include "mrvs/test/euroc_sensor_yaml.h"
#include "mrvs/test/shared_data.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::sim::test {
namespace {

std::unique_ptr<RenderTestWorld> build_world() {
  auto w = std::make_unique<RenderTestWorld>();
  StatusOr<config::StereoRigCalibration> rig = euroc_rig();
  if (!rig.ok()) {
    ADD_FAILURE() << rig.status();
    return nullptr;
  }
  w->rig = *rig;
  StatusOr<io::Trajectory> traj = io::read_trajectory(mrvs::test::euroc_groundtruth_file("V1_01_easy.txt"));
  if (!traj.ok()) {
    ADD_FAILURE() << traj.status();
    return nullptr;
  }
  w->trajectory = *traj;
  // Keep clear: body and camera centres every 50 ms.
  std::vector<Vec3d> keep_clear;
  for (std::size_t i = 0; i < w->trajectory.size(); i += 10) {
    const SE3d& T_w_b = w->trajectory[i].T_w_b;
    keep_clear.push_back(T_w_b.translation());
    for (const config::CameraCalibration& c : w->rig.cameras)
      keep_clear.push_back((T_w_b * c.T_b_c).translation());
  }
  StatusOr<Scene> scene = make_scene(SceneProfile::kIndoor, SceneOptions{}, keep_clear, kSceneSeed);
  if (!scene.ok()) {
    ADD_FAILURE() << scene.status();
    return nullptr;
  }
  w->scene = std::make_unique<Scene>(std::move(*scene));
  StatusOr<StereoRenderer> renderer = StereoRenderer::create(*w->scene, w->rig, RenderOptions{}, kNoiseSeed);
  if (!renderer.ok()) {
    ADD_FAILURE() << renderer.status();
    return nullptr;
  }
  w->renderer = std::make_unique<StereoRenderer>(std::move(*renderer));
  return w;
}

}  // namespace

const RenderTestWorld* world() {
  static const std::unique_ptr<RenderTestWorld> instance = build_world();
  return instance.get();
}

StatusOr<config::StereoRigCalibration> euroc_rig() {
  mrvs::test::TempDir dir;
  config::StereoRigCalibration rig;
  for (int cam = 0; cam < 2; ++cam) {
    const std::string name = cam == 0 ? "cam0" : "cam1";
    MRVS_ASSIGN_OR_RETURN(rig.cameras[static_cast<std::size_t>(cam)],
                          config::load_euroc_camera_yaml(
                              dir.write(name + "/sensor.yaml", mrvs::test::euroc_camera_sensor_yaml(cam))));
  }
  return rig;
}

std::size_t pose_index_at(const io::Trajectory& trajectory, double seconds) {
  if (trajectory.empty()) return 0;
  const TimestampNs target = trajectory.front().t_ns + static_cast<TimestampNs>(seconds * 1e9);
  std::size_t i = 0;
  while (i + 1 < trajectory.size() && trajectory[i].t_ns < target) ++i;
  return i;
}

bool uniform_face(const cv::Mat& face, int u, int v, int r) {
  if (u - r < 0 || v - r < 0 || u + r >= face.cols || v + r >= face.rows) return false;
  const int f = face.at<int>(v, u);
  for (int dv = -r; dv <= r; ++dv) {
    for (int du = -r; du <= r; ++du) {
      if (face.at<int>(v + dv, u + du) != f) return false;
    }
  }
  return true;
}

}  // namespace mrvs::sim::test
