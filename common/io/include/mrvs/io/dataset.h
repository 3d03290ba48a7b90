#pragma once
// Dataset readers (Basalt-style): an abstract DatasetReader holding the time-ordered
// records of one sequence, and a factory choosing the implementation by format name.
// Only the EuRoC ASL layout ("euroc") exists for now; a simulator or rosbag reader can be
// added behind the same interface.
//
// EuRoC ASL layout (https://projects.asl.ethz.ch/datasets/doku.php?id=kmavvisualinertialdatasets):
//   <sequence>/mav0/cam0/data.csv      "#timestamp [ns],filename"
//   <sequence>/mav0/cam0/data/<filename>.png
//   <sequence>/mav0/cam0/sensor.yaml   (cam1 likewise)
//   <sequence>/mav0/imu0/data.csv      "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y,w_RS_S_z,
//                                        a_RS_S_x [m s^-2],a_RS_S_y,a_RS_S_z"
//   <sequence>/mav0/imu0/sensor.yaml
//   <sequence>/mav0/state_groundtruth_estimate0/data.csv   (optional)
//   <sequence>/mav0/gnss0/data.csv, sensor.yaml   (optional, the simulator's extension:
//                                                   GNSS fixes of an antenna, see mrvs/io/gnss.h)
#include <array>
#include <cstddef>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "mrvs/config/calibration.h"
#include "mrvs/core/status.h"
#include "mrvs/io/gnss.h"
#include "mrvs/io/trajectory_io.h"
#include "mrvs/io/types.h"

namespace mrvs::io {

/// Left (cam0) and right (cam1) images taken at the same time.
struct StereoFrame {
  TimestampNs t_ns = 0;  ///< cam0 time
  ImageRecord left;      ///< cam0
  ImageRecord right;     ///< cam1 (its t_ns may differ from t_ns by up to the tolerance)
};

/// Two consecutive samples further apart than twice the nominal period.
struct TimeGap {
  TimestampNs from_ns = 0;  ///< last sample before the gap
  TimestampNs to_ns = 0;    ///< first sample after the gap
};

/// Counts and timing of one stream of time-stamped records.
struct StreamSummary {
  std::string name;
  std::size_t count = 0;
  TimestampNs first_ns = 0;
  TimestampNs last_ns = 0;
  double rate_hz = 0.0;              ///< (count - 1) / span; 0 with fewer than 2 samples
  DurationNs median_period_ns = 0;   ///< median time between consecutive samples
  DurationNs nominal_period_ns = 0;  ///< from the calibration rate when known, else the median
  std::size_t gap_count = 0;         ///< periods longer than 2 * nominal_period_ns
  std::vector<TimeGap> gaps;         ///< the first kMaxListedGaps of them
  DurationNs largest_period_ns = 0;

  static constexpr std::size_t kMaxListedGaps = 10;
  /// Seconds between the first and last sample.
  double span_s() const { return to_seconds(last_ns - first_ns); }
  /// One line, e.g. "imu0: 36820 samples, 1403636579.758555717 .. 1403636763.963555527 s (184.205 s),
  /// 199.9 Hz, median period 5.000 ms, no gaps".
  std::string describe() const;
};

/// Summary of `t_ns` (strictly increasing). nominal_rate_hz <= 0: use the median period.
StreamSummary summarize_stream(const std::string& name, const std::vector<TimestampNs>& t_ns,
                               double nominal_rate_hz);

/// Everything a user wants to see before a run.
struct DatasetSummary {
  std::string format;  ///< "euroc"
  std::string name;    ///< sequence name (folder name)
  std::filesystem::path root;
  std::array<StreamSummary, 2> cameras;
  StreamSummary stereo;
  std::array<std::size_t, 2> unmatched = {0, 0};  ///< frames of cam0 / cam1 without a partner
  StreamSummary imu;
  std::optional<StreamSummary> groundtruth;
  std::optional<StreamSummary> gnss;  ///< "gnss0", when the dataset has GNSS fixes
  std::optional<Vec3d> p_b_gnss;      ///< the GNSS antenna in the body frame (lever arm), m
  /// Multi-line human-readable text.
  std::string describe() const;
};

/// Options of a dataset reader.
struct DatasetOptions {
  /// EuRoC: the sequence folder (containing mav0/) or the mav0/ folder itself.
  std::filesystem::path path;
  ReadPolicy policy;
  /// Largest |t_cam0 - t_cam1| paired into a stereo frame (ns). Must be below half the
  /// camera period. 0: exact timestamps only.
  DurationNs stereo_tolerance_ns = 0;
  /// When set, used instead of the dataset's own sensor.yaml files (e.g. a Kalibr result).
  std::optional<config::StereoRigCalibration> calibration;
  /// Stat every listed image file when opening (recommended; the first missing ones are
  /// named in the error).
  bool check_image_files = true;
  /// Read state_groundtruth_estimate0 when present. Off: the ground-truth files are never
  /// opened (what a run without ground truth does; groundtruth() stays empty).
  bool read_groundtruth = true;
};

/// Time-ordered records of one sequence. All timestamps are int64 ns on the dataset's clock.
class DatasetReader {
 public:
  virtual ~DatasetReader() = default;

