// EuRoC ASL dataset reader.
#include <algorithm>
#include <string>
#include <system_error>
#include <utility>

#include <fmt/format.h>

#include "mrvs/io/csv.h"
#include "mrvs/io/dataset.h"
#include "mrvs/io/row_order.h"
#include "read_table.h"

namespace mrvs::io {
namespace {

constexpr const char* kLayout =
    "the EuRoC ASL layout is <sequence>/mav0/ with cam0/data.csv, cam0/data/*.png, cam0/sensor.yaml, the "
    "same for cam1, imu0/data.csv, imu0/sensor.yaml and optionally state_groundtruth_estimate0/data.csv; "
    "give the sequence folder or its mav0 folder";
constexpr const char* kImageColumns = "#timestamp [ns],filename";
constexpr const char* kImuColumns =
    "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y,w_RS_S_z,a_RS_S_x [m s^-2],a_RS_S_y,a_RS_S_z";
/// Missing images named one by one in the error.
constexpr std::size_t kMaxListedMissing = 5;
/// Unmatched stereo stamps named one by one in the warning.
constexpr std::size_t kMaxListedUnmatched = 5;

bool is_dir(const std::filesystem::path& p) {
  std::error_code ec;
  return std::filesystem::is_directory(p, ec);
}

bool is_file(const std::filesystem::path& p) {
  std::error_code ec;
  return std::filesystem::is_regular_file(p, ec);
}

Status require_file(const std::filesystem::path& file, const char* what) {
  if (is_file(file)) return absl::OkStatus();
  return absl::NotFoundError(fmt::format("{} {} does not exist; {}", what, file.string(), kLayout));
}

/// The mav0 folder of `given` (the sequence folder or mav0 itself), absolute.
StatusOr<std::filesystem::path> find_mav0(const std::filesystem::path& given) {
  if (given.empty()) {
    return absl::InvalidArgumentError(fmt::format("no dataset folder given; {}", kLayout));
  }
  std::error_code ec;
  std::filesystem::path path = std::filesystem::absolute(given, ec).lexically_normal();
  if (ec) path = given.lexically_normal();
  if (!path.has_filename() && path.has_parent_path()) path = path.parent_path();  // "seq/mav0/"
  if (!std::filesystem::exists(path, ec)) {
    const std::string shown =
        given == path ? path.string() : fmt::format("{} (= {})", given.string(), path.string());
    return absl::NotFoundError(fmt::format("dataset folder {} does not exist; {}", shown, kLayout));
  }
  if (!is_dir(path)) {
    return absl::InvalidArgumentError(
        fmt::format("{} is a file, not a dataset folder; {}", path.string(), kLayout));
  }
  if (is_dir(path / "mav0")) return path / "mav0";
  if (is_dir(path / "cam0") || is_dir(path / "imu0")) return path;
  return absl::NotFoundError(
      fmt::format("{} is not an EuRoC folder: it has neither a mav0/ folder nor cam0/ and "
                  "imu0/ folders; {}",
                  path.string(), kLayout));
}

StatusOr<ImageRecord> parse_image_row(const TableReader& reader, const TextRow& row,
                                      const std::filesystem::path& folder) {
  MRVS_RETURN_IF_ERROR(reader.check_field_count(row, 2, kImageColumns));
  ImageRecord record;
  MRVS_ASSIGN_OR_RETURN(record.t_ns, reader.parse_ns(row, 0, "#timestamp [ns]"));
  if (row.fields[1].empty()) {
    return reader.row_error(row,
                            "field 2 ('filename') is empty; write the image file name or delete this line");
  }
  record.path = folder / row.fields[1];
  return record;
}

/// Error naming the first listed images that do not exist (one stat per file).
Status check_images_exist(const std::filesystem::path& csv, const std::filesystem::path& folder,
                          const std::vector<NumberedRow<ImageRecord>>& rows) {
  if (!is_dir(folder)) {
    return absl::NotFoundError(
        fmt::format("image folder {} (for the {} images listed in {}) does not exist; {}", folder.string(),
                    rows.size(), csv.string(), kLayout));
  }
  std::size_t missing = 0;
  std::string listed;
  for (const NumberedRow<ImageRecord>& row : rows) {
    if (is_file(row.value.path)) continue;
    if (++missing <= kMaxListedMissing) {
      listed += fmt::format("{}{} (line {})", listed.empty() ? "" : ", ", row.value.path.filename().string(),
                            row.line);
    }
  }
  if (missing == 0) return absl::OkStatus();
  return absl::NotFoundError(
      fmt::format("{} of the {} images listed in {} do not exist in {}: {}{}; re-extract the dataset, or "
                  "delete those rows "
                  "from the csv",
                  missing, rows.size(), csv.string(), folder.string(), listed,
                  missing > kMaxListedMissing ? ", ..." : ""));
}

StatusOr<ImuSample> parse_imu_row(const TableReader& reader, const TextRow& row) {
  MRVS_RETURN_IF_ERROR(reader.check_field_count(row, 7, kImuColumns));
  static constexpr const char* kNames[6] = {"w_RS_S_x [rad s^-1]", "w_RS_S_y [rad s^-1]",
                                            "w_RS_S_z [rad s^-1]", "a_RS_S_x [m s^-2]",
                                            "a_RS_S_y [m s^-2]",   "a_RS_S_z [m s^-2]"};
  ImuSample s;
  MRVS_ASSIGN_OR_RETURN(s.t_ns, reader.parse_ns(row, 0, "#timestamp [ns]"));
  for (int i = 0; i < 3; ++i) {
    MRVS_ASSIGN_OR_RETURN(s.gyro_radps[i], reader.parse_double(row, 1 + i, kNames[i]));
    MRVS_ASSIGN_OR_RETURN(s.accel_mps2[i], reader.parse_double(row, 4 + i, kNames[3 + i]));
  }
  return s;
}

}  // namespace

StatusOr<std::vector<ImageRecord>> read_euroc_image_csv(const std::filesystem::path& csv,
                                                        const std::filesystem::path& image_folder,
                                                        bool check_files, const ReadPolicy& policy,
                                                        Warnings* warnings) {
  MRVS_ASSIGN_OR_RETURN(auto rows, internal::read_table<ImageRecord>(
                                       csv, Separator::kComma, fmt::format("'{}'", kImageColumns), warnings,
                                       [&image_folder](const TableReader& reader, const TextRow& row) {
                                         return parse_image_row(reader, row, image_folder);
                                       }));
  if (check_files) MRVS_RETURN_IF_ERROR(check_images_exist(csv, image_folder, rows));
  return order_rows(csv, std::move(rows), policy, warnings, TimeColumn::kNanoseconds,
                    [](const ImageRecord& a, const ImageRecord& b) { return a.path == b.path; });
}

StatusOr<std::vector<ImuSample>> read_euroc_imu_csv(const std::filesystem::path& csv,
                                                    const ReadPolicy& policy, Warnings* warnings) {
  MRVS_ASSIGN_OR_RETURN(
      auto rows, internal::read_table<ImuSample>(csv, Separator::kComma, fmt::format("'{}'", kImuColumns),
                                                 warnings, parse_imu_row));
  return order_rows(csv, std::move(rows), policy, warnings, TimeColumn::kNanoseconds,
                    [](const ImuSample& a, const ImuSample& b) {
                      return a.gyro_radps == b.gyro_radps && a.accel_mps2 == b.accel_mps2;
                    });
}

namespace {

class EurocDataset final : public DatasetReader {
 public:
  std::string format() const override { return "euroc"; }
  const std::array<std::vector<ImageRecord>, 2>& images() const override { return images_; }
  const std::vector<StereoFrame>& stereo_frames() const override { return stereo_; }
  const std::vector<ImuSample>& imu() const override { return imu_; }
  const std::vector<GroundTruthState>& groundtruth() const override { return groundtruth_; }
  const std::vector<GnssFix>& gnss() const override { return gnss_; }
  const std::optional<SE3d>& T_b_gnss() const override { return T_b_gnss_; }
  const config::StereoRigCalibration& calibration() const override { return calibration_; }
  const DatasetSummary& summary() const override { return summary_; }
  const Warnings& warnings() const override { return warnings_; }

