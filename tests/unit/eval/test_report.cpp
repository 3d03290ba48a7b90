#include <cmath>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "mrvs/eval/report.h"
#include "synthetic.h"

namespace mrvs::eval {
namespace {

constexpr TimestampNs kT0 = 1'403'715'273'262'142'976;
constexpr DurationNs kMs = 1'000'000;

/// Value of the "KEY: value" line, NaN when the key is missing.
double value_of(const std::string& text, const std::string& key) {
  const std::string needle = "\n" + key + ": ";
  const std::size_t pos = ("\n" + text).find(needle);
  if (pos == std::string::npos) return std::nan("");
  return std::stod(text.substr(pos + needle.size() - 1));
}

TEST(EvalReport, EvaluatesAllAlignmentsAndPrintsKeyValues) {
  const synthetic::SmoothTrajectory traj(31);
  const io::Trajectory gt =
      synthetic::sample([&](double t) { return traj.pose(t); }, kT0, 5 * kMs, 4000);  // 20 s
  const Vec3d t(0.3, -0.4, 1.2);
  io::Trajectory est;
  for (std::size_t i = 10; i + 10 < gt.size(); i += 4) est.push_back(gt[i]);
  est = synthetic::transform(SE3d(Quatd::Identity(), t), est);
  est.push_back({gt.back().t_ns + 500 * kMs, SE3d()});  // beyond the ground truth: unmatched

  EvaluationOptions options;
  options.alignments = {AlignmentMethod::kSE3, AlignmentMethod::kSim3, AlignmentMethod::kFirstPose};
  auto report = evaluate(est, gt, options);
  ASSERT_TRUE(report.ok()) << report.status();
  ASSERT_EQ(report->ate.size(), 4u);
  EXPECT_EQ(report->num_matched, est.size() - 1);
  EXPECT_EQ(report->num_unmatched, 1u);
  ASSERT_NE(find_ate(*report, AlignmentMethod::kSim3), nullptr);
  EXPECT_NEAR(find_ate(*report, AlignmentMethod::kSim3)->alignment.scale, 1.0, 1e-9);
  ASSERT_TRUE(report->rpe_distance.has_value());
  ASSERT_TRUE(report->rpe_time.has_value());

  const std::string kv = format_key_values(*report);
  EXPECT_NEAR(value_of(kv, "ATE_RMSE_m"), 1.3, 1e-7) << kv;
  EXPECT_LT(value_of(kv, "ATE_RMSE_SE3_m"), 1e-7) << kv;
  EXPECT_LT(value_of(kv, "ATE_RMSE_SIM3_m"), 1e-7) << kv;
  EXPECT_LT(value_of(kv, "ATE_RMSE_FIRST_m"), 1e-7) << kv;
  EXPECT_NEAR(value_of(kv, "ATE_ROT_RMSE_deg"), 0.0, 1e-7) << kv;
  EXPECT_NEAR(value_of(kv, "ATE_HEADING_RMSE_deg"), 0.0, 1e-7) << kv;
  EXPECT_NEAR(value_of(kv, "ATE_HEADING_FINAL_SE3_deg"), 0.0, 1e-7) << kv;
  EXPECT_NEAR(value_of(kv, "SIM3_SCALE"), 1.0, 1e-7) << kv;
  EXPECT_NEAR(value_of(kv, "RPE_TRANS_RMSE_m"), 0.0, 1e-7) << kv;
  EXPECT_NEAR(value_of(kv, "RPE_ROT_RMSE_deg"), 0.0, 1e-7) << kv;
  EXPECT_EQ(value_of(kv, "MATCHED_POSES"), static_cast<double>(est.size() - 1)) << kv;
  EXPECT_EQ(value_of(kv, "UNMATCHED_POSES"), 1.0) << kv;
  EXPECT_GT(value_of(kv, "RPE_PAIRS"), 0.0) << kv;
  EXPECT_GT(value_of(kv, "RPE_TIME_PAIRS"), 0.0) << kv;

  const std::string summary = format_summary(*report);
  EXPECT_NE(summary.find("ATE position [m]"), std::string::npos) << summary;
  EXPECT_NE(summary.find("ATE heading [deg]"), std::string::npos) << summary;
  EXPECT_NE(summary.find("1 unmatched"), std::string::npos) << summary;
  const std::string json = to_json(*report);
  EXPECT_NE(json.find("\"matched_poses\": " + std::to_string(est.size() - 1)), std::string::npos) << json;
  EXPECT_NE(json.find("\"alignment\": \"sim3\""), std::string::npos) << json;
  EXPECT_NE(json.find("\"heading_final_deg\": "), std::string::npos) << json;
}

TEST(EvalReport, MissingRpeIsANoteAndNan) {
  const auto line = [](double t) { return SE3d(Quatd::Identity(), Vec3d(t, 0.1 * t * t, 0.0)); };
  const io::Trajectory gt = synthetic::sample(line, kT0, 100 * kMs, 11);  // ~1 m, 1 s
  EvaluationOptions options;
  options.rpe_delta_m = 5.0;
  options.rpe_delta_s = 0.0;  // disabled
  auto report = evaluate(gt, gt, options);
  ASSERT_TRUE(report.ok()) << report.status();
  EXPECT_FALSE(report->rpe_distance.has_value());
  ASSERT_EQ(report->notes.size(), 1u);
  const std::string kv = format_key_values(*report);
  EXPECT_NE(kv.find("RPE_TRANS_RMSE_m: nan"), std::string::npos) << kv;
  EXPECT_NE(kv.find("RPE_PAIRS: 0"), std::string::npos) << kv;
  EXPECT_EQ(kv.find("RPE_TIME_"), std::string::npos) << kv;
  EXPECT_NE(to_json(*report).find("\"rpe_distance\": null"), std::string::npos);
}

TEST(EvalReport, AlignmentErrorsPropagate) {
  const io::Trajectory two = {{kT0, SE3d()}, {kT0 + kMs, SE3d(Quatd::Identity(), Vec3d(1, 0, 0))}};
  auto report = evaluate(two, two, {});
  EXPECT_EQ(report.status().code(), absl::StatusCode::kFailedPrecondition);
}

}  // namespace
}  // namespace mrvs::eval