  /// Format name ("euroc").
  virtual std::string format() const = 0;
  /// Images of cam0 and cam1, strictly increasing in time.
  virtual const std::array<std::vector<ImageRecord>, 2>& images() const = 0;
  /// cam0/cam1 pairs (see DatasetOptions::stereo_tolerance_ns).
  virtual const std::vector<StereoFrame>& stereo_frames() const = 0;
  virtual const std::vector<ImuSample>& imu() const = 0;
  /// Empty when the dataset has no ground truth.
  virtual const std::vector<GroundTruthState>& groundtruth() const = 0;
  bool has_groundtruth() const { return !groundtruth().empty(); }
  /// GNSS fixes (antenna positions in the map frame, mrvs/io/gnss.h), strictly increasing in
  /// time; empty when the dataset has none (real EuRoC).
  virtual const std::vector<GnssFix>& gnss() const = 0;
  bool has_gnss() const { return !gnss().empty(); }
  /// The GNSS antenna in the IMU body frame (gnss0/sensor.yaml T_BS); nullopt without GNSS.
  virtual const std::optional<SE3d>& T_b_gnss() const = 0;
  virtual const config::StereoRigCalibration& calibration() const = 0;
  virtual const DatasetSummary& summary() const = 0;
  /// Non-fatal findings while opening (dropped duplicates, unmatched frames, gaps, ...).
  virtual const Warnings& warnings() const = 0;

  /// Loads image `record` of camera `cam` (0 or 1) as CV_8UC1, checking its size against
  /// the calibration.
  StatusOr<cv::Mat> load_image(int cam, const ImageRecord& record) const;

 protected:
  DatasetReader() = default;
  DatasetReader(const DatasetReader&) = default;
  DatasetReader& operator=(const DatasetReader&) = default;
};

/// Format names open_dataset() accepts.
std::vector<std::string> dataset_formats();

/// Opens a dataset of the named format; an unknown name is an error listing the known ones.
StatusOr<std::unique_ptr<DatasetReader>> open_dataset(const std::string& format,
                                                      const DatasetOptions& options);

/// Opens an EuRoC ASL sequence: reads all CSV files, checks that listed images exist,
/// loads the calibration (unless given), pairs stereo frames, and summarises. Every error
/// names the path (and line) at fault and what the EuRoC layout expects.
StatusOr<std::unique_ptr<DatasetReader>> open_euroc_dataset(const DatasetOptions& options);

// ---- Building blocks (also useful for tests and other readers) --------------------------

/// EuRoC camN/data.csv: rows "t_ns,filename"; paths become image_folder / filename.
/// check_files: stat every file, error naming the first missing ones.
StatusOr<std::vector<ImageRecord>> read_euroc_image_csv(const std::filesystem::path& csv,
                                                        const std::filesystem::path& image_folder,
                                                        bool check_files, const ReadPolicy& policy = {},
                                                        Warnings* warnings = nullptr);

/// EuRoC imu0/data.csv: rows "t_ns, gyro xyz (rad/s), accel xyz (m/s^2)".
StatusOr<std::vector<ImuSample>> read_euroc_imu_csv(const std::filesystem::path& csv,
                                                    const ReadPolicy& policy = {},
                                                    Warnings* warnings = nullptr);

/// Writes EuRoC camN/data.csv ("#timestamp [ns],filename", filename = the record path's
/// file name). Times must strictly increase.
Status write_euroc_image_csv(const std::filesystem::path& csv, const std::vector<ImageRecord>& records);

/// Writes EuRoC imu0/data.csv with the real header; values in the shortest text that reads
/// back to the same double. Times must strictly increase, values be finite.
Status write_euroc_imu_csv(const std::filesystem::path& csv, const std::vector<ImuSample>& samples);

/// Result of pairing two image streams.
struct StereoMatch {
  std::vector<StereoFrame> frames;
  std::vector<TimestampNs> unmatched_left;   ///< cam0 stamps without a cam1 partner
  std::vector<TimestampNs> unmatched_right;  ///< cam1 stamps without a cam0 partner
};

/// Pairs left/right images (both strictly increasing) whose stamps differ by at most
/// tolerance_ns. Error when the tolerance is negative or not below half the median
/// period of either camera (it would pair frames of different exposures).
StatusOr<StereoMatch> match_stereo(const std::vector<ImageRecord>& left,
                                   const std::vector<ImageRecord>& right, DurationNs tolerance_ns);

}  // namespace mrvs::io