  /// Reads the CSV files, then the calibration, pairs stereo frames and summarises.
  Status open(const DatasetOptions& options);

 private:
  Status read_streams(const std::filesystem::path& mav0, const ReadPolicy& policy, bool check_files,
                      bool read_groundtruth);
  Status load_calibration(const std::filesystem::path& mav0, const DatasetOptions& options);
  Status read_gnss(const std::filesystem::path& mav0, const ReadPolicy& policy);
  Status pair_stereo(DurationNs tolerance_ns);
  void summarize(const std::filesystem::path& mav0);
  void check_imu_coverage();

  std::array<std::vector<ImageRecord>, 2> images_;
  std::vector<StereoFrame> stereo_;
  std::vector<ImuSample> imu_;
  std::vector<GroundTruthState> groundtruth_;
  std::vector<GnssFix> gnss_;
  std::optional<SE3d> T_b_gnss_;
  double gnss_rate_hz_ = 0.0;
  config::StereoRigCalibration calibration_;
  DatasetSummary summary_;
  Warnings warnings_;
};

Status EurocDataset::open(const DatasetOptions& options) {
  MRVS_ASSIGN_OR_RETURN(const std::filesystem::path mav0, find_mav0(options.path));
  MRVS_RETURN_IF_ERROR(
      read_streams(mav0, options.policy, options.check_image_files, options.read_groundtruth));
  MRVS_RETURN_IF_ERROR(load_calibration(mav0, options));
  MRVS_RETURN_IF_ERROR(read_gnss(mav0, options.policy));
  MRVS_RETURN_IF_ERROR(pair_stereo(options.stereo_tolerance_ns));
  summarize(mav0);
  check_imu_coverage();
  return absl::OkStatus();
}

Status EurocDataset::read_streams(const std::filesystem::path& mav0, const ReadPolicy& policy,
                                  bool check_files, bool read_groundtruth) {
  for (std::size_t cam = 0; cam < 2; ++cam) {
    const std::filesystem::path folder = mav0 / fmt::format("cam{}", cam);
    MRVS_RETURN_IF_ERROR(require_file(folder / "data.csv", "image list"));
    MRVS_ASSIGN_OR_RETURN(images_[cam], read_euroc_image_csv(folder / "data.csv", folder / "data",
                                                             check_files, policy, &warnings_));
  }
  MRVS_RETURN_IF_ERROR(require_file(mav0 / "imu0" / "data.csv", "IMU data"));
  MRVS_ASSIGN_OR_RETURN(imu_, read_euroc_imu_csv(mav0 / "imu0" / "data.csv", policy, &warnings_));
  const std::filesystem::path gt_folder = mav0 / "state_groundtruth_estimate0";
  if (!read_groundtruth) return absl::OkStatus();  // never opened: a run without ground truth
  if (is_file(gt_folder / "data.csv")) {
    MRVS_ASSIGN_OR_RETURN(groundtruth_, read_euroc_groundtruth(gt_folder / "data.csv", policy, &warnings_));
  } else if (is_dir(gt_folder)) {
    warnings_.push_back(fmt::format(
        "{} exists but has no data.csv; reading the sequence without ground truth", gt_folder.string()));
  }
  return absl::OkStatus();
}

Status EurocDataset::load_calibration(const std::filesystem::path& mav0, const DatasetOptions& options) {
  if (options.calibration) {
    calibration_ = *options.calibration;
  } else {
    for (std::size_t cam = 0; cam < 2; ++cam) {
      const std::filesystem::path yaml = mav0 / fmt::format("cam{}", cam) / "sensor.yaml";
      MRVS_RETURN_IF_ERROR(require_file(yaml, "camera calibration"));
      MRVS_ASSIGN_OR_RETURN(calibration_.cameras[cam], config::load_euroc_camera_yaml(yaml));
      if (calibration_.cameras[cam].name.empty()) calibration_.cameras[cam].name = fmt::format("cam{}", cam);
    }
    const std::filesystem::path imu_yaml = mav0 / "imu0" / "sensor.yaml";
    MRVS_RETURN_IF_ERROR(require_file(imu_yaml, "IMU calibration"));
    MRVS_ASSIGN_OR_RETURN(calibration_.imu, config::load_euroc_imu_yaml(imu_yaml));
  }
  for (std::size_t cam = 0; cam < 2; ++cam) {
    if (!calibration_.cameras[cam].model) {
      return absl::InvalidArgumentError(
          fmt::format("the calibration of camera {} has no camera model (intrinsics and image size); give a "
                      "complete calibration for both cameras",
                      cam));
    }
  }
  return absl::OkStatus();
}

/// mav0/gnss0 (optional): data.csv and, with it, sensor.yaml for the antenna's lever arm.
Status EurocDataset::read_gnss(const std::filesystem::path& mav0, const ReadPolicy& policy) {
  const std::filesystem::path folder = mav0 / "gnss0";
  if (!is_file(folder / "data.csv")) {
    if (is_dir(folder)) {
      warnings_.push_back(
          fmt::format("{} exists but has no data.csv; reading the sequence without GNSS", folder.string()));
    }
    return absl::OkStatus();
  }
  const std::filesystem::path yaml = folder / "sensor.yaml";
  if (!is_file(yaml)) {
    return absl::NotFoundError(
        fmt::format("GNSS calibration {} does not exist: it gives the antenna position in the body frame "
                    "(T_BS) and the fix rate for the fixes in {}; add it, or remove the gnss0 folder",
                    yaml.string(), (folder / "data.csv").string()));
  }
  MRVS_ASSIGN_OR_RETURN(const GnssSensor sensor, read_gnss_sensor_yaml(yaml));
  MRVS_ASSIGN_OR_RETURN(gnss_, read_euroc_gnss_csv(folder / "data.csv", policy, &warnings_));
  T_b_gnss_ = sensor.T_b_antenna;
  gnss_rate_hz_ = sensor.rate_hz;
  return absl::OkStatus();
}

Status EurocDataset::pair_stereo(DurationNs tolerance_ns) {
  MRVS_ASSIGN_OR_RETURN(StereoMatch match, match_stereo(images_[0], images_[1], tolerance_ns));
  stereo_ = std::move(match.frames);
  const std::array<const std::vector<TimestampNs>*, 2> unmatched = {&match.unmatched_left,
                                                                    &match.unmatched_right};
  for (std::size_t cam = 0; cam < 2; ++cam) {
    const std::vector<TimestampNs>& lost = *unmatched[cam];
    summary_.unmatched[cam] = lost.size();
    if (lost.empty()) continue;
    std::string listed;
    for (std::size_t k = 0; k < std::min(lost.size(), kMaxListedUnmatched); ++k) {
      listed += fmt::format("{}{}", k == 0 ? "" : ", ", lost[k]);
    }
    warnings_.push_back(
        fmt::format("cam{}: {} of {} frames have no cam{} frame within {} ns and are not used as stereo "
                    "frames (t_ns: {}{}); "
                    "check the other camera's data.csv, or allow a stereo time tolerance",
                    cam, lost.size(), images_[cam].size(), 1 - cam, tolerance_ns, listed,
                    lost.size() > kMaxListedUnmatched ? ", ..." : ""));
  }
  if (stereo_.empty()) {
    return absl::InvalidArgumentError(
        "no cam0 frame has a cam1 frame with the same timestamp, so there are no stereo frames; check that "
        "cam0/data.csv and cam1/data.csv belong to the same sequence, or allow a stereo time tolerance");
  }
  return absl::OkStatus();
}

void EurocDataset::summarize(const std::filesystem::path& mav0) {
  summary_.format = "euroc";
  summary_.root = mav0;
  summary_.name = (mav0.filename() == "mav0" ? mav0.parent_path() : mav0).filename().string();
  for (std::size_t cam = 0; cam < 2; ++cam) {
    std::vector<TimestampNs> t;
    for (const ImageRecord& r : images_[cam]) t.push_back(r.t_ns);
    summary_.cameras[cam] = summarize_stream(fmt::format("cam{}", cam), t, calibration_.cameras[cam].rate_hz);
  }
  std::vector<TimestampNs> t;
  for (const StereoFrame& f : stereo_) t.push_back(f.t_ns);
  summary_.stereo = summarize_stream("stereo", t, calibration_.cameras[0].rate_hz);
  t.clear();
  for (const ImuSample& s : imu_) t.push_back(s.t_ns);
  summary_.imu = summarize_stream("imu0", t, calibration_.imu.rate_hz);
  if (!groundtruth_.empty()) {
    t.clear();
    for (const GroundTruthState& s : groundtruth_) t.push_back(s.t_ns);
    summary_.groundtruth = summarize_stream("groundtruth", t, 0.0);
  }
  for (const StreamSummary* s : {&summary_.cameras[0], &summary_.cameras[1], &summary_.imu}) {
    if (s->gap_count > 0) warnings_.push_back(s->describe());
  }
  if (!gnss_.empty()) {
    t.clear();
    for (const GnssFix& f : gnss_) t.push_back(f.t_ns);
    summary_.gnss = summarize_stream("gnss0", t, gnss_rate_hz_);
    summary_.p_b_gnss = T_b_gnss_->translation();
    if (summary_.gnss->gap_count > 0) warnings_.push_back(summary_.gnss->describe());
  }
}

void EurocDataset::check_imu_coverage() {
  if (imu_.empty() || stereo_.empty()) return;
  const TimestampNs first = imu_.front().t_ns;
  const TimestampNs last = imu_.back().t_ns;
  const auto before =
      std::count_if(stereo_.begin(), stereo_.end(), [&](const StereoFrame& f) { return f.t_ns < first; });
  const auto after =
      std::count_if(stereo_.begin(), stereo_.end(), [&](const StereoFrame& f) { return f.t_ns > last; });
  if (before + after == 0) return;
  warnings_.push_back(fmt::format(
      "{} stereo frames lie before the first IMU sample ({} ns) and {} after the last ({} ns); they have no "
      "IMU data around them",
      before, first, after, last));
}

}  // namespace

StatusOr<std::unique_ptr<DatasetReader>> open_euroc_dataset(const DatasetOptions& options) {
  auto dataset = std::make_unique<EurocDataset>();
  MRVS_RETURN_IF_ERROR(dataset->open(options));
  return std::unique_ptr<DatasetReader>(std::move(dataset));
}

}  // namespace mrvs::io
