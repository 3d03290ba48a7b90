#include "mrvs/io/trajectory_io.h"
#include "mrvs/core/file.h"
#include "write_rows.h"

#include <cmath>
#include <fstream>
#include <iterator>
#include <system_error>

#include <fmt/format.h>

#include "mrvs/io/csv.h"
#include "mrvs/io/row_order.h"
#include "read_table.h"

namespace mrvs::io {
namespace {

constexpr const char* kTumColumns = "t tx ty tz qx qy qz qw";
constexpr const char* kTumLayout = "'t tx ty tz qx qy qz qw' (TUM: t in seconds, quaternion x y z w)";
constexpr const char* kEurocGtColumns =
    "#timestamp [ns], p_RS_R_x/y/z [m], q_RS_w/x/y/z [], v_RS_R_x/y/z [m s^-1], b_w_RS_S_x/y/z [rad s^-1], "
    "b_a_RS_S_x/y/z [m s^-2]";
// The real EuRoC header, blanks after the commas included.
constexpr const char* kEurocGtHeader =
    "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], q_RS_z [], "
    "v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], b_w_RS_S_y [rad s^-1], "
    "b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], b_a_RS_S_z [m s^-2]";
constexpr std::size_t kTumFields = 8;
constexpr std::size_t kEurocGtFields = 17;

/// Reads consecutive fields [first, first + 3) as a vector.
StatusOr<Vec3d> parse_vec3(const TableReader& reader, const TextRow& row, std::size_t first,
                           const char* const names[3]) {
  Vec3d v;
  for (int i = 0; i < 3; ++i) {
    MRVS_ASSIGN_OR_RETURN(v[i], reader.parse_double(row, first + i, names[i]));
  }
  return v;
}

/// Checks |q| against 1 and normalises. `order` names the file's column order for messages.
StatusOr<Quatd> unit_quaternion(const TableReader& reader, const TextRow& row, const Quatd& q,
                                const char* order) {
  const double n = q.norm();
  if (!(n > 0.0) || std::abs(1.0 - n) > kMaxQuaternionNormError) {
    return reader.row_error(
        row, fmt::format("quaternion ({}) = ({}, {}, {}, {}) has norm {:.9g}, expected 1 (within {}): the "
                         "row is corrupt or its columns are in the wrong order; fix or delete this line",
                         order, q.x(), q.y(), q.z(), q.w(), n, kMaxQuaternionNormError));
  }
  return q.normalized();
}

StatusOr<StampedPose> parse_tum_row(const TableReader& reader, const TextRow& row) {
  MRVS_RETURN_IF_ERROR(reader.check_field_count(row, kTumFields, kTumColumns));
  static constexpr const char* kP[3] = {"tx", "ty", "tz"};
  StampedPose pose;
  MRVS_ASSIGN_OR_RETURN(pose.t_ns, reader.parse_seconds(row, 0, "t"));
  MRVS_ASSIGN_OR_RETURN(const Vec3d p, parse_vec3(reader, row, 1, kP));
  double q[4];  // x y z w
  static constexpr const char* kQ[4] = {"qx", "qy", "qz", "qw"};
  for (int i = 0; i < 4; ++i) {
    MRVS_ASSIGN_OR_RETURN(q[i], reader.parse_double(row, 4 + i, kQ[i]));
  }
  MRVS_ASSIGN_OR_RETURN(const Quatd unit, unit_quaternion(reader, row, Quatd(q[3], q[0], q[1], q[2]),
                                                          "qx qy qz qw printed as x, y, z, w"));
  pose.T_w_b = SE3d(unit, p);
  return pose;
}

StatusOr<GroundTruthState> parse_euroc_gt_row(const TableReader& reader, const TextRow& row) {
  MRVS_RETURN_IF_ERROR(reader.check_field_count(row, kEurocGtFields, kEurocGtColumns));
  static constexpr const char* kP[3] = {"p_RS_R_x", "p_RS_R_y", "p_RS_R_z"};
  static constexpr const char* kQ[4] = {"q_RS_w", "q_RS_x", "q_RS_y", "q_RS_z"};
  static constexpr const char* kV[3] = {"v_RS_R_x", "v_RS_R_y", "v_RS_R_z"};
  static constexpr const char* kBw[3] = {"b_w_RS_S_x", "b_w_RS_S_y", "b_w_RS_S_z"};
  static constexpr const char* kBa[3] = {"b_a_RS_S_x", "b_a_RS_S_y", "b_a_RS_S_z"};
  GroundTruthState s;
  MRVS_ASSIGN_OR_RETURN(s.t_ns, reader.parse_ns(row, 0, "#timestamp [ns]"));
  MRVS_ASSIGN_OR_RETURN(const Vec3d p, parse_vec3(reader, row, 1, kP));
  double q[4];  // w x y z, as in the file
  for (int i = 0; i < 4; ++i) {
    MRVS_ASSIGN_OR_RETURN(q[i], reader.parse_double(row, 4 + i, kQ[i]));
  }
  MRVS_ASSIGN_OR_RETURN(const Quatd unit, unit_quaternion(reader, row, Quatd(q[0], q[1], q[2], q[3]),
                                                          "q_RS_w x y z printed as x, y, z, w"));
  s.T_w_b = SE3d(unit, p);
  MRVS_ASSIGN_OR_RETURN(s.v_w_b, parse_vec3(reader, row, 8, kV));
  MRVS_ASSIGN_OR_RETURN(s.bias_gyro, parse_vec3(reader, row, 11, kBw));
  MRVS_ASSIGN_OR_RETURN(s.bias_accel, parse_vec3(reader, row, 14, kBa));
  return s;
}

bool same_pose(const SE3d& a, const SE3d& b) {
  return a.translation() == b.translation() && a.quaternion().coeffs() == b.quaternion().coeffs();
}

StatusOr<Trajectory> read_tum_impl(const std::filesystem::path& path, Separator separator,
                                   const ReadPolicy& policy, Warnings* warnings) {
  MRVS_ASSIGN_OR_RETURN(
      auto rows, internal::read_table<StampedPose>(path, separator, kTumLayout, warnings, parse_tum_row));
  return order_rows(path, std::move(rows), policy, warnings, TimeColumn::kSeconds,
                    [](const StampedPose& a, const StampedPose& b) { return same_pose(a.T_w_b, b.T_w_b); });
}

bool finite_pose(const SE3d& T) { return T.translation().allFinite() && T.quaternion().coeffs().allFinite(); }

}  // namespace

const char* to_string(TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      return "TUM";
    case TrajectoryFormat::kTumComma:
      return "TUM (comma-separated)";
    case TrajectoryFormat::kEurocGroundTruth:
      return "EuRoC ground truth";
  }
  return "unknown";
}

