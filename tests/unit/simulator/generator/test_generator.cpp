// End-to-end checks of the generator on short sequences: the files pass the project's EuRoC
// reader, the IMU and ground truth files agree, map points and images agree geometrically
// and photometrically, output is deterministic, bad input leaves nothing behind.
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "generated_sequence.h"
#include "mrvs/config/calibration.h"
#include "mrvs/io/dataset.h"
#include "mrvs/io/trajectory_io.h"
#include "mrvs/sim/calibration_error.h"
#include "mrvs/sim/exposure_log.h"
#include "mrvs/sim/map_io.h"
#include "mrvs/sim/people_plan.h"
#include "mrvs/sim/test/strapdown.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::sim {
namespace {

using ::testing::HasSubstr;

class GeneratedIndoor : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new mrvs::test::TempDir();
    request_ = new GeneratorRequest(test::indoor_request(dir_->path() / "seq"));
    // Under CTest the fixture step generated it with dataset_simulator; a copy is enough.
    const std::filesystem::path shared = test::shared_indoor_sequence();
    if (!shared.empty()) {
      std::filesystem::copy(shared, request_->out, std::filesystem::copy_options::recursive);
    } else {
      auto report = generate_dataset(*request_);
      ASSERT_TRUE(report.ok()) << report.status();
    }
    auto world = build_world(*request_);
    ASSERT_TRUE(world.ok()) << world.status();
    world_ = new World(std::move(*world));
    io::DatasetOptions options;
    options.path = dir_->path() / "seq";
    auto dataset = io::open_dataset("euroc", options);
    ASSERT_TRUE(dataset.ok()) << dataset.status();
    dataset_ = dataset->release();
  }
  static void TearDownTestSuite() {
    delete dataset_;
    delete world_;
    delete request_;
    delete dir_;
  }
  static mrvs::test::TempDir* dir_;
  static GeneratorRequest* request_;
  static World* world_;
  static io::DatasetReader* dataset_;
};
mrvs::test::TempDir* GeneratedIndoor::dir_ = nullptr;
GeneratorRequest* GeneratedIndoor::request_ = nullptr;
World* GeneratedIndoor::world_ = nullptr;
io::DatasetReader* GeneratedIndoor::dataset_ = nullptr;

TEST_F(GeneratedIndoor, TheProjectsEurocReaderTakesItUnchanged) {
  ASSERT_NE(dataset_, nullptr);
  EXPECT_TRUE(dataset_->warnings().empty()) << dataset_->warnings().front();
  EXPECT_EQ(dataset_->stereo_frames().size(), world_->grid.camera_true_ns.size());
  EXPECT_EQ(dataset_->imu().size(), world_->grid.imu_ns.size());
  EXPECT_EQ(dataset_->groundtruth().size(), dataset_->imu().size());
  EXPECT_EQ(dataset_->stereo_frames().size(), 20u);  // 1 s at 20 Hz
  for (int cam = 0; cam < 2; ++cam) {
    auto image = dataset_->load_image(cam, dataset_->images()[cam].front());
    ASSERT_TRUE(image.ok()) << image.status();
    EXPECT_EQ(image->cols, 752);
    EXPECT_EQ(image->rows, 480);
    EXPECT_EQ(image->type(), CV_8UC1);
  }
  EXPECT_TRUE(std::filesystem::exists(dir_->path() / "seq/mav0/pointcloud0/data.ply"));
  for (const char* f : {"config.yaml", "scene.yaml", "imu_noiseless.csv", "T_map_world.yaml"}) {
    EXPECT_TRUE(std::filesystem::exists(dir_->path() / "seq/sim0" / f)) << f;
  }
}

TEST_F(GeneratedIndoor, HasNoGnss) {
  EXPECT_FALSE(request_->options.gnss.enabled);
  EXPECT_FALSE(std::filesystem::exists(dir_->path() / "seq/mav0/gnss0"));
  EXPECT_FALSE(std::filesystem::exists(dir_->path() / "seq/sim0/gnss_truth.csv"));
  EXPECT_TRUE(world_->gnss.empty());
  EXPECT_FALSE(dataset_->has_gnss());
  EXPECT_FALSE(dataset_->T_b_gnss().has_value());
}

