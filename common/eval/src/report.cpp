// evaluate() and the text / JSON renderings of its report.
#include "mrvs/eval/report.h"

#include <cmath>
#include <iterator>

#include <fmt/format.h>

#include "mrvs/geometry/angles.h"
#include "mrvs/geometry/so3.h"

namespace mrvs::eval {
namespace {

/// Suffix of the machine-readable keys of an alignment ("" for none).
std::string key_suffix(AlignmentMethod method) {
  switch (method) {
    case AlignmentMethod::kNone:
      return "";
    case AlignmentMethod::kSE3:
      return "_SE3";
    case AlignmentMethod::kSim3:
      return "_SIM3";
    case AlignmentMethod::kFirstPose:
      return "_FIRST";
  }
  return "_UNKNOWN";
}

/// Adds the requested RPE (or a note when it cannot be computed).
void add_rpe(const Association& association, const RpeOptions& options, double scale,
             EvaluationReport* report, std::optional<RpeResult>* slot) {
  if (!(options.delta > 0.0)) return;
  StatusOr<RpeResult> rpe = compute_rpe(association, options, scale);
  if (rpe.ok()) {
    *slot = *std::move(rpe);
  } else {
    report->notes.push_back(std::string(rpe.status().message()));
  }
}

void append_stats_row(std::string* out, const std::string& label, const ErrorStats& s) {
  fmt::format_to(std::back_inserter(*out),
                 "  {:<8} {:>10.6f} {:>10.6f} {:>10.6f} {:>10.6f} {:>10.6f} {:>10.6f}\n", label, s.rmse,
                 s.mean, s.median, s.std, s.min, s.max);
}

void append_rpe_summary(std::string* out, const char* label, const std::optional<RpeResult>& rpe) {
  if (!rpe) return;
  const char* unit = rpe->options.unit == RpeUnit::kMetres ? "m" : "s";
  fmt::format_to(std::back_inserter(*out),
                 "RPE per {} {} ({} pairs, mean separation {:.3f} {}), {}:\n"
                 "  translation [m]:  rmse {:.6f}  mean {:.6f}  median {:.6f}  max {:.6f}\n"
                 "  rotation  [deg]:  rmse {:.6f}  mean {:.6f}  median {:.6f}  max {:.6f}\n",
                 rpe->options.delta, unit, rpe->num_pairs, rpe->mean_pair_delta, unit, label,
                 rpe->translation_m.rmse, rpe->translation_m.mean, rpe->translation_m.median,
                 rpe->translation_m.max, rpe->rotation_deg.rmse, rpe->rotation_deg.mean,
                 rpe->rotation_deg.median, rpe->rotation_deg.max);
}

/// JSON number (null when not finite).
std::string json_number(double v) { return std::isfinite(v) ? fmt::format("{:.17g}", v) : "null"; }

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      out += fmt::format("\\u{:04x}", static_cast<int>(c));
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string json_stats(const ErrorStats& s) {
  return fmt::format(
      R"({{"count": {}, "rmse": {}, "mean": {}, "median": {}, "std": {}, "min": {}, "max": {}}})", s.count,
      json_number(s.rmse), json_number(s.mean), json_number(s.median), json_number(s.std), json_number(s.min),
      json_number(s.max));
}

std::string json_ate(const AteResult& ate) {
  const Alignment& a = ate.alignment;
  const Vec3d t = a.T_gt_est.translation();
  const Quatd q = a.T_gt_est.quaternion();
  return fmt::format(
      R"({{"alignment": "{}", "scale": {}, "t_gt_est_m": [{}, {}, {}], "q_gt_est_xyzw": [{}, {}, {}, {}], )"
      R"("position_m": {}, "rotation_deg": {}, "heading_deg": {}, "heading_final_deg": {}}})",
      alignment_name(a.method), json_number(a.scale), json_number(t.x()), json_number(t.y()),
      json_number(t.z()), json_number(q.x()), json_number(q.y()), json_number(q.z()), json_number(q.w()),
      json_stats(ate.position_m), json_stats(ate.rotation_deg), json_stats(ate.heading_deg),
      json_number(ate.heading_errors_deg.back()));
}

std::string json_rpe(const std::optional<RpeResult>& rpe) {
  if (!rpe) return "null";
  return fmt::format(R"({{"delta": {}, "unit": "{}", "pairs": {}, "mean_pair_delta": {}, )"
                     R"("translation_m": {}, "rotation_deg": {}}})",
                     json_number(rpe->options.delta), rpe->options.unit == RpeUnit::kMetres ? "m" : "s",
                     rpe->num_pairs, json_number(rpe->mean_pair_delta), json_stats(rpe->translation_m),
                     json_stats(rpe->rotation_deg));
}

}  // namespace

StatusOr<EvaluationReport> evaluate(const io::Trajectory& estimate, const io::Trajectory& ground_truth,
                                    const EvaluationOptions& options) {
  EvaluationReport report;
  report.options = options;
  report.num_estimate_poses = estimate.size();
  report.num_ground_truth_poses = ground_truth.size();
  MRVS_ASSIGN_OR_RETURN(const Association association,
                        associate(estimate, ground_truth, options.association));
  report.num_matched = association.matches.size();
  report.num_exact = association.num_exact;
  report.num_interpolated = association.num_interpolated;
  report.num_nearest = association.num_nearest;
  report.num_unmatched = association.num_unmatched;
  report.duration_s = to_seconds(association.matches.back().t_ns - association.matches.front().t_ns);
  report.ground_truth_path_length_m = ground_truth_path_length(association).back();

  std::vector<AlignmentMethod> methods = {AlignmentMethod::kNone};
  for (AlignmentMethod m : options.alignments) {
    if (m != AlignmentMethod::kNone) methods.push_back(m);
  }
  double rpe_scale = 1.0;
  for (AlignmentMethod m : methods) {
    MRVS_ASSIGN_OR_RETURN(const Alignment alignment, align(association, m));
    MRVS_ASSIGN_OR_RETURN(AteResult ate, compute_ate(association, alignment));
    if (m == AlignmentMethod::kSim3 && options.rpe_use_sim3_scale) rpe_scale = alignment.scale;
    report.ate.push_back(std::move(ate));
  }
  add_rpe(association, RpeOptions{options.rpe_delta_m, RpeUnit::kMetres}, rpe_scale, &report,
          &report.rpe_distance);
  add_rpe(association, RpeOptions{options.rpe_delta_s, RpeUnit::kSeconds}, rpe_scale, &report,
          &report.rpe_time);
  return report;
}

const AteResult* find_ate(const EvaluationReport& report, AlignmentMethod method) {
  for (const AteResult& ate : report.ate) {
    if (ate.alignment.method == method) return &ate;
  }
  return nullptr;
}

std::string format_summary(const EvaluationReport& r) {
  std::string out;
  auto it = std::back_inserter(out);
  fmt::format_to(it, "estimate:     {} ({} poses)\nground truth: {} ({} poses)\n", r.estimate_file,
                 r.num_estimate_poses, r.ground_truth_file, r.num_ground_truth_poses);
  fmt::format_to(
      it,
      "association:  {} matched ({} exact, {} interpolated, {} nearest), {} unmatched; max_dt {} s, "
      "time offset {} s\n",
      r.num_matched, r.num_exact, r.num_interpolated, r.num_nearest, r.num_unmatched,
      format_seconds(r.options.association.max_dt_ns), format_seconds(r.options.association.time_offset_ns));
  fmt::format_to(it, "span:         {:.3f} s, {:.3f} m of ground-truth path\n", r.duration_s,
                 r.ground_truth_path_length_m);
  const std::string header = fmt::format("  {:<8} {:>10} {:>10} {:>10} {:>10} {:>10} {:>10}\n", "align",
                                         "rmse", "mean", "median", "std", "min", "max");
  out += "ATE position [m]:\n" + header;
  for (const AteResult& ate : r.ate)
    append_stats_row(&out, alignment_name(ate.alignment.method), ate.position_m);
  out += "ATE rotation [deg]:\n" + header;
  for (const AteResult& ate : r.ate)
    append_stats_row(&out, alignment_name(ate.alignment.method), ate.rotation_deg);
  out += "ATE heading [deg] (about the ground truth's z axis, magnitude; final: signed, at the end):\n" +
         header.substr(0, header.size() - 1) + fmt::format(" {:>10}\n", "final");
  for (const AteResult& ate : r.ate) {
    append_stats_row(&out, alignment_name(ate.alignment.method), ate.heading_deg);
    out.insert(out.size() - 1, fmt::format(" {:>10.6f}", ate.heading_errors_deg.back()));
  }
  for (const AteResult& ate : r.ate) {
    const Alignment& a = ate.alignment;
    if (a.method == AlignmentMethod::kNone) continue;
    const Vec3d t = a.T_gt_est.translation();
    const double angle_deg = so3::log<double>(a.T_gt_est.quaternion()).norm() * kRadToDeg;
    fmt::format_to(
        it, "T_gt_est ({}): translation [{:.4f}, {:.4f}, {:.4f}] m, rotation {:.3f} deg, scale {:.6f}\n",
        alignment_name(a.method), t.x(), t.y(), t.z(), angle_deg, a.scale);
  }
  const std::string rpe_label = r.options.rpe_use_sim3_scale ? "Sim(3) scale applied" : "unscaled";
  append_rpe_summary(&out, rpe_label.c_str(), r.rpe_distance);
  append_rpe_summary(&out, rpe_label.c_str(), r.rpe_time);
  for (const std::string& note : r.notes) fmt::format_to(it, "note: {}\n", note);
  return out;
}

std::string format_key_values(const EvaluationReport& r) {
  std::string out;
  auto it = std::back_inserter(out);
  fmt::format_to(it, "MATCHED_POSES: {}\nUNMATCHED_POSES: {}\n", r.num_matched, r.num_unmatched);
  for (const AteResult& ate : r.ate) {
    const std::string suffix = key_suffix(ate.alignment.method);
    fmt::format_to(it, "ATE_RMSE{}_m: {:.9g}\nATE_ROT_RMSE{}_deg: {:.9g}\n", suffix, ate.position_m.rmse,
                   suffix, ate.rotation_deg.rmse);
    if (ate.alignment.method == AlignmentMethod::kSim3)
      fmt::format_to(it, "SIM3_SCALE: {:.9g}\n", ate.alignment.scale);
  }
  for (const AteResult& ate : r.ate) {  // after the lines above, which scripts read in this order
    const std::string suffix = key_suffix(ate.alignment.method);
    fmt::format_to(it, "ATE_HEADING_RMSE{}_deg: {:.9g}\nATE_HEADING_FINAL{}_deg: {:.9g}\n", suffix,
                   ate.heading_deg.rmse, suffix, ate.heading_errors_deg.back());
  }
  const auto rpe_lines = [&](const char* prefix, double delta, const std::optional<RpeResult>& rpe) {
    if (!(delta > 0.0)) return;
    const double nan = std::nan("");
    fmt::format_to(it, "{}TRANS_RMSE_m: {:.9g}\n{}ROT_RMSE_deg: {:.9g}\n{}PAIRS: {}\n", prefix,
                   rpe ? rpe->translation_m.rmse : nan, prefix, rpe ? rpe->rotation_deg.rmse : nan, prefix,
                   rpe ? rpe->num_pairs : 0);
  };
  rpe_lines("RPE_", r.options.rpe_delta_m, r.rpe_distance);
  rpe_lines("RPE_TIME_", r.options.rpe_delta_s, r.rpe_time);
  return out;
}

std::string to_json(const EvaluationReport& r) {
  std::string ate;
  for (const AteResult& a : r.ate) ate += (ate.empty() ? "" : ", ") + json_ate(a);
  std::string notes;
  for (const std::string& n : r.notes) notes += (notes.empty() ? "" : ", ") + json_string(n);
  return fmt::format(
      "{{\n  \"estimate_file\": {},\n  \"ground_truth_file\": {},\n  \"max_dt_s\": {},\n  \"time_offset_s\": "
      "{},\n"
      "  \"estimate_poses\": {},\n  \"ground_truth_poses\": {},\n  \"matched_poses\": {},\n  \"exact\": {},\n"
      "  \"interpolated\": {},\n  \"nearest\": {},\n  \"unmatched_poses\": {},\n  \"duration_s\": {},\n"
      "  \"ground_truth_path_length_m\": {},\n  \"ate\": [{}],\n  \"rpe_distance\": {},\n  \"rpe_time\": "
      "{},\n"
      "  \"notes\": [{}]\n}}\n",
      json_string(r.estimate_file), json_string(r.ground_truth_file),
      json_number(to_seconds(r.options.association.max_dt_ns)),
      json_number(to_seconds(r.options.association.time_offset_ns)), r.num_estimate_poses,
      r.num_ground_truth_poses, r.num_matched, r.num_exact, r.num_interpolated, r.num_nearest,
      r.num_unmatched, json_number(r.duration_s), json_number(r.ground_truth_path_length_m), ate,
      json_rpe(r.rpe_distance), json_rpe(r.rpe_time), notes);
}

}  // namespace mrvs::eval
