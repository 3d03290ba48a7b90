#pragma once
// One-call evaluation of an estimate against ground truth (association, ATE for several
// alignments, RPE per distance and per time) and its text / JSON renderings, used by the
// evaluate_trajectory tool.
#include <optional>
#include <string>
#include <vector>

#include "mrvs/eval/trajectory_eval.h"

namespace mrvs::eval {

/// Options of evaluate().
struct EvaluationOptions {
  AssociationOptions association;
  /// Alignments to report in addition to the unaligned ATE (always computed, first).
  std::vector<AlignmentMethod> alignments = {AlignmentMethod::kSE3};
  double rpe_delta_m = 1.0;  ///< RPE step in travelled ground-truth metres; <= 0 disables
  double rpe_delta_s = 1.0;  ///< RPE step in seconds; <= 0 disables
  /// Multiply estimate translations by the Sim(3) scale for RPE (needs kSim3 in alignments).
  bool rpe_use_sim3_scale = false;
};

/// Everything evaluate() computed.
struct EvaluationReport {
  std::string estimate_file;      ///< for printing only; filled by the caller
  std::string ground_truth_file;  ///< for printing only; filled by the caller
  EvaluationOptions options;
  std::size_t num_estimate_poses = 0;
  std::size_t num_ground_truth_poses = 0;
  std::size_t num_matched = 0;
  std::size_t num_exact = 0;
  std::size_t num_interpolated = 0;
  std::size_t num_nearest = 0;
  std::size_t num_unmatched = 0;
  double duration_s = 0.0;                  ///< first to last matched stamp
  double ground_truth_path_length_m = 0.0;  ///< over the matched poses
  std::vector<AteResult> ate;               ///< ate[0] unaligned, then options.alignments
  std::optional<RpeResult> rpe_distance;    ///< unset when disabled or not computable
  std::optional<RpeResult> rpe_time;        ///< unset when disabled or not computable
  std::vector<std::string> notes;           ///< why a requested figure is missing
};

/// Associates, aligns and computes ATE / RPE. Errors of association and alignment are
/// returned; an RPE that cannot be computed (trajectory shorter than delta) only adds a note.
StatusOr<EvaluationReport> evaluate(const io::Trajectory& estimate, const io::Trajectory& ground_truth,
                                    const EvaluationOptions& options);

/// The ATE result for `method`, or nullptr when it was not computed.
const AteResult* find_ate(const EvaluationReport& report, AlignmentMethod method);

/// Multi-line human-readable summary.
std::string format_summary(const EvaluationReport& report);

/// "KEY: value" lines for scripts, one per figure: MATCHED_POSES, UNMATCHED_POSES,
/// ATE_RMSE_m and ATE_ROT_RMSE_deg (unaligned), ATE_RMSE_<SE3|SIM3|FIRST>_m and
/// ATE_ROT_RMSE_<...>_deg per computed alignment, SIM3_SCALE, RPE_TRANS_RMSE_m,
/// RPE_ROT_RMSE_deg, RPE_PAIRS (per distance) and RPE_TIME_* (per time). A requested RPE
/// that could not be computed prints "nan" and 0 pairs.
std::string format_key_values(const EvaluationReport& report);

/// All figures as a JSON object (non-finite numbers as null).
std::string to_json(const EvaluationReport& report);

}  // namespace mrvs::eval