TEST_F(GeneratedIndoor, TheRequestReadBackRebuildsTheSameWorld) {
  auto request = load_generator_request(dir_->path() / "seq");
  ASSERT_TRUE(request.ok()) << request.status();
  EXPECT_TRUE(request->options == request_->options);
  EXPECT_EQ(request->profile, request_->profile);
  EXPECT_EQ(request->preset, request_->preset);
  EXPECT_EQ(std::filesystem::canonical(request->trajectory),
            std::filesystem::canonical(request_->trajectory));
  auto world = build_world(*request);
  ASSERT_TRUE(world.ok()) << world.status();
  ASSERT_EQ(world->map.points.size(), world_->map.points.size());
  EXPECT_EQ(world->map.points.back().position, world_->map.points.back().position);
  EXPECT_EQ(world->frame_pose(5).matrix(), world_->frame_pose(5).matrix());
  EXPECT_FALSE(load_generator_request(dir_->path() / "nowhere").ok());
}

TEST_F(GeneratedIndoor, StampsAreExactAndCamerasTickOnImuStamps) {
  const auto& imu = dataset_->imu();
  for (std::size_t k = 1; k < imu.size(); ++k) ASSERT_EQ(imu[k].t_ns - imu[k - 1].t_ns, 5'000'000) << k;
  const auto& frames = dataset_->stereo_frames();
  for (std::size_t k = 1; k < frames.size(); ++k) {
    ASSERT_EQ(frames[k].t_ns - frames[k - 1].t_ns, 50'000'000) << k;
  }
  for (const io::StereoFrame& f : frames) {
    ASSERT_TRUE(std::binary_search(imu.begin(), imu.end(), f.t_ns, [](const auto& a, const auto& b) {
      auto t = [](const auto& x) {
        if constexpr (std::is_same_v<std::decay_t<decltype(x)>, TimestampNs>) {
          return x;
        } else {
          return x.t_ns;
        }
      };
      return t(a) < t(b);
    })) << f.t_ns;
  }
  EXPECT_LT(imu.front().t_ns, frames.front().t_ns);  // an IMU row precedes the first image
}

TEST_F(GeneratedIndoor, NoiselessImuFileReproducesTheGroundTruthFile) {
  auto noiseless = io::read_euroc_imu_csv(dir_->path() / "seq/sim0/imu_noiseless.csv");
  ASSERT_TRUE(noiseless.ok()) << noiseless.status();
  const auto& gt = dataset_->groundtruth();
  ASSERT_EQ(noiseless->size(), gt.size());
  std::vector<Vec3d> gyro, accel;
  for (const io::ImuSample& s : *noiseless) {
    gyro.push_back(s.gyro_radps);
    accel.push_back(s.accel_mps2);
  }
  test::NavState state{gt.front().T_w_b.quaternion(), gt.front().T_w_b.translation(), gt.front().v_w_b};
  const std::size_t last = gt.size() - 1;  // the whole 1 s sequence
  state =
      test::integrate_midpoint(state, gyro, accel, 0, last, 0.005, request_->options.imu.gravity_magnitude);
  EXPECT_LT((state.p_w - gt[last].T_w_b.translation()).norm(), 1e-3);
  EXPECT_LT(quat::angular_distance(state.q_w_b, gt[last].T_w_b.quaternion()) * test::kRadToDeg, 0.01);
  EXPECT_LT((state.v_w - gt[last].v_w_b).norm(), 1e-3);
}

TEST_F(GeneratedIndoor, MeasuredImuIsNoiselessPlusTrueBiasPlusNoise) {
  auto noiseless = io::read_euroc_imu_csv(dir_->path() / "seq/sim0/imu_noiseless.csv");
  ASSERT_TRUE(noiseless.ok());
  const auto& measured = dataset_->imu();
  const auto& gt = dataset_->groundtruth();
  double sum2 = 0.0;
  for (std::size_t k = 0; k < measured.size(); ++k) {
    const Vec3d n = measured[k].gyro_radps - (*noiseless)[k].gyro_radps - gt[k].bias_gyro;
    sum2 += n.squaredNorm();
  }
  const double sigma = std::sqrt(sum2 / (3.0 * measured.size()));
  EXPECT_NEAR(sigma, 1.6968e-4 / std::sqrt(0.005), 0.1 * 1.6968e-4 / std::sqrt(0.005));  // 200 samples
}

TEST_F(GeneratedIndoor, CalibrationFilesAreTheRenderedRig) {
  const Rig rig = euroc_rig();
  for (int cam = 0; cam < 2; ++cam) {
    const auto& c = dataset_->calibration().cameras[cam];
    EXPECT_EQ(c.model->params(), rig.cameras[cam].params);
    EXPECT_LT((c.T_b_c.matrix() - rig.cameras[cam].T_BS).cwiseAbs().maxCoeff(), 1e-12);
  }
  EXPECT_NEAR(dataset_->calibration().T_c0_c1().translation().norm(), 0.11008, 5e-5);
}

