// Motion blur (simulator.md section 4.3): an image integrated over its exposure along the
// true motion, as the mean radiance of sub-sample poses evenly spaced in time, and how many
// sub-samples an exposure needs so that the image moves at most a step between two.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "mrvs/sim/stereo_renderer.h"

namespace mrvs::sim {

Status StereoRenderer::render_exposure(int cam, const std::vector<SE3d>& T_w_c, const FrameInfo& frame,
                                       cv::Mat* image, const std::vector<TimestampNs>& times_ns) const {
  if (T_w_c.empty()) return absl::InvalidArgumentError("StereoRenderer::render_exposure: no pose");
  if (!times_ns.empty() && times_ns.size() != T_w_c.size()) {
    return absl::InvalidArgumentError(
        fmt::format("StereoRenderer::render_exposure: {} poses but {} times", T_w_c.size(), times_ns.size()));
  }
  if (T_w_c.size() == 1) {
    FrameInfo at = frame;
    if (!times_ns.empty()) at.t_ns = times_ns.front();
    return render(cam, T_w_c.front(), at, image);
  }
  std::vector<float> sum;
  for (std::size_t i = 0; i < T_w_c.size(); ++i) {
    const SE3d& T = T_w_c[i];
    MRVS_ASSIGN_OR_RETURN(const cv::Mat radiance,
                          render_radiance(cam, T, times_ns.empty() ? frame.t_ns : times_ns[i]));
    if (sum.empty()) sum.assign(radiance.total(), 0.0f);
    const float* r = radiance.ptr<float>(0);  // continuous: made by render_radiance
    for (std::size_t p = 0; p < sum.size(); ++p) sum[p] += r[p];
  }
  return to_image(cam, frame, sum, 1.0f / static_cast<float>(T_w_c.size()), image);
}

int StereoRenderer::exposure_samples(int cam, const SE3d& T_w_a, const SE3d& T_w_b, double step_px,
                                     int max_samples) const {
  if (!check_request(cam, T_w_a).ok() || !check_request(cam, T_w_b).ok() || !(step_px > 0.0)) return 1;
  constexpr int kGridU = 9, kGridV = 7;  // surface points probed, spread over the image
  const camera::CameraModel& model = camera(cam);
  const SE3d T_b_w = T_w_b.inverse();
  double motion = 0.0;
  for (int j = 0; j < kGridV; ++j) {
    for (int i = 0; i < kGridU; ++i) {
      const Vec2d uv((i + 0.5) * model.width() / kGridU, (j + 0.5) * model.height() / kGridV);
      const std::optional<PixelHit> hit = cast_pixel(cam, T_w_a, uv);
      // A point far away (or the sky) moves with the rotation alone.
      const Vec3d p_b = hit ? Vec3d(T_b_w * hit->point_w)
                            : Vec3d(T_b_w.quaternion() * (T_w_a.quaternion() * *model.unproject(uv)));
      const std::optional<Vec2d> to = model.project(p_b);
      if (to) motion = std::max(motion, (*to - uv).norm());
    }
  }
  return std::clamp(static_cast<int>(std::ceil(motion / step_px)), 1, std::max(1, max_samples));
}

}  // namespace mrvs::sim
