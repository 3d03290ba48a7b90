// evaluate_trajectory: ATE / RPE of an estimated trajectory against ground truth.
//
//   evaluate_trajectory --est EST --gt GT [--max-dt 0.01] [--time-offset 0] [--rpe-delta 1.0]
//                       [--rpe-delta-t 1.0] [--align all|se3|sim3|first|none]
//                       [--log-level info] [--json OUT.json]
//
// Both files are TUM ("t tx ty tz qx qy qz qw") or EuRoC ground-truth CSV, detected by
// content. Exit codes: 0 success, 1 data error (unreadable / inconsistent input, nothing
// to align), 2 usage error.
#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "mrvs/core/cli.h"
#include "mrvs/core/log.h"
#include "mrvs/eval/report.h"
#include "mrvs/io/trajectory_io.h"

namespace {

struct Args {
  std::string est_path;
  std::string gt_path;
  double max_dt_s = 0.01;
  double time_offset_s = 0.0;
  double rpe_delta_m = 1.0;
  double rpe_delta_s = 1.0;
  std::string align = "all";
  std::string log_level = "info";
  std::string json_path;
  long long at_ns = -1;
};

void add_options(CLI::App& app, Args& args) {
  app.add_option("--est", args.est_path, "Estimated trajectory (TUM txt or EuRoC ground-truth CSV), T_w_b")
      ->required();
  app.add_option("--gt", args.gt_path, "Ground-truth trajectory (TUM txt or EuRoC ground-truth CSV), T_w_b")
      ->required();
  app.add_option(
         "--max-dt", args.max_dt_s,
         "Association tolerance in seconds: ground truth is interpolated between samples within this "
         "distance of an estimate stamp, else the nearest sample within it is used, else the estimate "
         "pose is unmatched")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e6));
  app.add_option("--time-offset", args.time_offset_s,
                 "Seconds added to every estimate stamp before association (t_gt = t_est + offset)")
      ->capture_default_str()
      ->check(CLI::Range(-1e6, 1e6));
  app.add_option("--rpe-delta", args.rpe_delta_m,
                 "RPE step in metres of travelled ground-truth path (pairs closest to this distance)")
      ->capture_default_str()
      ->check(CLI::Range(1e-9, 1e9));
  app.add_option("--rpe-delta-t", args.rpe_delta_s,
                 "RPE step in seconds (pairs closest to this time); 0 disables")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1e9));
  app.add_option(
         "--align", args.align,
         "Alignments reported besides the unaligned ATE: se3 (Umeyama rigid), sim3 (Umeyama with scale; "
         "its scale is also applied to RPE), first (first pose), none, or all (se3, sim3 and first)")
      ->capture_default_str()
      ->check(CLI::IsMember({"all", "se3", "sim3", "first", "none"}));
  mrvs::add_log_level_option(app, args.log_level);
  app.add_option("--json", args.json_path, "Also write every figure as JSON to this file");
  app.add_option(
      "--at", args.at_ns,
      "Also the error of the one estimate pose at this time (ns; e.g. the edge's LOCALISED_AT_T_NS): "
      "POSE_ERROR_AT_M, POSE_ERROR_AT_DEG, POSE_HEADING_ERROR_AT_DEG, no alignment");
  app.footer(
      "Output: a human-readable summary, then machine-readable lines 'KEY: value': MATCHED_POSES, "
      "UNMATCHED_POSES, ATE_RMSE_m and ATE_ROT_RMSE_deg (unaligned), ATE_RMSE_SE3_m, ATE_ROT_RMSE_SE3_deg, "
      "ATE_RMSE_SIM3_m, ATE_ROT_RMSE_SIM3_deg, SIM3_SCALE, ATE_RMSE_FIRST_m, ATE_ROT_RMSE_FIRST_deg (per "
      "alignment), RPE_TRANS_RMSE_m, RPE_ROT_RMSE_deg, RPE_PAIRS (per --rpe-delta metres), "
      "RPE_TIME_TRANS_RMSE_m, "
      "RPE_TIME_ROT_RMSE_deg, RPE_TIME_PAIRS (per --rpe-delta-t seconds; 'nan' when the trajectory is too "
      "short).\nExit codes: 0 success, 1 data error, 2 usage error.");
}

std::vector<mrvs::eval::AlignmentMethod> alignments_for(const std::string& align) {
  using mrvs::eval::AlignmentMethod;
  if (align == "all") return {AlignmentMethod::kSE3, AlignmentMethod::kSim3, AlignmentMethod::kFirstPose};
  if (align == "se3") return {AlignmentMethod::kSE3};
  if (align == "sim3") return {AlignmentMethod::kSim3};
  if (align == "first") return {AlignmentMethod::kFirstPose};
  return {};
}