// The map points seen in an image: project each into the image, cast that pixel's ray in the
// scene, and compare: the ray hits the map point, the hit reprojects to the pixel, and the
// image there has the map point's intensity.
TEST_F(GeneratedIndoor, MapPointsSeenInImagesReprojectExactlyAndMatchIntensity) {
  auto map = read_ply_xyzi(dir_->path() / "seq/mav0/pointcloud0/data.ply");
  ASSERT_TRUE(map.ok()) << map.status();
  ASSERT_EQ(map->size(), world_->map.points.size());
  const auto& calib = dataset_->calibration().cameras[0];
  const std::size_t frame = 10;
  auto image = dataset_->load_image(0, dataset_->images()[0][frame]);
  ASSERT_TRUE(image.ok());
  const io::GroundTruthState* gt = nullptr;
  for (const auto& s : dataset_->groundtruth()) {
    if (s.t_ns == dataset_->images()[0][frame].t_ns) gt = &s;
  }
  ASSERT_NE(gt, nullptr);
  const SE3d T_w_c = gt->T_w_b * calib.T_b_c;
  const SE3d T_c_w = T_w_c.inverse();
  std::vector<double> dn_image, dn_map;
  double worst_px = 0.0, worst_m = 0.0;
  for (std::size_t i = 0; i < map->size(); i += 7) {
    const Vec3d X = (*map)[i].position.cast<double>();
    auto uv = calib.model->project(T_c_w * X);
    if (!uv || !calib.model->in_image(*uv, 2.0)) continue;
    auto bearing = calib.model->unproject(*uv);
    ASSERT_TRUE(bearing.ok());
    const Vec3d d_w = T_w_c.quaternion() * *bearing;
    auto hit = world_->scene->intersect(T_w_c.translation().cast<float>(), d_w.cast<float>(), 100.0f);
    // Seen: the pixel's ray stops on the face the point was sampled on (the world holds the
    // face ids in PLY order). Otherwise it is occluded or beyond a face edge.
    if (!hit || hit->face != world_->map.points[i].face) continue;
    const Vec3d H = T_w_c.translation() + static_cast<double>(hit->distance) * d_w;
    worst_m = std::max(worst_m, (H - X).norm());
    worst_px = std::max(worst_px, (*calib.model->project(T_c_w * H) - *uv).norm());
    cv::Mat patch;
    cv::getRectSubPix(*image, cv::Size(1, 1), cv::Point2f(float((*uv).x()), float((*uv).y())), patch, CV_32F);
    dn_image.push_back(patch.at<float>(0, 0));
    dn_map.push_back(255.0 * (*map)[i].intensity);
  }
  ASSERT_GT(dn_image.size(), 1000u);
  EXPECT_LT(worst_m, 1e-4);   // the map point is where the pixel's ray meets the surface (float32)
  EXPECT_LT(worst_px, 1e-3);  // and reprojects to that pixel
  const auto n = static_cast<double>(dn_image.size());
  double ma = 0, mb = 0;
  for (std::size_t i = 0; i < dn_image.size(); ++i) ma += dn_image[i] / n, mb += dn_map[i] / n;
  double sab = 0, saa = 0, sbb = 0;
  int close = 0;
  for (std::size_t i = 0; i < dn_image.size(); ++i) {
    sab += (dn_image[i] - ma) * (dn_map[i] - mb);
    saa += (dn_image[i] - ma) * (dn_image[i] - ma);
    sbb += (dn_map[i] - mb) * (dn_map[i] - mb);
    close += std::abs(dn_image[i] - dn_map[i]) < 10.0;
  }
  const double correlation = sab / std::sqrt(saa * sbb);
  std::printf(
      "map vs image: %zu visible points, correlation %.4f, %.1f %% within 10 DN, worst %.2e m, %.2e px\n",
      dn_image.size(), correlation, 100.0 * close / n, worst_m, worst_px);
  EXPECT_GE(correlation, 0.95);
  EXPECT_GE(close / n, 0.90);
}

