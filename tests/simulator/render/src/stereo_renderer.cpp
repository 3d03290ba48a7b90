#include "mrvs/sim/stereo_renderer.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <fmt/format.h>

#include "mrvs/sim/photometry.h"
#include "render_internal.h"

namespace mrvs::sim {

namespace {

bool pose_finite(const SE3d& T) { return T.quaternion().coeffs().allFinite() && T.translation().allFinite(); }

}  // namespace

StatusOr<StereoRenderer> StereoRenderer::create(const Scene& scene, const config::StereoRigCalibration& rig,
                                                const RenderOptions& options, std::uint64_t noise_seed) {
  MRVS_RETURN_IF_ERROR(config::validate_options(options, "render"));
  StereoRenderer r;
  r.scene_ = &scene;
  r.options_ = options;
  r.noise_seed_ = noise_seed;
  for (std::size_t c = 0; c < 2; ++c) {
    const config::CameraCalibration& calib = rig.cameras[c];
    if (calib.model == nullptr) {
      return absl::InvalidArgumentError(
          fmt::format("StereoRenderer: camera {} ('{}') has no model", c, calib.name));
    }
    if (!pose_finite(calib.T_b_c)) {
      return absl::InvalidArgumentError(fmt::format("StereoRenderer: camera {} T_b_c is not finite", c));
    }
    r.cameras_[c] = calib.model;
    r.T_b_c_[c] = calib.T_b_c;
    MRVS_ASSIGN_OR_RETURN(RayTable table, RayTable::build(*calib.model));
    r.tables_[c] = std::make_shared<const RayTable>(std::move(table));
  }
  auto faces = std::make_shared<std::vector<FaceInfo>>();
  faces->reserve(scene.faces().size());
  for (const Face& f : scene.faces()) {
    FaceInfo info;
    info.normal = f.normal.cast<float>();
    const float texel = scene.texel_size(f.id);
    info.inv_texel = texel > 0.0f ? 1.0f / texel : 1.0f;
    faces->push_back(info);
  }
  r.faces_ = std::move(faces);
  return r;
}

StatusOr<StereoRenderer> StereoRenderer::with_options(const RenderOptions& options) const {
  MRVS_RETURN_IF_ERROR(config::validate_options(options, "render"));
  StereoRenderer r = *this;
  r.options_ = options;
  return r;
}

StatusOr<StereoRenderer> StereoRenderer::with_illumination(const Illumination& light) const {
  if (!(light.level > 0.0f && light.level <= 1.0f) || !(light.radius_m > 0.0f) ||
      !light.centre_xy.allFinite()) {
    return absl::InvalidArgumentError(
        fmt::format("StereoRenderer: illumination level {} must be in (0, 1], radius {} m > 0, centre finite",
                    light.level, light.radius_m));
  }
  StereoRenderer r = *this;
  r.light_ = light;
  return r;
}

Status StereoRenderer::check_request(int cam, const SE3d& T_w_c) const {
  if (cam != 0 && cam != 1) {
    return absl::InvalidArgumentError(fmt::format("StereoRenderer: camera index {} is not 0 or 1", cam));
  }
  if (!pose_finite(T_w_c)) {
    return absl::InvalidArgumentError(fmt::format("StereoRenderer: camera {} pose T_w_c is not finite", cam));
  }
  return absl::OkStatus();
}

StereoRenderer::View StereoRenderer::make_view(int cam, const SE3d& T_w_c) const {
  View view;
  view.cam = cam;
  view.table = &rays(cam);
  view.R_w_c = T_w_c.rotation_matrix().cast<float>();
  view.origin = T_w_c.translation().cast<float>();
  view.max_distance = static_cast<float>(options_.max_distance_m);
  view.min_cos = static_cast<float>(options_.min_cos_incidence);
  view.mip = options_.aa == AntiAliasing::kAdaptive;
  return view;
}

float StereoRenderer::shade_center(const View& view, int u, int v, int* face) const {
  const Eigen::Vector3f d_w = view.R_w_c * view.table->center(u, v);
  const std::optional<Hit> hit = scene_->intersect(view.origin, d_w, view.max_distance);
  if (!hit) {
    *face = -1;
    return scene_->background(d_w);
  }
  *face = hit->face;
  float lod = 0.0f;
  if (view.mip) {
    const FaceInfo& info = (*faces_)[static_cast<std::size_t>(hit->face)];
    lod = detail::mip_level(hit->distance, view.table->pixel_angle(u, v), info.normal.dot(d_w), view.min_cos,
                            info.inv_texel);
  }
  const float albedo = scene_->albedo(hit->face, hit->u, hit->v, lod);
  return light_.enabled ? albedo * light_.light(view.origin + hit->distance * d_w) : albedo;
}

float StereoRenderer::shade_supersampled(const View& view, int u, int v) const {
  float sum = 0.0f;
  for (int k = 0; k < RayTable::kSubsamples; ++k) {
    const Eigen::Vector3f d_w = view.R_w_c * view.table->subsample(u, v, k);
    const std::optional<Hit> hit = scene_->intersect(view.origin, d_w, view.max_distance);
    if (!hit) {
      sum += scene_->background(d_w);
      continue;
    }
    const float albedo = scene_->albedo(hit->face, hit->u, hit->v, 0.0f);
    sum += light_.enabled ? albedo * light_.light(view.origin + hit->distance * d_w) : albedo;
  }
  return 0.25f * sum;
}

void StereoRenderer::render_pass(const View& view, std::vector<float>* radiance,
                                 std::vector<int>* faces) const {
  const int w = view.table->width(), h = view.table->height();
  const bool full = options_.aa == AntiAliasing::kFull;
#pragma omp parallel for schedule(dynamic, 8)
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const std::size_t i =
          static_cast<std::size_t>(v) * static_cast<std::size_t>(w) + static_cast<std::size_t>(u);
      if (full) {
        (*radiance)[i] = shade_supersampled(view, u, v);
      } else {
        (*radiance)[i] = shade_center(view, u, v, &(*faces)[i]);
      }
    }
  }
}

