#pragma once
// Stereo image renderer (simulator.md section 4): ray-casts a Scene through per-camera ray
// tables, shades with the scene albedo times the light (Illumination), anti-aliases
// (adaptive / full / none) and maps radiance to 8-bit DN with gain, vignetting and noise
// (photometry.h). Also gives the truth needed by tests: per-pixel depth, face id and face
// (u, v), and the true image motion of a pixel between two poses or cameras.
//
// Frames: w = world, b = body (IMU), c = camera; T_w_c = T_w_b * T_b_c.
// Output is identical for any OpenMP thread count (disjoint writes, counter-based noise).
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "mrvs/camera/camera_model.h"
#include "mrvs/config/calibration.h"
#include "mrvs/core/status.h"
#include "mrvs/geometry/se3.h"
#include "mrvs/sim/people.h"
#include "mrvs/sim/ray_table.h"
#include "mrvs/sim/render_options.h"
#include "mrvs/sim/scene.h"

namespace mrvs::sim {

/// Per-frame inputs of one render.
struct FrameInfo {
  std::int64_t index = 0;    ///< frame number (keys the image noise)
  double gain = 1.0;         ///< frame gain g_k (exposure_gains() times AutoExposure), both cameras
  double analog_gain = 1.0;  ///< A_k, amplifies the noise too (photometry.h)
  TimestampNs t_ns = 0;      ///< where the moving people are (with_people)
};

/// The scene's light (render.dim_area): 1 everywhere but in a dim area around a vertical
/// axis through centre_xy, light(p) = 1 - (1 - level) exp(-d^2 / (2 r^2)) with d the
/// horizontal distance of p from the axis. Radiance = albedo * light; the sky is unlit.
struct Illumination {
  bool enabled = false;
  Eigen::Vector2f centre_xy = Eigen::Vector2f::Zero();  ///< world, m
  float level = 1.0f;                                   ///< light on the axis
  float radius_m = 1.0f;                                ///< r, m

  float light(const Eigen::Vector3f& p_w) const {
    if (!enabled) return 1.0f;
    const float d2 = (p_w.head<2>() - centre_xy).squaredNorm();
    return 1.0f - (1.0f - level) * std::exp(-d2 / (2.0f * radius_m * radius_m));
  }
};

/// Per-pixel truth of one camera pose (pixel centre rays, the same casts as the image).
struct TruthImage {
  cv::Mat range;  ///< CV_32F, distance along the unit ray to the hit, m; 0 where nothing is hit (sky)
  cv::Mat depth;  ///< CV_32F, z-depth in the camera frame, m; 0 where nothing is hit
  cv::Mat face;   ///< CV_32S, Face::id of the hit; -1 where nothing is hit
  cv::Mat u;      ///< CV_32F, hit position along Face::axis_u, m
  cv::Mat v;      ///< CV_32F, hit position along Face::axis_v, m
  cv::Mat lod;    ///< CV_32F, mip level the adaptive pass 1 samples at (0 for sky)
};

/// A pixel's ray hit in the world.
struct PixelHit {
  Hit hit;                            ///< face, distance (m) and face (u, v)
  Vec3d point_w = Vec3d::Zero();      ///< the hit point, world frame, m
  Vec3d direction_w = Vec3d::Zero();  ///< unit ray direction, world frame
};

/// Where the surface point seen at a pixel appears in another view.
struct Correspondence {
  Vec2d uv = Vec2d::Zero();       ///< pixel in the target view
  Vec3d point_w = Vec3d::Zero();  ///< the surface point, world frame, m
  double range_from = 0.0;        ///< distance from the source camera, m
  double range_to = 0.0;          ///< distance from the target camera, m
};

class StereoRenderer {
 public:
  /// Builds the ray tables of both cameras of `rig` (each must have a model). `scene` must
  /// outlive the renderer. `noise_seed` keys the image noise (Stream::kImageNoise).
  /// InvalidArgument for invalid options, a missing camera model or a camera whose rays
  /// cannot be computed.
  static StatusOr<StereoRenderer> create(const Scene& scene, const config::StereoRigCalibration& rig,
                                         const RenderOptions& options, std::uint64_t noise_seed);

  /// A renderer sharing this one's scene, cameras and ray tables, with other options.
  StatusOr<StereoRenderer> with_options(const RenderOptions& options) const;
  /// The same renderer under `light` (InvalidArgument for a level outside (0, 1] or r <= 0).
  StatusOr<StereoRenderer> with_illumination(const Illumination& light) const;
  const Illumination& illumination() const { return light_; }
  /// The same renderer with people walking through the images (people.h); the truth
  /// functions (render_truth, cast_pixel, correspondence, true_flow) see the static scene only.
  StereoRenderer with_people(std::vector<Walker> walkers) const;
  /// Pixel-centre rays of camera `cam` at pose T_w_c whose nearest hit at time t is a person.
  std::int64_t people_pixels(int cam, const SE3d& T_w_c, TimestampNs t_ns) const;

  const RenderOptions& options() const { return options_; }
  const camera::CameraModel& camera(int cam) const { return *cameras_[static_cast<std::size_t>(cam)]; }
  const RayTable& rays(int cam) const { return *tables_[static_cast<std::size_t>(cam)]; }
  /// T_b_c of camera `cam` (camera -> body).
  const SE3d& T_b_c(int cam) const { return T_b_c_[static_cast<std::size_t>(cam)]; }
  /// Camera pose T_w_c = T_w_b * T_b_c.
  SE3d camera_pose(int cam, const SE3d& T_w_b) const { return T_w_b * T_b_c(cam); }