TEST_F(GeneratedIndoor, SameSeedGivesIdenticalBytesWhateverTheThreadCount) {
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  const auto again = generate_dataset(test::indoor_request(dir_->path() / "again"));
  omp_set_num_threads(threads);
  ASSERT_TRUE(again.ok()) << again.status();
  const auto a = test::read_tree(dir_->path() / "seq");
  const auto b = test::read_tree(dir_->path() / "again");
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [name, bytes] : a) {
    ASSERT_TRUE(b.count(name)) << name;
    EXPECT_TRUE(bytes == b.at(name)) << name << " differs";
  }
}

TEST_F(GeneratedIndoor, AnotherSeedChangesImagesImuAndMap) {
  GeneratorRequest r = test::indoor_request(dir_->path() / "seed2");
  r.options.seed = 2;
  ASSERT_TRUE(generate_dataset(r).ok());
  const auto a = test::read_tree(dir_->path() / "seq");
  const auto b = test::read_tree(dir_->path() / "seed2");
  for (const char* f : {"mav0/imu0/data.csv", "mav0/pointcloud0/data.ply", "sim0/scene.yaml"}) {
    EXPECT_NE(a.at(f), b.at(f)) << f;
  }
  // The motion depends on the trajectory only; the true biases (also in the ground truth) on
  // the seed.
  EXPECT_EQ(a.at("sim0/imu_noiseless.csv"), b.at("sim0/imu_noiseless.csv"));
  auto gt_a = io::read_euroc_groundtruth(dir_->path() / "seq/mav0/state_groundtruth_estimate0/data.csv");
  auto gt_b = io::read_euroc_groundtruth(dir_->path() / "seed2/mav0/state_groundtruth_estimate0/data.csv");
  ASSERT_TRUE(gt_a.ok() && gt_b.ok());
  ASSERT_EQ(gt_a->size(), gt_b->size());
  for (std::size_t k = 0; k < gt_a->size(); ++k) {
    ASSERT_EQ((*gt_a)[k].T_w_b.matrix(), (*gt_b)[k].T_w_b.matrix()) << k;
  }
  EXPECT_NE(gt_a->back().bias_accel, gt_b->back().bias_accel);
}