/// Reads one trajectory, logging reader warnings; the error names the file.
mrvs::StatusOr<mrvs::io::Trajectory> read_input(const std::string& path, const char* what) {
  mrvs::io::Warnings warnings;
  auto trajectory = mrvs::io::read_trajectory(path, {}, &warnings);
  for (const std::string& w : warnings) spdlog::warn("{}", w);
  if (!trajectory.ok()) {
    return absl::Status(trajectory.status().code(),
                        fmt::format("cannot read {} trajectory '{}': {}", what, path,
                                    std::string(trajectory.status().message())));
  }
  spdlog::info("read {} poses from {} trajectory {}", trajectory->size(), what, path);
  return trajectory;
}

/// The unaligned error of the estimate pose at t_ns (the nearest within the association's
/// tolerance) against the ground truth there.
mrvs::Status print_error_at(const mrvs::io::Trajectory& est, const mrvs::io::Trajectory& gt,
                            mrvs::TimestampNs t_ns, const mrvs::eval::AssociationOptions& association) {
  const auto it = std::min_element(est.begin(), est.end(), [&](const auto& a, const auto& b) {
    return std::llabs(a.t_ns - t_ns) < std::llabs(b.t_ns - t_ns);
  });
  if (it == est.end() || std::llabs(it->t_ns - t_ns) > association.max_dt_ns) {
    return absl::NotFoundError("no estimate pose within --max-dt of that time");
  }
  MRVS_ASSIGN_OR_RETURN(const auto matched, mrvs::eval::associate({*it}, gt, association));
  const mrvs::eval::Match& m = matched.matches.front();
  const mrvs::SE3d d = m.T_wgt_b.inverse() * m.T_west_b;
  const mrvs::Mat3d R = m.T_west_b.rotation_matrix() * m.T_wgt_b.rotation_matrix().transpose();
  const double heading = std::atan2(R(1, 0) - R(0, 1), R(0, 0) + R(1, 1));
  fmt::print(
      "POSE_AT_T_NS: {}\nPOSE_ERROR_AT_M: {:.6f}\nPOSE_ERROR_AT_DEG: {:.4f}\nPOSE_HEADING_ERROR_AT_DEG: "
      "{:.4f}\n",
      it->t_ns, (m.T_west_b.translation() - m.T_wgt_b.translation()).norm(),
      Eigen::AngleAxisd(d.quaternion()).angle() * 180.0 / M_PI, heading * 180.0 / M_PI);
  return absl::OkStatus();
}

int run(const Args& args) {
  auto est = read_input(args.est_path, "estimate");
  if (!est.ok()) {
    fmt::print(stderr, "evaluate_trajectory: error: {}\n", std::string(est.status().message()));
    return mrvs::kExitDataError;
  }
  auto gt = read_input(args.gt_path, "ground-truth");
  if (!gt.ok()) {
    fmt::print(stderr, "evaluate_trajectory: error: {}\n", std::string(gt.status().message()));
    return mrvs::kExitDataError;
  }
  mrvs::eval::EvaluationOptions options;
  options.association.max_dt_ns = mrvs::from_seconds(args.max_dt_s);
  options.association.time_offset_ns = mrvs::from_seconds(args.time_offset_s);
  options.alignments = alignments_for(args.align);
  options.rpe_delta_m = args.rpe_delta_m;
  options.rpe_delta_s = args.rpe_delta_s;
  options.rpe_use_sim3_scale = args.align == "sim3";
  auto report = mrvs::eval::evaluate(*est, *gt, options);
  if (!report.ok()) {
    fmt::print(stderr, "evaluate_trajectory: error: evaluating '{}' against '{}': {}\n", args.est_path,
               args.gt_path, std::string(report.status().message()));
    return mrvs::kExitDataError;
  }
  report->estimate_file = args.est_path;
  report->ground_truth_file = args.gt_path;
  for (const std::string& note : report->notes) spdlog::warn("{}", note);
  if (report->num_unmatched > 0) {
    spdlog::warn("{} of {} estimate poses have no ground truth within {} s", report->num_unmatched,
                 report->num_estimate_poses, args.max_dt_s);
  }
  fmt::print("{}\n{}", mrvs::eval::format_summary(*report), mrvs::eval::format_key_values(*report));
  if (args.at_ns >= 0) {
    if (auto s = print_error_at(*est, *gt, args.at_ns, options.association); !s.ok()) {
      fmt::print(stderr, "evaluate_trajectory: error: --at {}: {}\n", args.at_ns, std::string(s.message()));
      return mrvs::kExitDataError;
    }
  }
  std::fflush(stdout);
  if (!args.json_path.empty()) {
    std::ofstream out(args.json_path);
    out << mrvs::eval::to_json(*report);
    out.close();
    if (!out) {
      fmt::print(stderr, "evaluate_trajectory: error: cannot write JSON file '{}'\n", args.json_path);
      return mrvs::kExitDataError;
    }
    spdlog::info("wrote {}", args.json_path);
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Evaluates an estimated trajectory against ground truth: association by timestamp (interpolated ground "
      "truth), absolute trajectory error (unaligned and aligned) and relative pose error.",
      "evaluate_trajectory"};
  Args args;
  add_options(app, args);
  if (auto exit_code = mrvs::parse_command_line(app, argc, argv, args.log_level)) return *exit_code;
  return run(args);
}
