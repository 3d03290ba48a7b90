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

/// Pixels person `box` may cover: the bounding rectangle of its projected corners grown by
/// a margin for the distortion's bulge; the whole image when a corner is behind the camera
/// or far outside the field of view. nullopt when it is wholly behind or outside.
std::optional<Eigen::Vector4i> person_rect(const camera::CameraModel& model, const SE3d& T_c_w,
                                           const PersonBox& box) {
  constexpr double kMarginPx = 8.0, kMaxSlope = 1.5;  // tan of the widest angle trusted to project
  const Eigen::Vector4i whole(0, 0, model.width() - 1, model.height() - 1);
  double u0 = 1e9, v0 = 1e9, u1 = -1e9, v1 = -1e9;
  int behind = 0;
  bool trusted = true;
  for (int k = 0; k < 8; ++k) {
    const Eigen::Vector3f corner(k & 1 ? box.half.x() : -box.half.x(), k & 2 ? box.half.y() : -box.half.y(),
                                 k & 4 ? box.half.z() : -box.half.z());
    const Vec3d p_w = (box.centre_w + box.R_p_w.transpose() * corner).cast<double>();
    const Vec3d p_c = T_c_w * p_w;
    if (p_c.z() < 0.05) {
      ++behind;
      continue;
    }
    const std::optional<Vec2d> uv = model.project(p_c);
    if (!uv || std::abs(p_c.x()) > kMaxSlope * p_c.z() || std::abs(p_c.y()) > kMaxSlope * p_c.z()) {
      trusted = false;
      continue;
    }
    u0 = std::min(u0, uv->x()), v0 = std::min(v0, uv->y()), u1 = std::max(u1, uv->x()),
    v1 = std::max(v1, uv->y());
  }
  if (behind == 8) return std::nullopt;
  if (behind > 0 || !trusted) return whole;
  const Eigen::Vector4i r(std::max(0, static_cast<int>(std::floor(u0 - kMarginPx))),
                          std::max(0, static_cast<int>(std::floor(v0 - kMarginPx))),
                          std::min(model.width() - 1, static_cast<int>(std::ceil(u1 + kMarginPx))),
                          std::min(model.height() - 1, static_cast<int>(std::ceil(v1 + kMarginPx))));
  if (r[0] > r[2] || r[1] > r[3]) return std::nullopt;
  return r;
}

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

StereoRenderer StereoRenderer::with_people(std::vector<Walker> walkers) const {
  StereoRenderer r = *this;
  r.walkers_ = walkers.empty() ? nullptr : std::make_shared<const std::vector<Walker>>(std::move(walkers));
  return r;
}

std::int64_t StereoRenderer::people_pixels(int cam, const SE3d& T_w_c, TimestampNs t_ns) const {
  if (!check_request(cam, T_w_c).ok()) return 0;
  const View view = make_view(cam, T_w_c, t_ns);
  std::int64_t count = 0;
  for (std::size_t i = 0; i < view.people.size(); ++i) {
    const Eigen::Vector4i& r = view.people_rects[i];
#pragma omp parallel for schedule(dynamic, 8) reduction(+ : count)
    for (int v = r[1]; v <= r[3]; ++v) {
      for (int u = r[0]; u <= r[2]; ++u) {
        // Counted once: by the first rect that holds the pixel.
        bool first = true;
        for (std::size_t j = 0; j < i; ++j) {
          const Eigen::Vector4i& q = view.people_rects[j];
          if (u >= q[0] && v >= q[1] && u <= q[2] && v <= q[3]) first = false;
        }
        if (!first) continue;
        const Eigen::Vector3f d_w = view.R_w_c * view.table->center(u, v);
        const auto person = nearest_person(view, u, v, d_w, view.max_distance);
        // The static scene is cast only up to the person: a face in front hides them.
        if (person && !scene_->intersect(view.origin, d_w, person->first)) ++count;
      }
    }
  }
  return count;
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

StereoRenderer::View StereoRenderer::make_view(int cam, const SE3d& T_w_c, TimestampNs t_ns) const {
  View view;
  view.cam = cam;
  view.table = &rays(cam);
  view.R_w_c = T_w_c.rotation_matrix().cast<float>();
  view.origin = T_w_c.translation().cast<float>();
  view.max_distance = static_cast<float>(options_.max_distance_m);
  view.min_cos = static_cast<float>(options_.min_cos_incidence);
  view.mip = options_.aa == AntiAliasing::kAdaptive;
  if (walkers_ == nullptr) return view;
  const SE3d T_c_w = T_w_c.inverse();
  for (const PersonBox& box : people_at(*walkers_, t_ns)) {
    const std::optional<Eigen::Vector4i> rect = person_rect(camera(cam), T_c_w, box);
    if (!rect) continue;
    view.people.push_back(box);
    view.people_rects.push_back(*rect);
  }
  return view;
}

std::optional<std::pair<float, int>> StereoRenderer::nearest_person(const View& view, int u, int v,
                                                                    const Eigen::Vector3f& d_w,
                                                                    float max_t) const {
  std::optional<std::pair<float, int>> best;
  for (std::size_t i = 0; i < view.people.size(); ++i) {
    const Eigen::Vector4i& r = view.people_rects[i];
    if (u < r[0] || v < r[1] || u > r[2] || v > r[3]) continue;
    const std::optional<float> t = view.people[i].intersect(view.origin, d_w, best ? best->first : max_t);
    if (t) best = std::make_pair(*t, static_cast<int>(i));
  }
  return best;
}

float StereoRenderer::shade_person(const View& view, const Eigen::Vector3f& d_w,
                                   std::pair<float, int> hit) const {
  const Eigen::Vector3f p = view.origin + hit.first * d_w;
  return view.people[static_cast<std::size_t>(hit.second)].albedo(p) * light_.light(p);
}

float StereoRenderer::shade_center(const View& view, int u, int v, int* face) const {
  const Eigen::Vector3f d_w = view.R_w_c * view.table->center(u, v);
  const std::optional<Hit> hit = scene_->intersect(view.origin, d_w, view.max_distance);
  if (!view.people.empty()) {
    const auto person = nearest_person(view, u, v, d_w, hit ? hit->distance : view.max_distance);
    if (person) {
      *face = static_cast<int>(faces_->size()) + view.people[static_cast<std::size_t>(person->second)].index;
      return shade_person(view, d_w, *person);
    }
  }
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
    if (!view.people.empty()) {
      const auto person = nearest_person(view, u, v, d_w, hit ? hit->distance : view.max_distance);
      if (person) {
        sum += shade_person(view, d_w, *person);
        continue;
      }
    }
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

StatusOr<cv::Mat> StereoRenderer::render_radiance(int cam, const SE3d& T_w_c, TimestampNs t_ns) const {
  MRVS_RETURN_IF_ERROR(check_request(cam, T_w_c));
  const View view = make_view(cam, T_w_c, t_ns);
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
  const View view = make_view(cam, T_w_c, frame.t_ns);
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
    photometry.dn_row(radiance.data() + static_cast<std::size_t>(v) * static_cast<std::size_t>(w), scale, v,
                      w, image->ptr<std::uint8_t>(v));
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