StatusOr<Trajectory> read_tum_trajectory(const std::filesystem::path& path, const ReadPolicy& policy,
                                         Warnings* warnings) {
  return read_tum_impl(path, Separator::kWhitespace, policy, warnings);
}

StatusOr<std::vector<GroundTruthState>> read_euroc_groundtruth(const std::filesystem::path& path,
                                                               const ReadPolicy& policy, Warnings* warnings) {
  MRVS_ASSIGN_OR_RETURN(auto rows, internal::read_table<GroundTruthState>(
                                       path, Separator::kComma, fmt::format("'{}'", kEurocGtColumns),
                                       warnings, parse_euroc_gt_row));
  return order_rows(path, std::move(rows), policy, warnings, TimeColumn::kNanoseconds,
                    [](const GroundTruthState& a, const GroundTruthState& b) {
                      return same_pose(a.T_w_b, b.T_w_b) && a.v_w_b == b.v_w_b &&
                             a.bias_gyro == b.bias_gyro && a.bias_accel == b.bias_accel;
                    });
}

StatusOr<TrajectoryFormat> detect_trajectory_format(const std::filesystem::path& path) {
  MRVS_ASSIGN_OR_RETURN(TableReader reader, TableReader::open(path, Separator::kWhitespace));
  TextRow row;
  if (!reader.next(row)) {
    MRVS_RETURN_IF_ERROR(reader.status());
    return absl::InvalidArgumentError(fmt::format(
        "{}: no data rows (the file holds only blank or '#' lines); expected a TUM or EuRoC trajectory",
        path.string()));
  }
  // Re-join the blank-separated fields to split the line on commas instead.
  std::string line;
  for (const std::string& f : row.fields) line += f + " ";
  const std::size_t comma_fields = split_fields(line, Separator::kComma).size();
  const bool has_comma = line.find(',') != std::string::npos;
  if (has_comma && comma_fields == kEurocGtFields) return TrajectoryFormat::kEurocGroundTruth;
  if (has_comma && comma_fields == kTumFields) return TrajectoryFormat::kTumComma;
  if (!has_comma && row.fields.size() == kTumFields) return TrajectoryFormat::kTum;
  return absl::InvalidArgumentError(fmt::format(
      "{}: cannot tell the trajectory format: the first data row has {} {} fields; expected either TUM "
      "({} separated by blanks) or EuRoC ground truth ({} comma-separated columns: {})",
      reader.where(row), has_comma ? comma_fields : row.fields.size(),
      has_comma ? "comma-separated" : "blank-separated", kTumLayout, kEurocGtFields, kEurocGtColumns));
}