  /// Renders camera `cam` (0 or 1) at pose T_w_c into `image` (reallocated to CV_8UC1,
  /// height x width). InvalidArgument for a bad camera index or a non-finite pose.
  Status render(int cam, const SE3d& T_w_c, const FrameInfo& frame, cv::Mat* image) const;
  StatusOr<cv::Mat> render(int cam, const SE3d& T_w_c, const FrameInfo& frame) const;
  /// Both cameras at body pose T_w_b (one after the other, each with all threads).
  StatusOr<std::array<cv::Mat, 2>> render_stereo(const SE3d& T_w_b, const FrameInfo& frame) const;

  /// Camera `cam` integrated over its exposure (motion blur): the mean radiance of the poses
  /// T_w_c (the exposure's sub-samples, evenly spaced in time, at `times_ns` when given,
  /// else all at frame.t_ns), then the DN mapping. One pose: render(). InvalidArgument for
  /// none, a non-finite one, a bad camera index or times of another size.
  Status render_exposure(int cam, const std::vector<SE3d>& T_w_c, const FrameInfo& frame, cv::Mat* image,
                         const std::vector<TimestampNs>& times_ns = {}) const;
  /// Sub-samples an exposure of camera `cam` from pose T_w_a to T_w_b needs for no surface
  /// point seen at a 9 x 7 grid of pixels (the sky: its direction) to move more than step_px
  /// between two: ceil(largest motion / step_px), in [1, max_samples].
  int exposure_samples(int cam, const SE3d& T_w_a, const SE3d& T_w_b, double step_px, int max_samples) const;

  /// Radiance in [0, 1] before the DN mapping (CV_32F), as the image render computes it
  /// (people where they are at t_ns).
  StatusOr<cv::Mat> render_radiance(int cam, const SE3d& T_w_c, TimestampNs t_ns = 0) const;
  /// Depth, face id, face (u, v) and mip level of every pixel centre ray.
  StatusOr<TruthImage> render_truth(int cam, const SE3d& T_w_c) const;

  /// Casts the ray of (sub)pixel `uv` of camera `cam` at pose T_w_c (camera unproject, not
  /// the table). nullopt when the ray hits nothing or uv cannot be unprojected.
  std::optional<PixelHit> cast_pixel(int cam, const SE3d& T_w_c, const Vec2d& uv) const;

  /// The surface point seen at pixel `uv` of camera `cam_from` (pose T_w_from), projected
  /// into camera `cam_to` at pose T_w_to. nullopt when the ray hits nothing, the point is
  /// behind or outside the target image, or it is occluded there (a ray cast from the target
  /// camera towards the point stops more than max(1 mm, 1e-3 * range) short of it).
  std::optional<Correspondence> correspondence(int cam_from, const SE3d& T_w_from, const Vec2d& uv,
                                               int cam_to, const SE3d& T_w_to) const;
  /// True optical flow of pixel `uv` of camera `cam` from pose T_w_c0 to pose T_w_c1:
  /// the target pixel minus uv (see correspondence() for when it is nullopt).
  std::optional<Vec2d> true_flow(int cam, const SE3d& T_w_c0, const SE3d& T_w_c1, const Vec2d& uv) const;

 private:
  struct FaceInfo {
    Eigen::Vector3f normal;
    float inv_texel = 1.0f;  ///< 1 / level-0 texel size, 1/m
  };
  struct View;  // one camera at one pose (defined in the .cpp)

  StereoRenderer() = default;
  Status check_request(int cam, const SE3d& T_w_c) const;
  View make_view(int cam, const SE3d& T_w_c, TimestampNs t_ns = 0) const;
  /// The nearest person along pixel (u, v)'s ray d_w closer than max_t: its distance and index.
  std::optional<std::pair<float, int>> nearest_person(const View& view, int u, int v,
                                                      const Eigen::Vector3f& d_w, float max_t) const;
  /// Albedo times light of person `index` where ray d_w meets it at distance t.
  float shade_person(const View& view, const Eigen::Vector3f& d_w, std::pair<float, int> hit) const;
  float shade_center(const View& view, int u, int v, int* face) const;
  float shade_supersampled(const View& view, int u, int v) const;
  void render_pass(const View& view, std::vector<float>* radiance, std::vector<int>* faces) const;
  void refine_edges(const View& view, const std::vector<int>& faces, std::vector<float>* radiance) const;
  /// The DN image of camera `cam` from its radiance (row-major) times `scale` (photometry.h).
  Status to_image(int cam, const FrameInfo& frame, const std::vector<float>& radiance, float scale,
                  cv::Mat* image) const;

  const Scene* scene_ = nullptr;
  RenderOptions options_;
  std::uint64_t noise_seed_ = 0;
  std::array<std::shared_ptr<const camera::CameraModel>, 2> cameras_;
  std::array<SE3d, 2> T_b_c_;
  std::array<std::shared_ptr<const RayTable>, 2> tables_;
  std::shared_ptr<const std::vector<FaceInfo>> faces_;
  Illumination light_;
  std::shared_ptr<const std::vector<Walker>> walkers_;
};

}  // namespace mrvs::sim