void StereoRenderer::refine_edges(const View& view, const std::vector<int>& faces,
                                  std::vector<float>* radiance) const {
  const int w = view.table->width(), h = view.table->height();
#pragma omp parallel for schedule(dynamic, 8)
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const std::size_t i =
          static_cast<std::size_t>(v) * static_cast<std::size_t>(w) + static_cast<std::size_t>(u);
      const int f = faces[i];
      const bool edge = (u > 0 && faces[i - 1] != f) || (u + 1 < w && faces[i + 1] != f) ||
                        (v > 0 && faces[i - static_cast<std::size_t>(w)] != f) ||
                        (v + 1 < h && faces[i + static_cast<std::size_t>(w)] != f);
      if (edge) (*radiance)[i] = shade_supersampled(view, u, v);
    }
  }
}

StatusOr<cv::Mat> StereoRenderer::render_radiance(int cam, const SE3d& T_w_c) const {
  MRVS_RETURN_IF_ERROR(check_request(cam, T_w_c));
  const View view = make_view(cam, T_w_c);
  const int w = view.table->width(), h = view.table->height();
  cv::Mat out(h, w, CV_32F);
  std::vector<float> radiance(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  std::vector<int> faces(radiance.size(), -1);
  render_pass(view, &radiance, &faces);
  if (options_.aa == AntiAliasing::kAdaptive) refine_edges(view, faces, &radiance);
  for (int v = 0; v < h; ++v) {
    std::copy_n(radiance.data() + static_cast<std::size_t>(v) * static_cast<std::size_t>(w), w,
                out.ptr<float>(v));
  }
  return out;
}

Status StereoRenderer::render(int cam, const SE3d& T_w_c, const FrameInfo& frame, cv::Mat* image) const {
  MRVS_RETURN_IF_ERROR(check_request(cam, T_w_c));
  const View view = make_view(cam, T_w_c);
  const int w = view.table->width(), h = view.table->height();
  std::vector<float> radiance(static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
  std::vector<int> faces(radiance.size(), -1);
  render_pass(view, &radiance, &faces);
  if (options_.aa == AntiAliasing::kAdaptive) refine_edges(view, faces, &radiance);
  return to_image(cam, frame, radiance, 1.0f, image);
}

Status StereoRenderer::to_image(int cam, const FrameInfo& frame, const std::vector<float>& radiance,
                                float scale, cv::Mat* image) const {
  if (image == nullptr) return absl::InvalidArgumentError("StereoRenderer::render: image is null");
  if (!std::isfinite(frame.gain) || frame.gain < 0.0) {
    return absl::InvalidArgumentError(
        fmt::format("StereoRenderer::render: frame gain {} is not >= 0", frame.gain));
  }
  const int w = camera(cam).width(), h = camera(cam).height();
  if (!std::isfinite(frame.analog_gain) || frame.analog_gain < 1.0) {
    return absl::InvalidArgumentError(
        fmt::format("StereoRenderer::render: analog gain {} is not >= 1", frame.analog_gain));
  }
  const PixelPhotometry photometry(options_, camera(cam), cam, frame.index, frame.gain, noise_seed_,
                                   frame.analog_gain);
  image->create(h, w, CV_8UC1);
#pragma omp parallel for schedule(dynamic, 8)
  for (int v = 0; v < h; ++v) {
    std::uint8_t* row = image->ptr<std::uint8_t>(v);
    const float* rad = radiance.data() + static_cast<std::size_t>(v) * static_cast<std::size_t>(w);
    for (int u = 0; u < w; ++u) row[u] = photometry.dn(rad[u] * scale, u, v);
  }
  return absl::OkStatus();
}

StatusOr<cv::Mat> StereoRenderer::render(int cam, const SE3d& T_w_c, const FrameInfo& frame) const {
  cv::Mat image;
  MRVS_RETURN_IF_ERROR(render(cam, T_w_c, frame, &image));
  return image;
}

StatusOr<std::array<cv::Mat, 2>> StereoRenderer::render_stereo(const SE3d& T_w_b,
                                                               const FrameInfo& frame) const {
  if (!pose_finite(T_w_b)) return absl::InvalidArgumentError("StereoRenderer: body pose T_w_b is not finite");
  std::array<cv::Mat, 2> images;
  for (int cam = 0; cam < 2; ++cam) {
    MRVS_RETURN_IF_ERROR(render(cam, camera_pose(cam, T_w_b), frame, &images[static_cast<std::size_t>(cam)]));
  }
  return images;
}

}  // namespace mrvs::sim
