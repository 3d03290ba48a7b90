// Truth outputs of StereoRenderer: per-pixel depth / face / face (u, v) / mip level, single
// pixel casts and true correspondences (optical flow, stereo matches).
#include <algorithm>
#include <cmath>

#include "mrvs/sim/stereo_renderer.h"
#include "render_internal.h"

namespace mrvs::sim {

StatusOr<TruthImage> StereoRenderer::render_truth(int cam, const SE3d& T_w_c) const {
  MRVS_RETURN_IF_ERROR(check_request(cam, T_w_c));
  const View view = make_view(cam, T_w_c);
  const int w = view.table->width(), h = view.table->height();
  TruthImage t;
  t.range = cv::Mat(h, w, CV_32F, cv::Scalar(0.0f));
  t.depth = cv::Mat(h, w, CV_32F, cv::Scalar(0.0f));
  t.face = cv::Mat(h, w, CV_32S, cv::Scalar(-1));
  t.u = cv::Mat(h, w, CV_32F, cv::Scalar(0.0f));
  t.v = cv::Mat(h, w, CV_32F, cv::Scalar(0.0f));
  t.lod = cv::Mat(h, w, CV_32F, cv::Scalar(0.0f));
#pragma omp parallel for schedule(dynamic, 8)
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const Eigen::Vector3f& d_c = view.table->center(u, v);
      const Eigen::Vector3f d_w = view.R_w_c * d_c;
      const std::optional<Hit> hit = scene_->intersect(view.origin, d_w, view.max_distance);
      if (!hit) continue;
      const FaceInfo& info = (*faces_)[static_cast<std::size_t>(hit->face)];
      t.range.at<float>(v, u) = hit->distance;
      t.depth.at<float>(v, u) = hit->distance * d_c.z();
      t.face.at<int>(v, u) = hit->face;
      t.u.at<float>(v, u) = hit->u;
      t.v.at<float>(v, u) = hit->v;
      t.lod.at<float>(v, u) = detail::mip_level(hit->distance, view.table->pixel_angle(u, v),
                                                info.normal.dot(d_w), view.min_cos, info.inv_texel);
    }
  }
  return t;
}

std::optional<PixelHit> StereoRenderer::cast_pixel(int cam, const SE3d& T_w_c, const Vec2d& uv) const {
  if (!check_request(cam, T_w_c).ok()) return std::nullopt;
  const StatusOr<Vec3d> d_c = camera(cam).unproject(uv);
  if (!d_c.ok()) return std::nullopt;
  const Vec3d d_w = T_w_c.quaternion() * *d_c;
  const std::optional<Hit> hit = scene_->intersect(T_w_c.translation().cast<float>(), d_w.cast<float>(),
                                                   static_cast<float>(options_.max_distance_m));
  if (!hit) return std::nullopt;
  PixelHit out;
  out.hit = *hit;
  out.direction_w = d_w;
  out.point_w = T_w_c.translation() + static_cast<double>(hit->distance) * d_w;
  return out;
}

std::optional<Correspondence> StereoRenderer::correspondence(int cam_from, const SE3d& T_w_from,
                                                             const Vec2d& uv, int cam_to,
                                                             const SE3d& T_w_to) const {
  if (!check_request(cam_to, T_w_to).ok()) return std::nullopt;
  const std::optional<PixelHit> from = cast_pixel(cam_from, T_w_from, uv);
  if (!from) return std::nullopt;
  const camera::CameraModel& target = camera(cam_to);
  const std::optional<Vec2d> uv_to = target.project(T_w_to.inverse() * from->point_w);
  if (!uv_to || !target.in_image(*uv_to)) return std::nullopt;
  // Occlusion: cast from the target camera towards the point; it must not stop short.
  const Vec3d diff = from->point_w - T_w_to.translation();
  const double range_to = diff.norm();
  if (!(range_to > 0.0)) return std::nullopt;
  const double tolerance = std::max(1e-3, 1e-3 * range_to);
  const std::optional<Hit> blocker =
      scene_->intersect(T_w_to.translation().cast<float>(), (diff / range_to).cast<float>(),
                        static_cast<float>(range_to + 1.0));
  if (blocker && static_cast<double>(blocker->distance) < range_to - tolerance) return std::nullopt;
  Correspondence c;
  c.uv = *uv_to;
  c.point_w = from->point_w;
  c.range_from = static_cast<double>(from->hit.distance);
  c.range_to = range_to;
  return c;
}

std::optional<Vec2d> StereoRenderer::true_flow(int cam, const SE3d& T_w_c0, const SE3d& T_w_c1,
                                               const Vec2d& uv) const {
  const std::optional<Correspondence> c = correspondence(cam, T_w_c0, uv, cam, T_w_c1);
  if (!c) return std::nullopt;
  return Vec2d(c->uv - uv);
}

}  // namespace mrvs::sim
