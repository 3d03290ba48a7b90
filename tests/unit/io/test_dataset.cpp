#include <algorithm>
#include <fstream>
#include <sstream>
#include <string>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "euroc_fixture.h"
#include "mrvs/camera/camera_model.h"
#include "mrvs/io/dataset.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::io {
namespace {

using test_fixture::EurocSpec;
using test_fixture::image_t_ns;
using test_fixture::imu_t_ns;
using ::testing::HasSubstr;

std::string message(const Status& s) { return std::string(s.message()); }

std::string all_warnings(const DatasetReader& d) {
  std::string text;
  for (const std::string& w : d.warnings()) text += w + "\n";
  return text;
}

StatusOr<std::unique_ptr<DatasetReader>> open(const std::filesystem::path& path,
                                              DatasetOptions options = {}) {
  options.path = path;
  return open_dataset("euroc", options);
}

/// Replaces the whole text of a file.
void overwrite(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

TEST(EurocDataset, ReadsEverythingFromTheSequenceFolder) {
  test::TempDir dir;
  const EurocSpec spec;
  const auto seq = test_fixture::write_euroc_sequence(dir, spec);
  const auto d = open(seq);
  ASSERT_TRUE(d.ok()) << d.status();
  const DatasetReader& data = **d;
  EXPECT_EQ(data.format(), "euroc");
  EXPECT_TRUE(data.warnings().empty()) << all_warnings(data);
  for (int cam = 0; cam < 2; ++cam) {
    const auto& images = data.images()[static_cast<std::size_t>(cam)];
    ASSERT_EQ(images.size(), 10u);
    for (int k = 0; k < spec.frames; ++k) {
      EXPECT_EQ(images[k].t_ns, image_t_ns(spec, k));
      EXPECT_EQ(images[k].path, seq / "mav0" / fmt::format("cam{}", cam) / "data" /
                                    fmt::format("{}.png", image_t_ns(spec, k)));
    }
  }
  EXPECT_EQ(data.images()[0][0].t_ns, std::int64_t{1403636579763555584});
  ASSERT_EQ(data.stereo_frames().size(), 10u);
  EXPECT_EQ(data.stereo_frames()[3].t_ns, image_t_ns(spec, 3));
  EXPECT_EQ(data.stereo_frames()[3].left.path, data.images()[0][3].path);
  EXPECT_EQ(data.stereo_frames()[3].right.path, data.images()[1][3].path);
  ASSERT_EQ(data.imu().size(), 100u);
  for (int k = 0; k < 100; ++k) {
    ASSERT_EQ(data.imu()[k].t_ns, imu_t_ns(spec, k));
    ASSERT_EQ(data.imu()[k].gyro_radps, test_fixture::imu_gyro(k)) << k;
    ASSERT_EQ(data.imu()[k].accel_mps2, test_fixture::imu_accel(k)) << k;
  }
  // Row 3 as written: "...,0.03, -0.125, 3e-05, 9.81, -1.5, 3.1".
  EXPECT_EQ(data.imu()[3].gyro_radps, Vec3d(0.03, -0.125, 3e-05));
  EXPECT_EQ(data.imu()[3].accel_mps2, Vec3d(9.81, -1.5, 3.1));
  ASSERT_TRUE(data.has_groundtruth());
  ASSERT_EQ(data.groundtruth().size(), 100u);
  EXPECT_EQ(data.groundtruth()[2].T_w_b.translation(), Vec3d(4.5 + 0.001 * 2, -1.786938, 0.783338));
  EXPECT_NEAR(data.groundtruth()[2].T_w_b.quaternion().w(), 0.534108, 1e-5);
  EXPECT_NEAR(data.groundtruth()[2].T_w_b.quaternion().z(), -0.082152, 1e-5);
  EXPECT_EQ(data.groundtruth()[2].v_w_b.x(), -0.027876 * 2);
}

TEST(EurocDataset, SummarisesCountsSpansRatesAndGaps) {
  test::TempDir dir;
  const EurocSpec spec;
  const auto d = open(test_fixture::write_euroc_sequence(dir, spec, "V1_01_easy"));
  ASSERT_TRUE(d.ok()) << d.status();
  const DatasetSummary& s = (*d)->summary();
  EXPECT_EQ(s.name, "V1_01_easy");
  EXPECT_EQ(s.cameras[0].count, 10u);
  EXPECT_EQ(s.cameras[1].first_ns, image_t_ns(spec, 0));
  EXPECT_EQ(s.cameras[1].last_ns, image_t_ns(spec, 9));
  EXPECT_NEAR(s.cameras[0].rate_hz, 20.0, 1e-9);
  EXPECT_EQ(s.cameras[0].median_period_ns, 50'000'000);
  EXPECT_EQ(s.cameras[0].nominal_period_ns, 50'000'000);
  EXPECT_EQ(s.stereo.count, 10u);
  EXPECT_EQ(s.unmatched[0], 0u);
  EXPECT_EQ(s.imu.count, 100u);
  EXPECT_NEAR(s.imu.rate_hz, 200.0, 1e-9);
  EXPECT_NEAR(s.imu.span_s(), 0.495, 1e-12);
  EXPECT_EQ(s.imu.gap_count, 0u);
  ASSERT_TRUE(s.groundtruth.has_value());
  EXPECT_EQ(s.groundtruth->count, 100u);
  const std::string text = s.describe();
  EXPECT_THAT(text, HasSubstr("euroc sequence 'V1_01_easy'"));
  EXPECT_THAT(
      text,
      HasSubstr("imu0: 100 samples, 1403636579.758555584 .. 1403636580.253555584 s (0.495 s), 200.00 Hz"));
}

TEST(EurocDataset, AcceptsTheMav0FolderAndLoadsCalibration) {
  test::TempDir dir;
  const auto d = open(test_fixture::write_euroc_sequence(dir, {}) / "mav0");
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_EQ((*d)->summary().name, "MH_test");
  const config::StereoRigCalibration& calib = (*d)->calibration();
  ASSERT_NE(calib.cameras[0].model, nullptr);
  ASSERT_NE(calib.cameras[1].model, nullptr);
  EXPECT_EQ(calib.cameras[0].model->width(), 16);
  EXPECT_EQ(calib.cameras[0].model->height(), 12);
  EXPECT_EQ(calib.cameras[0].model->fx(), 20.5);
  EXPECT_EQ(calib.cameras[1].model->cx(), 8.0);
  EXPECT_EQ(calib.cameras[0].rate_hz, 20.0);
  EXPECT_NEAR(
      (calib.cameras[0].T_b_c.translation() - Vec3d(-0.0216401454975, -0.064676986768, 0.00981073058949))
          .norm(),
      0.0, 1e-12);
  EXPECT_NEAR(calib.cameras[1].T_b_c.translation().y(), 0.0453689425024, 1e-12);
  EXPECT_EQ(calib.imu.rate_hz, 200.0);
  EXPECT_EQ(calib.imu.gyroscope_noise_density, 1.6968e-04);
  EXPECT_EQ(calib.imu.accelerometer_random_walk, 3.0e-3);
}

TEST(EurocDataset, LoadsImagesOnDemandAndChecksTheirSize) {
  test::TempDir dir;
  const EurocSpec spec;
  const auto seq = test_fixture::write_euroc_sequence(dir, spec);
  const auto d = open(seq);
  ASSERT_TRUE(d.ok()) << d.status();
  const StereoFrame& frame = (*d)->stereo_frames()[4];
  const auto left = (*d)->load_image(0, frame.left);
  const auto right = (*d)->load_image(1, frame.right);
  ASSERT_TRUE(left.ok()) << left.status();
  ASSERT_TRUE(right.ok()) << right.status();
  EXPECT_EQ(left->type(), CV_8UC1);
  EXPECT_EQ(left->at<std::uint8_t>(5, 7), test_fixture::pixel_value(0, 4));
  EXPECT_EQ(right->at<std::uint8_t>(11, 15), test_fixture::pixel_value(1, 4));
  EXPECT_FALSE((*d)->load_image(2, frame.left).ok());
  // An image of another size than the calibration says.
  ASSERT_TRUE(cv::imwrite(frame.left.path.string(), cv::Mat(10, 10, CV_8UC1, cv::Scalar(1))));
  const auto wrong = (*d)->load_image(0, frame.left);
  ASSERT_FALSE(wrong.ok());
  EXPECT_THAT(message(wrong.status()), HasSubstr(frame.left.path.string()));
  EXPECT_THAT(message(wrong.status()), HasSubstr("is 10x10 pixels but the camera calibration says 16x12"));
}

TEST(EurocDataset, MissingFolderIsNamed) {
  test::TempDir dir;
  const auto d = open(dir / "no_such_sequence");
  ASSERT_FALSE(d.ok());
  EXPECT_EQ(d.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(message(d.status()),
              HasSubstr("dataset folder " + (dir / "no_such_sequence").string() + " does not exist"));
  EXPECT_THAT(message(d.status()), HasSubstr("mav0"));
}

TEST(EurocDataset, FolderWithoutEurocLayoutExplainsTheLayout) {
  test::TempDir dir;
  dir.write("seq/readme.txt", "hello\n");
  const auto d = open(dir / "seq");
  ASSERT_FALSE(d.ok());
  EXPECT_THAT(message(d.status()), HasSubstr((dir / "seq").string() + " is not an EuRoC folder"));
  EXPECT_THAT(message(d.status()), HasSubstr("cam0/data.csv"));
}

TEST(EurocDataset, MissingCsvIsNamed) {
  test::TempDir dir;
  const auto seq = test_fixture::write_euroc_sequence(dir, {});
  std::filesystem::remove(seq / "mav0/imu0/data.csv");
  const auto d = open(seq);
  ASSERT_FALSE(d.ok());
  EXPECT_EQ(d.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(message(d.status()),
              HasSubstr("IMU data " + (seq / "mav0/imu0/data.csv").string() + " does not exist"));
}

TEST(EurocDataset, MissingImageFilesAreNamed) {
  test::TempDir dir;
  const EurocSpec spec;
  const auto seq = test_fixture::write_euroc_sequence(dir, spec);
  std::filesystem::remove(seq / fmt::format("mav0/cam1/data/{}.png", image_t_ns(spec, 7)));
  std::filesystem::remove(seq / fmt::format("mav0/cam1/data/{}.png", image_t_ns(spec, 2)));
  const auto d = open(seq);
  ASSERT_FALSE(d.ok());
  EXPECT_EQ(d.status().code(), absl::StatusCode::kNotFound);
  EXPECT_EQ(
      message(d.status()),
      fmt::format("2 of the 10 images listed in {} do not exist in {}: {}.png (line 4), {}.png (line 9); "
                  "re-extract the dataset, or delete those rows from the csv",
                  (seq / "mav0/cam1/data.csv").string(), (seq / "mav0/cam1/data").string(),
                  image_t_ns(spec, 2), image_t_ns(spec, 7)));
  // Without the check the sequence opens, and loading the missing image names it.
  DatasetOptions options;
  options.check_image_files = false;
  const auto lazy = open(seq, options);
  ASSERT_TRUE(lazy.ok()) << lazy.status();
  const auto image = (*lazy)->load_image(1, (*lazy)->images()[1][2]);
  ASSERT_FALSE(image.ok());
  EXPECT_THAT(message(image.status()), HasSubstr(fmt::format("{}.png", image_t_ns(spec, 2))));
}

TEST(EurocDataset, UnmatchedStereoFramesAreCountedAndReported) {
  test::TempDir dir;
  const EurocSpec spec;
  const auto seq = test_fixture::write_euroc_sequence(dir, spec);
  std::string csv = test_fixture::image_csv(spec);
  const std::string row = fmt::format("{}, {}.png\r\n", image_t_ns(spec, 5), image_t_ns(spec, 5));
  csv.erase(csv.find(row), row.size());
  overwrite(seq / "mav0/cam1/data.csv", csv);
  const auto d = open(seq);
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_EQ((*d)->images()[0].size(), 10u);
  EXPECT_EQ((*d)->images()[1].size(), 9u);
  EXPECT_EQ((*d)->stereo_frames().size(), 9u);
  EXPECT_EQ((*d)->summary().unmatched[0], 1u);
  EXPECT_EQ((*d)->summary().unmatched[1], 0u);
  ASSERT_EQ((*d)->warnings().size(), 1u);
  EXPECT_THAT((*d)->warnings()[0],
              HasSubstr(fmt::format("cam0: 1 of 10 frames have no cam1 frame within 0 ns and are not used as "
                                    "stereo frames (t_ns: {})",
                                    image_t_ns(spec, 5))));
}

TEST(EurocDataset, StereoToleranceAcceptsSmallOffsetsOnly) {
  test::TempDir dir;
  EurocSpec spec;
  const auto seq = test_fixture::write_euroc_sequence(dir, spec);
  // cam1 stamps 1 us later: the file names stay those of the images on disk.
  std::string csv = "#timestamp [ns],filename\r\n";
  for (int k = 0; k < spec.frames; ++k)
    csv += fmt::format("{},{}.png\r\n", image_t_ns(spec, k) + 1000, image_t_ns(spec, k));
  overwrite(seq / "mav0/cam1/data.csv", csv);
  const auto exact = open(seq);
  ASSERT_FALSE(exact.ok());
  EXPECT_THAT(message(exact.status()), HasSubstr("no cam0 frame has a cam1 frame"));
  DatasetOptions options;
  options.stereo_tolerance_ns = 1000;
  const auto loose = open(seq, options);
  ASSERT_TRUE(loose.ok()) << loose.status();
  ASSERT_EQ((*loose)->stereo_frames().size(), 10u);
  EXPECT_EQ((*loose)->stereo_frames()[1].t_ns, image_t_ns(spec, 1));
  EXPECT_EQ((*loose)->stereo_frames()[1].right.t_ns, image_t_ns(spec, 1) + 1000);
  options.stereo_tolerance_ns = 25'000'000;  // half the frame period
  const auto too_loose = open(seq, options);
  ASSERT_FALSE(too_loose.ok());
  EXPECT_THAT(message(too_loose.status()), HasSubstr("not below half the camera period"));
}

TEST(EurocDataset, ImuGapsAreSummarisedAndWarned) {
  test::TempDir dir;
  const EurocSpec spec;
  const auto seq = test_fixture::write_euroc_sequence(dir, spec);
  std::string csv;
  std::istringstream in(test_fixture::imu_csv(spec));
  std::string line;
  for (int i = 0; std::getline(in, line); ++i) {
    if (i < 40 || i > 45) csv += line + "\n";  // drops samples 39..44 (30 ms)
  }
  overwrite(seq / "mav0/imu0/data.csv", csv);
  const auto d = open(seq);
  ASSERT_TRUE(d.ok()) << d.status();
  const StreamSummary& imu = (*d)->summary().imu;
  EXPECT_EQ(imu.count, 94u);
  EXPECT_EQ(imu.gap_count, 1u);
  ASSERT_EQ(imu.gaps.size(), 1u);
  EXPECT_EQ(imu.gaps[0].from_ns, imu_t_ns(spec, 38));
  EXPECT_EQ(imu.gaps[0].to_ns, imu_t_ns(spec, 45));
  EXPECT_EQ(imu.largest_period_ns, 35'000'000);
  EXPECT_THAT(all_warnings(**d), HasSubstr("imu0: 94 samples"));
  EXPECT_THAT(all_warnings(**d), HasSubstr("1 gaps longer than 2 x 5.000 ms (largest 35.000 ms"));
}

TEST(EurocDataset, BadCsvRowsNameFileAndLine) {
  test::TempDir dir;
  const EurocSpec spec;
  const auto seq = test_fixture::write_euroc_sequence(dir, spec);
  const auto imu = seq / "mav0/imu0/data.csv";
  std::string csv = test_fixture::imu_csv(spec);
  // Truncated copy: the file ends in the middle of row 51 (line 53).
  std::string truncated = csv.substr(0, csv.find(fmt::format("{},", imu_t_ns(spec, 51))) + 30);
  overwrite(imu, truncated);
  const auto a = open(seq);
  ASSERT_FALSE(a.ok());
  EXPECT_EQ(a.status().code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(message(a.status()), HasSubstr(imu.string() + ":53: expected 7 comma-separated fields"));
  EXPECT_THAT(message(a.status()), HasSubstr("does not end in a newline"));
  // A non-numeric field.
  std::string text = csv;
  const std::string row = fmt::format("{}, 0.02, -0.125, 2e-05", imu_t_ns(spec, 2));
  text.replace(text.find(row), row.size(), fmt::format("{}, 0.02, -O.125, 2e-05", imu_t_ns(spec, 2)));
  overwrite(imu, text);
  const auto b = open(seq);
  ASSERT_FALSE(b.ok());
  EXPECT_EQ(message(b.status()),
            imu.string() +
                ":4: field 3 ('w_RS_S_y [rad s^-1]'): '-O.125' is not a number; fix or delete this line");
  // A bad image row.
  overwrite(seq / "mav0/cam0/data.csv", "#timestamp [ns],filename\n1403636579763555584\n");
  const auto c = open(seq);
  ASSERT_FALSE(c.ok());
  EXPECT_THAT(message(c.status()),
              HasSubstr((seq / "mav0/cam0/data.csv").string() +
                        ":2: expected 2 comma-separated fields (#timestamp [ns],filename), found 1"));
}

TEST(EurocDataset, RowOrderPolicyAppliesToDatasetFiles) {
  test::TempDir dir;
  const EurocSpec spec;
  const auto seq = test_fixture::write_euroc_sequence(dir, spec);
  const auto imu = seq / "mav0/imu0/data.csv";
  std::istringstream in(test_fixture::imu_csv(spec));
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  std::swap(lines[10], lines[11]);  // rows 9 and 10 swapped (file lines 11 and 12)
  const std::string duplicate = lines[20];
  lines.insert(lines.begin() + 20, duplicate);  // an exact duplicate at file line 22
  std::string text;
  for (const std::string& line : lines) text += line + "\n";
  overwrite(imu, text);
  const auto strict = open(seq);
  ASSERT_FALSE(strict.ok());
  EXPECT_THAT(
      message(strict.status()),
      HasSubstr(fmt::format("{}:12: timestamp {} ns is not after the previous timestamp {} ns (line 11)",
                            imu.string(), imu_t_ns(spec, 9), imu_t_ns(spec, 10))));
  EXPECT_THAT(message(strict.status()), HasSubstr("sort the file by its first column"));
  DatasetOptions options;
  options.policy.sort_out_of_order = true;
  const auto sorted = open(seq, options);
  ASSERT_TRUE(sorted.ok()) << sorted.status();
  ASSERT_EQ((*sorted)->imu().size(), 100u);
  for (int k = 0; k < 100; ++k) ASSERT_EQ((*sorted)->imu()[k].gyro_radps, test_fixture::imu_gyro(k)) << k;
  const std::string warnings = all_warnings(**sorted);
  EXPECT_THAT(warnings, HasSubstr(imu.string() + ":12: rows are not in time order"));
  EXPECT_THAT(warnings, HasSubstr(imu.string() + ":22: duplicate of line 21, dropped"));
  // Conflicting duplicate image rows.
  overwrite(seq / "mav0/cam0/data.csv",
            fmt::format("#t,f\n{0},{0}.png\n{0},other.png\n", image_t_ns(spec, 0)));
  options.check_image_files = false;
  const auto conflict = open(seq, options);
  ASSERT_FALSE(conflict.ok());
  EXPECT_THAT(message(conflict.status()), HasSubstr(":3: timestamp"));
  EXPECT_THAT(message(conflict.status()), HasSubstr("also appears on line 2 with different values"));
}

TEST(EurocDataset, CallerCalibrationReplacesSensorYaml) {
  test::TempDir dir;
  const auto seq = test_fixture::write_euroc_sequence(dir, {});
  for (const char* f : {"cam0", "cam1", "imu0"}) std::filesystem::remove(seq / "mav0" / f / "sensor.yaml");
  const auto without = open(seq);
  ASSERT_FALSE(without.ok());
  EXPECT_THAT(
      message(without.status()),
      HasSubstr("camera calibration " + (seq / "mav0/cam0/sensor.yaml").string() + " does not exist"));

  config::StereoRigCalibration calib;
  camera::Params params;
  params << 30, 30, 8, 6, 0, 0, 0, 0;
  for (auto& cam : calib.cameras) {
    auto model = camera::make_camera(camera::DistortionModel::kRadTan, 16, 12, params);
    ASSERT_TRUE(model.ok()) << model.status();
    cam.model = std::move(*model);
  }
  calib.imu.rate_hz = 200.0;
  DatasetOptions options;
  options.calibration = calib;
  const auto with = open(seq, options);
  ASSERT_TRUE(with.ok()) << with.status();
  EXPECT_EQ((*with)->calibration().cameras[0].model->fx(), 30.0);
  EXPECT_TRUE((*with)->load_image(0, (*with)->images()[0][0]).ok());
  options.calibration->cameras[1].model.reset();
  const auto incomplete = open(seq, options);
  ASSERT_FALSE(incomplete.ok());
  EXPECT_THAT(message(incomplete.status()), HasSubstr("camera 1 has no camera model"));
}

TEST(EurocDataset, GroundTruthIsOptional) {
  test::TempDir dir;
  EurocSpec spec;
  spec.groundtruth = false;
  const auto d = open(test_fixture::write_euroc_sequence(dir, spec));
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_FALSE((*d)->has_groundtruth());
  EXPECT_FALSE((*d)->summary().groundtruth.has_value());
  EXPECT_THAT((*d)->summary().describe(), HasSubstr("ground truth: none"));
}

TEST(EurocDataset, UnknownFormatListsKnownOnes) {
  const auto d = open_dataset("rosbag", DatasetOptions{});
  ASSERT_FALSE(d.ok());
  EXPECT_EQ(message(d.status()), "unknown dataset format 'rosbag'; known formats: euroc");
}

TEST(MatchStereo, PairsWithinToleranceAndReportsTheRest) {
  const std::vector<ImageRecord> left = {{100, "l0"}, {200, "l1"}, {300, "l2"}, {400, "l3"}};
  const std::vector<ImageRecord> right = {{90, "r0"}, {210, "r1"}, {350, "r2"}, {395, "r3"}, {500, "r4"}};
  const auto m = match_stereo(left, right, 10);
  ASSERT_TRUE(m.ok()) << m.status();
  ASSERT_EQ(m->frames.size(), 3u);
  EXPECT_EQ(m->frames[0].right.path, "r0");
  EXPECT_EQ(m->frames[1].t_ns, 200);
  EXPECT_EQ(m->frames[2].right.path, "r3");
  EXPECT_EQ(m->unmatched_left, std::vector<TimestampNs>({300}));
  EXPECT_EQ(m->unmatched_right, std::vector<TimestampNs>({350, 500}));
  EXPECT_FALSE(match_stereo(left, right, -1).ok());
  EXPECT_FALSE(match_stereo(left, right, 50).ok());
}

TEST(SummarizeStream, UsesNominalRateForGaps) {
  const std::vector<TimestampNs> t = {0, 10, 20, 30, 55, 65};
  const StreamSummary median = summarize_stream("s", t, 0.0);
  EXPECT_EQ(median.median_period_ns, 10);
  EXPECT_EQ(median.gap_count, 1u);
  EXPECT_EQ(median.gaps[0].from_ns, 30);
  EXPECT_NEAR(median.rate_hz, 5.0 / 65e-9, 1e-3);
  const StreamSummary nominal = summarize_stream("s", t, 1e8);  // 10 ns nominal period
  EXPECT_EQ(nominal.nominal_period_ns, 10);
  EXPECT_EQ(nominal.gap_count, 1u);
  const StreamSummary slow = summarize_stream("s", t, 5e7);  // 20 ns: 25 ns is no gap
  EXPECT_EQ(slow.gap_count, 0u);
  EXPECT_EQ(summarize_stream("s", {}, 0.0).count, 0u);
  EXPECT_EQ(summarize_stream("s", {7}, 0.0).rate_hz, 0.0);
}

}  // namespace
}  // namespace mrvs::io