StatusOr<Trajectory> read_trajectory(const std::filesystem::path& path, const ReadPolicy& policy,
                                     Warnings* warnings) {
  MRVS_ASSIGN_OR_RETURN(const TrajectoryFormat format, detect_trajectory_format(path));
  switch (format) {
    case TrajectoryFormat::kTum:
      return read_tum_impl(path, Separator::kWhitespace, policy, warnings);
    case TrajectoryFormat::kTumComma:
      return read_tum_impl(path, Separator::kComma, policy, warnings);
    case TrajectoryFormat::kEurocGroundTruth:
      break;
  }
  MRVS_ASSIGN_OR_RETURN(const auto states, read_euroc_groundtruth(path, policy, warnings));
  return to_trajectory(states);
}

Trajectory to_trajectory(const std::vector<GroundTruthState>& states) {
  Trajectory trajectory;
  trajectory.reserve(states.size());
  for (const GroundTruthState& s : states) trajectory.push_back(StampedPose{s.t_ns, s.T_w_b});
  return trajectory;
}

Status write_tum_trajectory(const std::filesystem::path& path, const Trajectory& trajectory) {
  MRVS_RETURN_IF_ERROR(
      check_rows_to_write(path, trajectory, [](const StampedPose& p) { return finite_pose(p.T_w_b); }));
  fmt::memory_buffer out;
  fmt::format_to(std::back_inserter(out), "# timestamp(s) tx ty tz qx qy qz qw\n");
  for (const StampedPose& pose : trajectory) {
    const Vec3d& p = pose.T_w_b.translation();
    const Quatd& q = pose.T_w_b.quaternion();
    fmt::format_to(std::back_inserter(out), "{} {} {} {} {} {} {} {}\n", format_seconds(pose.t_ns), p.x(),
                   p.y(), p.z(), q.x(), q.y(), q.z(), q.w());
  }
  return write_file_atomically(path, fmt::to_string(out));
}

Status write_euroc_groundtruth(const std::filesystem::path& path,
                               const std::vector<GroundTruthState>& states) {
  MRVS_RETURN_IF_ERROR(check_rows_to_write(path, states, [](const GroundTruthState& s) {
    return finite_pose(s.T_w_b) && s.v_w_b.allFinite() && s.bias_gyro.allFinite() && s.bias_accel.allFinite();
  }));
  fmt::memory_buffer out;
  fmt::format_to(std::back_inserter(out), "{}\n", kEurocGtHeader);
  for (const GroundTruthState& s : states) {
    const Vec3d& p = s.T_w_b.translation();
    const Quatd& q = s.T_w_b.quaternion();
    fmt::format_to(std::back_inserter(out), "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", s.t_ns,
                   p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z(), s.v_w_b.x(), s.v_w_b.y(), s.v_w_b.z(),
                   s.bias_gyro.x(), s.bias_gyro.y(), s.bias_gyro.z(), s.bias_accel.x(), s.bias_accel.y(),
                   s.bias_accel.z());
  }
  return write_file_atomically(path, fmt::to_string(out));
}

}  // namespace mrvs::io