TEST_F(GeneratedIndoor, MotionBlurChangesOnlyTheImagesAndIsDeterministic) {
  GeneratorRequest r = test::indoor_request(dir_->path() / "blur");
  r.options.render.motion_blur = true;
  r.options.render.exposure_ms = 10.0;
  ASSERT_TRUE(generate_dataset(r).ok());
  const int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  r.out = dir_->path() / "blur_again";
  const auto again = generate_dataset(r);
  omp_set_num_threads(threads);
  ASSERT_TRUE(again.ok()) << again.status();
  const auto sharp = test::read_tree(dir_->path() / "seq");
  const auto blur = test::read_tree(dir_->path() / "blur");
  EXPECT_TRUE(blur == test::read_tree(dir_->path() / "blur_again"));
  ASSERT_EQ(sharp.size(), blur.size());
  int images = 0, blurred = 0;
  double sharp_gradient = 0.0, blur_gradient = 0.0;  // blur removes image gradient
  for (const auto& [name, bytes] : sharp) {
    ASSERT_TRUE(blur.count(name)) << name;
    if (name.rfind(".png") != name.size() - 4) {
      if (name != "sim0/config.yaml" && name != "sim0/request.yaml" && name != "sim0/exposure.csv") {
        EXPECT_TRUE(bytes == blur.at(name)) << name;
      }
      continue;
    }
    ++images;
    blurred += bytes != blur.at(name);
    const cv::Mat a = cv::imread((dir_->path() / "seq" / name).string(), cv::IMREAD_GRAYSCALE);
    const cv::Mat b = cv::imread((dir_->path() / "blur" / name).string(), cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(a.empty() || b.empty()) << name;
    cv::Mat ga, gb;
    cv::Sobel(a, ga, CV_32F, 1, 0);
    cv::Sobel(b, gb, CV_32F, 1, 0);
    sharp_gradient += cv::norm(ga, cv::NORM_L1);
    blur_gradient += cv::norm(gb, cv::NORM_L1);
  }
  EXPECT_EQ(images, 2 * static_cast<int>(world_->grid.camera_true_ns.size()));
  EXPECT_GT(blurred, images / 2) << "V1_01 moves at 20 s: most frames blur over 10 ms";
  EXPECT_LT(blur_gradient, sharp_gradient);
}

/// sim0/exposure.csv of a sequence generated from `r`; empty after a failure (reported).
std::vector<FrameExposure> exposures_of(const GeneratorRequest& r) {
  const auto report = generate_dataset(r);
  EXPECT_TRUE(report.ok()) << report.status();
  if (!report.ok()) return {};
  auto frames = read_exposure_csv(r.out / "sim0/exposure.csv");
  EXPECT_TRUE(frames.ok()) << frames.status();
  return frames.ok() ? *frames : std::vector<FrameExposure>{};
}

double median_exposure(std::vector<FrameExposure> frames) {
  std::sort(frames.begin(), frames.end(),
            [](const FrameExposure& a, const FrameExposure& b) { return a.exposure_ms < b.exposure_ms; });
  return frames[frames.size() / 2].exposure_ms;
}

// Auto-exposure in a generated sequence: the image mean stays near the target; a room 4x
// darker takes 4x the exposure (and blurs more); one too dark for the longest exposure
// saturates at it with the full analog gain. Every frame within its bounds.
TEST_F(GeneratedIndoor, AutoExposureLengthensTheExposureInTheDarkWithinItsBounds) {
  GeneratorRequest r = test::indoor_request(dir_->path() / "ae");
  r.options.render.auto_exposure = true;
  const std::vector<FrameExposure> lit = exposures_of(r);
  r.out = dir_->path() / "ae_dim";
  r.options.render.dim_area = true;  // the whole room at 1/4 of the light
  r.options.render.dim_level = 0.25;
  r.options.render.dim_radius_m = 1000.0;
  r.options.render.motion_blur = true;
  const std::vector<FrameExposure> dim = exposures_of(r);
  r.out = dir_->path() / "ae_dark";
  r.options.render.dim_level = 0.01;
  r.options.render.motion_blur = false;
  const std::vector<FrameExposure> dark = exposures_of(r);
  const std::size_t frames = world_->grid.camera_true_ns.size();
  ASSERT_EQ(lit.size(), frames);
  ASSERT_EQ(dim.size(), frames);
  ASSERT_EQ(dark.size(), frames);
  const RenderOptions& o = r.options.render;
  for (const auto* run : {&lit, &dim, &dark}) {
    for (std::size_t k = 0; k < frames; ++k) {
      const FrameExposure& f = (*run)[k];
      EXPECT_EQ(f.t_ns, world_->grid.camera_stamp_ns[k]);
      EXPECT_GE(f.exposure_ms, o.ae_min_exposure_ms);
      EXPECT_LE(f.exposure_ms, o.ae_max_exposure_ms);
      EXPECT_GE(f.analog_gain, 1.0);
      EXPECT_LE(f.analog_gain, o.ae_max_analog_gain + 1e-9);
      if (f.analog_gain > 1.0) {
        EXPECT_EQ(f.exposure_ms, o.ae_max_exposure_ms);
      }
      // The DN scale is exposure x gain over the reference (the easy preset has no walk).
      EXPECT_NEAR(f.gain, f.exposure_ms * f.analog_gain / o.exposure_ms, 1e-9);
    }
  }
  for (std::size_t k = 0; k < frames; ++k) {
    EXPECT_LT(std::abs(std::log2(lit[k].mean_dn / o.ae_target_dn)), 0.35) << k;
    EXPECT_LT(std::abs(std::log2(dim[k].mean_dn / o.ae_target_dn)), 0.35) << k;
    EXPECT_EQ(lit[k].samples, 1) << "no blur asked";
    EXPECT_EQ(dark[k].exposure_ms, o.ae_max_exposure_ms) << k;
    EXPECT_NEAR(dark[k].analog_gain, o.ae_max_analog_gain, 1e-9) << k;
    EXPECT_LT(dark[k].mean_dn, 0.5 * o.ae_target_dn) << k;
  }
  const double ratio = median_exposure(dim) / median_exposure(lit);
  EXPECT_GT(ratio, 4.0 * std::exp2(-0.35));
  EXPECT_LT(ratio, 4.0 * std::exp2(0.35));
  int blurred = 0;
  for (const FrameExposure& f : dim) blurred += f.samples > 1;
  EXPECT_GT(blurred, static_cast<int>(frames) / 2) << "V1_01 moves at 20 s: a ~20 ms exposure blurs";
  const auto light = read_illumination_yaml(dir_->path() / "ae_dim/sim0/illumination.yaml");
  ASSERT_TRUE(light.ok()) << light.status();
  EXPECT_TRUE(light->enabled);
  EXPECT_FLOAT_EQ(light->level, 0.25f);
}

// Calibration error: mav0 keeps the written (nominal) calibration, the images are rendered by
// the drawn true rig written to sim0/true_calibration/, and the stamps carry the true offset.
TEST_F(GeneratedIndoor, CalibrationErrorRendersWithTheTrueRigAndWritesTheNominalOne) {
  GeneratorRequest r = test::indoor_request(dir_->path() / "calib");
  r.options.calib_error.enabled = true;
  ASSERT_TRUE(generate_dataset(r).ok());
  const std::filesystem::path seq = dir_->path() / "seq", calib = dir_->path() / "calib";
  const auto nominal_tree = test::read_tree(seq), calib_tree = test::read_tree(calib);
  for (const char* file : {"mav0/cam0/sensor.yaml", "mav0/cam1/sensor.yaml", "mav0/imu0/sensor.yaml"}) {
    ASSERT_TRUE(nominal_tree.count(file) && calib_tree.count(file)) << file;
    EXPECT_EQ(nominal_tree.at(file), calib_tree.at(file)) << file;
  }
  auto world = build_world(r);
  ASSERT_TRUE(world.ok()) << world.status();
  const TrueCalibration drawn = draw_true_calibration(world->rig, 0.0, r.options.calib_error, 1);
  EXPECT_EQ(world->time_offset_ms, drawn.time_offset_ms);
  const StatusOr<double> td = read_true_time_offset_ms(calib / "sim0/true_calibration");
  ASSERT_TRUE(td.ok()) << td.status();
  EXPECT_EQ(*td, drawn.time_offset_ms);
  EXPECT_NE(*td, 0.0);
  config::StereoRigCalibration truth = world->calibration;
  for (int c = 0; c < 2; ++c) {
    auto cam =
        config::load_euroc_camera_yaml(calib / fmt::format("sim0/true_calibration/cam{}/sensor.yaml", c));
    ASSERT_TRUE(cam.ok()) << cam.status();
    truth.cameras[static_cast<std::size_t>(c)] = *cam;
  }
  auto true_renderer = StereoRenderer::create(*world->scene, truth, r.options.render, 1);
  auto written_renderer = StereoRenderer::create(*world->scene, world_->calibration, r.options.render, 1);
  ASSERT_TRUE(true_renderer.ok() && written_renderer.ok());
  const std::size_t frames = world->grid.camera_true_ns.size();
  for (std::size_t k : {std::size_t{0}, frames / 2, frames - 1}) {
    // Written stamp = true time - t_d.
    EXPECT_EQ(world->grid.camera_stamp_ns[k],
              world->grid.camera_true_ns[k] - std::llround(drawn.time_offset_ms * 1e6));
    const std::string png = fmt::format("mav0/cam1/data/{}.png", world->grid.camera_stamp_ns[k]);
    const cv::Mat image = cv::imread((calib / png).string(), cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(image.empty()) << png;
    const FrameInfo info{static_cast<std::int64_t>(k), 1.0};
    const SE3d& T_w_b = world->frame_pose(k);
    auto expected = true_renderer->render(1, true_renderer->camera_pose(1, T_w_b), info);
    auto nominal = written_renderer->render(1, written_renderer->camera_pose(1, T_w_b), info);
    ASSERT_TRUE(expected.ok() && nominal.ok());
    EXPECT_EQ(cv::norm(image, *expected, cv::NORM_INF), 0.0) << png;
    EXPECT_GT(cv::norm(image, *nominal, cv::NORM_L1) / static_cast<double>(image.total()), 2.0)
        << png << ": the true rig moves the image";
  }
}

// Moving people: planned clear of the camera, crossing its view, counted per frame, in the
// images only where counted, never in the map.
TEST_F(GeneratedIndoor, PeopleCrossTheViewClearOfTheCameraAndStayOutOfTheMap) {
  GeneratorRequest r = test::indoor_request(dir_->path() / "people");
  r.options.people.count = 2;
  ASSERT_TRUE(generate_dataset(r).ok());
  auto world = build_world(r);
  ASSERT_TRUE(world.ok()) << world.status();
  ASSERT_EQ(world->people.size(), 2u);
  const auto rows = read_people_csv(dir_->path() / "people/sim0/people.csv");
  ASSERT_TRUE(rows.ok()) << rows.status();
  const std::size_t frames = world->grid.camera_true_ns.size();
  ASSERT_EQ(rows->size(), frames);
  const PeopleOptions& o = r.options.people;
  int seen = 0;
  for (std::size_t k = 0; k < frames; ++k) {
    EXPECT_EQ((*rows)[k].t_ns, world->grid.camera_stamp_ns[k]);
    const TimestampNs t = world->grid.camera_true_ns[k];
    for (const Walker& w : world->people) {
      const double gap = (w.centre(t).head<2>() - world->frame_pose(k).translation().head<2>()).norm();
      EXPECT_GE(gap, o.clearance_m + 0.5 * std::hypot(o.width_m, o.depth_m)) << k;
    }
    seen += (*rows)[k].pixels[0] > 0;
    const std::string png = fmt::format("mav0/cam0/data/{}.png", world->grid.camera_stamp_ns[k]);
    const cv::Mat with = cv::imread((dir_->path() / "people" / png).string(), cv::IMREAD_GRAYSCALE);
    const cv::Mat without = cv::imread((dir_->path() / "seq" / png).string(), cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(with.empty() || without.empty()) << png;
    cv::Mat diff;
    cv::compare(with, without, diff, cv::CMP_NE);
    const int changed = cv::countNonZero(diff);
    EXPECT_LE(changed, 1.1 * static_cast<double>((*rows)[k].pixels[0]) + 50.0) << png;  // + edge pixels
    EXPECT_GE(changed, 0.8 * static_cast<double>((*rows)[k].pixels[0])) << png;
  }
  // 20 frames of a 1 s window: each person is drawn to be in front of cam0 at some time of it.
  EXPECT_GT(seen, 0);
  const auto plain = test::read_tree(dir_->path() / "seq");
  const auto people = test::read_tree(dir_->path() / "people");
  EXPECT_TRUE(plain.at("mav0/pointcloud0/data.ply") == people.at("mav0/pointcloud0/data.ply"))
      << "not in the map";
}

// Bad input: a clear error, nothing at --out, no staging folder left in its parent.
class GeneratorBadInput : public ::testing::Test {
 protected:
  void expect_fails_cleanly(const GeneratorRequest& r, const std::string& message_part) {
    auto report = generate_dataset(r);
    ASSERT_FALSE(report.ok());
    EXPECT_THAT(std::string(report.status().message()), HasSubstr(message_part));
    EXPECT_FALSE(std::filesystem::exists(r.out));
    if (std::filesystem::exists(r.out.parent_path())) {
      for (const std::string& name : test::list_dir(r.out.parent_path())) {
        EXPECT_EQ(name.find(".partial"), std::string::npos) << name << " left behind";
      }
    }
  }
  mrvs::test::TempDir dir_;
};

TEST_F(GeneratorBadInput, MissingTrajectoryFile) {
  GeneratorRequest r = test::indoor_request(dir_ / "out");
  r.trajectory = dir_ / "no_such_trajectory.txt";
  expect_fails_cleanly(r, "no_such_trajectory.txt");
}

TEST_F(GeneratorBadInput, MalformedTrajectoryFile) {
  GeneratorRequest r = test::indoor_request(dir_ / "out");
  r.trajectory = dir_.write("bad.txt", "1403715274.30214 0.878612 2.142470 0.947262 -0.828459 -0.058956\n");
  expect_fails_cleanly(r, "bad.txt:1");
}

TEST_F(GeneratorBadInput, WindowOutsideTheTrajectory) {
  GeneratorRequest r = test::indoor_request(dir_ / "out", 5.0, 1000.0);
  expect_fails_cleanly(r, "window");
}

TEST_F(GeneratorBadInput, UnwritableOutputFolder) {
  dir_.write("a_file", "x");
  GeneratorRequest r = test::indoor_request(dir_ / "a_file" / "out");
  auto report = generate_dataset(r);
  ASSERT_FALSE(report.ok());
  EXPECT_THAT(std::string(report.status().message()), HasSubstr("a_file"));
}

TEST_F(GeneratorBadInput, ExistingOutputIsKeptUnlessOverwriteIsAsked) {
  dir_.write("out/keep.txt", "mine");
  GeneratorRequest r = test::indoor_request(dir_ / "out", 0.3);
  auto refused = generate_dataset(r);
  ASSERT_FALSE(refused.ok());
  EXPECT_THAT(std::string(refused.status().message()), HasSubstr("--overwrite"));
  EXPECT_TRUE(std::filesystem::exists(dir_ / "out/keep.txt"));
  r.overwrite = true;
  ASSERT_TRUE(generate_dataset(r).ok());
  EXPECT_FALSE(std::filesystem::exists(dir_ / "out/keep.txt"));
  EXPECT_TRUE(std::filesystem::exists(dir_ / "out/mav0/imu0/data.csv"));
  for (const std::string& name : test::list_dir(dir_.path()))
    EXPECT_EQ(name.find(".partial"), std::string::npos);
}

TEST(GeneratorOutdoor, WritesAKaistLikeSequenceTheReaderTakes) {
  mrvs::test::TempDir dir;
  GeneratorRequest r;
  r.profile = SceneProfile::kOutdoor;
  r.out = dir / "street";
  r.options = default_options(SceneProfile::kOutdoor);
  r.options.trajectory.window_start_s = 10.0;  // moving
  r.options.trajectory.window_duration_s = 1.0;
  auto report = generate_dataset(r);
  ASSERT_TRUE(report.ok()) << report.status();
  io::DatasetOptions options;
  options.path = dir / "street";
  auto dataset = io::open_dataset("euroc", options);
  ASSERT_TRUE(dataset.ok()) << dataset.status();
  EXPECT_TRUE((*dataset)->warnings().empty());
  EXPECT_EQ((*dataset)->stereo_frames().size(), 10u);  // 10 Hz
  EXPECT_EQ((*dataset)->imu().size(), 101u);           // 100 Hz
  EXPECT_EQ((*dataset)->gnss().size(), 2u);            // 1 Hz, at 0 and 1 s
  EXPECT_NEAR((*dataset)->calibration().T_c0_c1().translation().norm(), 0.47515, 5e-5);
  auto image = (*dataset)->load_image(0, (*dataset)->images()[0].front());
  ASSERT_TRUE(image.ok()) << image.status();
  EXPECT_EQ(image->cols, 1280);
  EXPECT_EQ(image->rows, 560);
  EXPECT_GT(report->map_points, 1000);
  // The car moves at about 10 m/s.
  const auto& gt = (*dataset)->groundtruth();
  EXPECT_NEAR(gt.back().v_w_b.norm(), 10.0, 1.0);
}

TEST(GeneratorOptions, PresetsAndProfilesDiffer) {
  SimulatorOptions easy = default_options(SceneProfile::kIndoor);
  SimulatorOptions realistic = easy;
  ASSERT_TRUE(apply_preset("easy", SceneProfile::kIndoor, easy).ok());
  ASSERT_TRUE(apply_preset("realistic", SceneProfile::kIndoor, realistic).ok());
  EXPECT_FALSE(easy == realistic);
  EXPECT_GT(realistic.render.read_noise_sigma, 0.0);
  EXPECT_TRUE(realistic.render.exposure_walk);
  EXPECT_GT(realistic.map.holes_fraction, 0.0);
  // Issue 31's knobs: on in hard, off in easy and realistic; the scanner survey indoors only.
  SimulatorOptions hard = default_options(SceneProfile::kIndoor);
  ASSERT_TRUE(apply_preset("hard", SceneProfile::kIndoor, hard).ok());
  for (const SimulatorOptions* o : {&easy, &realistic, &hard}) {
    const bool on = o == &hard;
    EXPECT_EQ(o->render.motion_blur, on);
    EXPECT_EQ(o->render.auto_exposure, on);
    EXPECT_EQ(o->render.dim_area, on);
    EXPECT_EQ(o->calib_error.enabled, on);
    EXPECT_EQ(o->people.count > 0, on);
    EXPECT_EQ(o->map.model == MapModel::kScanner, on);
  }
  // hard is realistic plus those: the realistic knobs are all there.
  EXPECT_EQ(hard.render.read_noise_sigma, realistic.render.read_noise_sigma);
  EXPECT_EQ(hard.map.holes_fraction, realistic.map.holes_fraction);
  SimulatorOptions street = default_options(SceneProfile::kOutdoor);
  ASSERT_TRUE(apply_preset("hard", SceneProfile::kOutdoor, street).ok());
  EXPECT_EQ(street.map.model, MapModel::kSurface);
  EXPECT_TRUE(street.render.motion_blur);
  const Status bad = apply_preset("impossible", SceneProfile::kIndoor, easy);
  ASSERT_FALSE(bad.ok());
  EXPECT_THAT(std::string(bad.message()), HasSubstr("easy, realistic, hard"));
  EXPECT_NE(default_options(SceneProfile::kOutdoor).imu.gravity_magnitude,
            default_options(SceneProfile::kIndoor).imu.gravity_magnitude);
  EXPECT_FALSE(parse_profile("underwater").ok());
}

}  // namespace
}  // namespace mrvs::sim
