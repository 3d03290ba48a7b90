#pragma once
// Trajectory files.
//
// TUM format: one pose per line, "t tx ty tz qx qy qz qw", t in seconds (decimal, parsed
// exactly into int64 ns), whitespace separated, '#' comments. The pose is T_w_b.
// EuRoC ground truth: state_groundtruth_estimate0/data.csv,
// "#timestamp [ns], p x y z, q w x y z, v x y z, b_w x y z, b_a x y z".
#include <filesystem>
#include <string>
#include <vector>

#include "mrvs/core/status.h"
#include "mrvs/io/types.h"

namespace mrvs::io {

/// How to treat rows that are out of time order or share a timestamp.
struct ReadPolicy {
  /// false (default): an out-of-order row is an error naming file and line.
  /// true: rows are sorted by time and a warning is recorded.
  bool sort_out_of_order = false;
};

/// Largest accepted |1 - |q|| of a quaternion read from a file (they are normalised).
inline constexpr double kMaxQuaternionNormError = 1e-3;

/// Non-fatal findings while reading (e.g. an identical duplicate row that was dropped),
/// each naming file and line. Callers log them.
using Warnings = std::vector<std::string>;

/// Reads a TUM trajectory. Time text is parsed exactly (parse_decimal_seconds); quaternions
/// are normalised, and one whose norm is zero or differs from 1 by more than 1e-3 is an
/// error naming the line. Rows are ordered per `policy`; findings go to `warnings`.
StatusOr<Trajectory> read_tum_trajectory(const std::filesystem::path& path, const ReadPolicy& policy = {},
                                         Warnings* warnings = nullptr);

/// Writes with 9 decimals for time and enough digits to round-trip doubles (the shortest
/// form that parses back to the same double), under a "# timestamp(s) tx ty tz qx qy qz qw"
/// header. Times must be strictly increasing and all values finite (error naming the pose
/// index otherwise); missing parent folders are created; the file is written to a temporary
/// name and renamed into place, so a failed write never leaves a half file behind.
Status write_tum_trajectory(const std::filesystem::path& path, const Trajectory& trajectory);

/// Reads EuRoC state_groundtruth_estimate0/data.csv (17 columns, quaternion w x y z).
/// The same quaternion and ordering rules as read_tum_trajectory apply.
StatusOr<std::vector<GroundTruthState>> read_euroc_groundtruth(const std::filesystem::path& path,
                                                               const ReadPolicy& policy = {},
                                                               Warnings* warnings = nullptr);

/// Reads either format, chosen by content (a CSV whose first data row has 17 comma
/// separated fields is EuRoC ground truth; whitespace-separated 8 fields is TUM).
StatusOr<Trajectory> read_trajectory(const std::filesystem::path& path, const ReadPolicy& policy = {},
                                     Warnings* warnings = nullptr);

// ---- Additions (io work) -----------------------------------------------------------------

/// The trajectory file formats read_trajectory() understands.
enum class TrajectoryFormat {
  kTum,               ///< "t tx ty tz qx qy qz qw", blank separated, t in seconds
  kTumComma,          ///< the same 8 columns separated by commas
  kEurocGroundTruth,  ///< 17 comma-separated columns, t in ns, quaternion w first
};

/// Human-readable name of a format ("TUM", "TUM (comma-separated)", "EuRoC ground truth").
const char* to_string(TrajectoryFormat format);

/// Looks at the first data row (blank and '#' lines skipped) of `path`. Error naming the
/// file, line and both accepted layouts when the row fits neither.
StatusOr<TrajectoryFormat> detect_trajectory_format(const std::filesystem::path& path);

/// Writes EuRoC state_groundtruth_estimate0/data.csv (header line, t in ns, quaternion w
/// first, doubles in shortest round-trip form). Times must be strictly increasing and all
/// values finite; the file is written to a temporary name and renamed into place.
Status write_euroc_groundtruth(const std::filesystem::path& path,
                               const std::vector<GroundTruthState>& states);

/// Just the poses of a ground-truth sequence.
Trajectory to_trajectory(const std::vector<GroundTruthState>& states);

}  // namespace mrvs::io
