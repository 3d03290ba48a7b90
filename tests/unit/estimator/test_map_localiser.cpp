// The edge's side of the localisation: when it asks (after first_request_s, with enough
// points, one request in flight), what it sends (points relative to the anchor, grouped by
// viewpoint, a prior from GNSS), and which answers it trusts: an "ok" alone is not enough, two
// agreeing answers from independent data are; a disagreeing or ambiguous answer makes it ask
// again with more data; stale replies are ignored; an unanswered request is asked again.
#include <deque>
#include <thread>

#include <gtest/gtest.h>

#include "mrvs/edge/map_localiser.h"
#include "mrvs/geometry/angles.h"

namespace mrvs::edge {
namespace {

constexpr TimestampNs kSecond = 1'000'000'000;

/// A cloud that records requests and answers each with the next scripted result (or nothing).
class ScriptedCloud : public MapService {
 public:
  std::optional<MapDescription> description() override { return MapDescription{}; }
  MapReply query(const std::vector<voxel::RayQuery>&, TimestampNs, DurationNs, bool) override { return {}; }
  bool offers_localisation() override { return offers; }
  StatusOr<std::size_t> send_localisation(const localisation::Request& request, float) override {
    sent.push_back(request);
    if (!script.empty()) {
      LocalisationReply r;
      r.seq = request.seq;
      r.result = script.front();
      script.pop_front();
      if (answer) ready.push_back(r);
    }
    return 100 + 6 * request.points.size();
  }
  std::vector<LocalisationReply> poll_localisation() override {
    std::vector<LocalisationReply> out(ready.begin(), ready.end());
    ready.clear();
    return out;
  }
  bool offers = true;
  bool answer = true;
  std::deque<localisation::Result> script;
  std::vector<localisation::Request> sent;
  std::vector<LocalisationReply> ready;
};

localisation::Result ok_result(const SE3d& T_m_o, double ambiguity = 0.3) {
  localisation::Result r;
  r.status = localisation::Status::kOk;
  r.T_m_o = T_m_o;
  r.covariance.diagonal() << 1e-4, 1e-4, 1e-4, 0.0, 0.0, 1e-5;
  r.fitness = 0.9;
  r.ambiguity = ambiguity;
  return r;
}

LocalisationOptions options() {
  LocalisationOptions o;
  o.first_request_s = 1.0;
  o.window_s = 1.0;
  o.max_window_s = 4.0;
  o.interval_s = 1.0;
  o.min_points = 20;
  o.voxel_m = 0.05;
  return o;
}

/// Feeds 30 new points a frame (a wall seen from moving cameras) at 20 Hz from t0 for `seconds`,
/// stepping the localiser; the accepted alignment, if any.
std::optional<Alignment> run(MapLocaliser& loc, ScriptedCloud& cloud, TimestampNs t0, double seconds,
                             LocalisationFrameStats* total = nullptr) {
  std::optional<Alignment> accepted;
  for (TimestampNs t = t0; t < t0 + static_cast<TimestampNs>(seconds * kSecond); t += kSecond / 20) {
    const double s = to_seconds(t - t0);
    std::vector<Vec3d> pts;
    for (int i = 0; i < 30; ++i) pts.emplace_back(3.0, 0.1 * i + s, 0.05 * (i % 7));
    loc.add_points(t, pts, Vec3d(0.0, s, 1.0));
    LocalisationFrameStats stats;
    if (auto a = loc.step(t, Vec3d(0.0, s, 1.0), std::nullopt, cloud, &stats)) accepted = a;
    if (total) total->requests += stats.requests;
    if (accepted) break;
  }
  return accepted;
}

TEST(MapLocaliser, TwoAgreeingAnswersFromNewDataPlaceTheFilter) {
  ScriptedCloud cloud;
  const SE3d T(Quatd(Eigen::AngleAxisd(0.7, Vec3d::UnitZ())), Vec3d(4.0, -2.0, 0.5));
  cloud.script = {ok_result(T), ok_result(T)};
  MapLocaliser loc(options());
  const auto a = run(loc, cloud, 10 * kSecond, 5.0);
  ASSERT_TRUE(a.has_value()) << loc.status();
  ASSERT_EQ(cloud.sent.size(), 2u);
  EXPECT_LT((a->T_m_o.translation() - T.translation()).norm(), 1e-12);
  // The first request waited first_request_s; the second came interval_s later.
  EXPECT_EQ(cloud.sent[0].stamp_ns, 11 * kSecond);
  EXPECT_EQ(cloud.sent[1].stamp_ns, 12 * kSecond);
  // Points relative to the anchor, all within the window, grouped by viewpoint.
  const auto& q = cloud.sent[1];
  std::uint32_t counted = 0;
  for (const auto& v : q.viewpoints) counted += v.count;
  EXPECT_EQ(counted, q.points.size());
  EXPECT_GT(q.viewpoints.size(), 2u);
  EXPECT_LE(q.viewpoints.size(), 64u);
  for (const auto& p : q.points) EXPECT_NEAR(p.x(), 3.0, 0.03);  // the wall, minus the anchor at x = 0
  EXPECT_EQ(q.gravity_o, Vec3d(0, 0, -1));
  EXPECT_EQ(a->anchor_m, T * q.anchor_o);
}

TEST(MapLocaliser, OneAnswerIsNotEnoughAndDisagreementStartsOver) {
  ScriptedCloud cloud;
  const SE3d T(Quatd::Identity(), Vec3d(1.0, 2.0, 0.0));
  const SE3d off(Quatd(Eigen::AngleAxisd(2.0 * kDegToRad, Vec3d::UnitZ())), Vec3d(1.4, 2.0, 0.0));
  cloud.script = {ok_result(T), ok_result(off), ok_result(T)};
  MapLocaliser loc(options());
  // Three answers: T, then a disagreeing one (40 cm off), then T again: never two agreeing in a row.
  EXPECT_FALSE(run(loc, cloud, 0, 4.0).has_value()) << loc.status();
  EXPECT_EQ(cloud.sent.size(), 3u);
  // A fourth agreeing with the third places it.
  cloud.script = {ok_result(T)};
  EXPECT_TRUE(run(loc, cloud, 4 * kSecond, 2.0).has_value()) << loc.status();
}

TEST(MapLocaliser, RefusalsAndAmbiguityAskAgainWithMoreData) {
  ScriptedCloud cloud;
  localisation::Result refused;
  refused.status = localisation::Status::kAmbiguous;
  refused.detail = "another pose";
  cloud.script = {refused, ok_result(SE3d(), 0.95), refused};
  MapLocaliser loc(options());
  EXPECT_FALSE(run(loc, cloud, 0, 3.5).has_value());
  ASSERT_EQ(cloud.sent.size(), 3u);
  // The submap grows after each refusal (1 s, 1.5 s, 2.25 s of data): more points.
  EXPECT_LT(cloud.sent[0].points.size(), cloud.sent[1].points.size());
  EXPECT_LT(cloud.sent[1].points.size(), cloud.sent[2].points.size());
  EXPECT_NE(loc.status().find("asking again"), std::string::npos) << loc.status();
}

/// An ambiguous answer with a best guess (the cloud refined distinct poses, hypotheses > 0).
localisation::Result guess_result(const SE3d& T_m_o, int hypotheses = 6) {
  localisation::Result r = ok_result(T_m_o, 0.9);
  r.status = localisation::Status::kAmbiguous;
  r.hypotheses = hypotheses;
  r.detail = "another pose 4 m / 90 deg away is told apart too weakly";
  return r;
}

LocalisationOptions guessing() {
  LocalisationOptions o = options();
  o.guesses_confirm = true;
  return o;
}

TEST(MapLocaliser, ABestGuessConfirmsAnOkAnswerFromNewDataBeforeOrAfterIt) {
  const SE3d T(Quatd(Eigen::AngleAxisd(0.3, Vec3d::UnitZ())), Vec3d(1.0, 2.0, 0.0));
  {
    ScriptedCloud cloud;
    cloud.script = {ok_result(T), guess_result(T)};
    MapLocaliser loc(guessing());
    const auto a = run(loc, cloud, 0, 3.0);
    ASSERT_TRUE(a.has_value()) << loc.status();
    EXPECT_EQ(cloud.sent.size(), 2u);
    EXPECT_EQ(a->ambiguity, 0.3);  // the ok answer is the one used
    EXPECT_LT((a->T_m_o.translation() - T.translation()).norm(), 1e-12);
    EXPECT_NE(loc.status().find("best guess"), std::string::npos) << loc.status();
  }
  {
    ScriptedCloud cloud;
    cloud.script = {guess_result(T), ok_result(T)};
    MapLocaliser loc(guessing());
    const auto a = run(loc, cloud, 0, 3.0);
    ASSERT_TRUE(a.has_value()) << loc.status();
    EXPECT_EQ(cloud.sent.size(), 2u);
    EXPECT_EQ(a->ambiguity, 0.3);
  }
  {
    // Off (the option's default), the same answers are not enough.
    ScriptedCloud cloud;
    cloud.script = {ok_result(T), guess_result(T)};
    MapLocaliser loc(options());
    EXPECT_FALSE(run(loc, cloud, 0, 3.0).has_value()) << loc.status();
  }
}

TEST(MapLocaliser, BestGuessesNeverLocaliseAloneNorConfirmAWrongPoseOrAStoppedSearch) {
  const SE3d T(Quatd::Identity(), Vec3d(1.0, 2.0, 0.0));
  const SE3d turned(Quatd(Eigen::AngleAxisd(0.5 * kPi, Vec3d::UnitZ())), Vec3d(5.0, 2.0, 0.0));
  {
    ScriptedCloud cloud;  // guesses agreeing with each other: still no ok answer
    cloud.script = {guess_result(T), guess_result(T), guess_result(T), guess_result(T)};
    MapLocaliser loc(guessing());
    EXPECT_FALSE(run(loc, cloud, 0, 5.0).has_value()) << loc.status();
    EXPECT_EQ(cloud.sent.size(), 4u);
  }
  {
    ScriptedCloud cloud;  // the guess puts another pose first
    cloud.script = {ok_result(T), guess_result(turned), guess_result(turned)};
    MapLocaliser loc(guessing());
    EXPECT_FALSE(run(loc, cloud, 0, 4.0).has_value()) << loc.status();
  }
  {
    ScriptedCloud cloud;  // a search stopped by max_search_nodes has no best guess (hypotheses 0)
    cloud.script = {ok_result(T), guess_result(T, 0), guess_result(T, 0)};
    MapLocaliser loc(guessing());
    EXPECT_FALSE(run(loc, cloud, 0, 4.0).has_value()) << loc.status();
  }
  {
    ScriptedCloud cloud;  // from the same data: the guess comes from a submap overlapping the ok one
    LocalisationOptions o = guessing();
    o.max_overlap = 0.0;
    o.window_s = 2.5;
    cloud.script = {ok_result(T), guess_result(T)};
    MapLocaliser loc(o);
    EXPECT_FALSE(run(loc, cloud, 0, 2.5).has_value()) << loc.status();
    EXPECT_EQ(cloud.sent.size(), 2u);
    EXPECT_TRUE(cloud.script.empty());  // both answered
  }
}

TEST(MapLocaliser, WithoutTheServiceItWaitsAndSaysSo) {
  ScriptedCloud cloud;
  cloud.offers = false;
  MapLocaliser loc(options());
  EXPECT_FALSE(run(loc, cloud, 0, 3.0).has_value());
  EXPECT_TRUE(cloud.sent.empty());
  EXPECT_NE(loc.status().find("waiting for the cloud"), std::string::npos) << loc.status();
}

TEST(MapLocaliser, AnUnansweredRequestIsAskedAgainAndItsLateReplyIgnored) {
  ScriptedCloud cloud;
  cloud.answer = false;
  const SE3d T(Quatd::Identity(), Vec3d(1.0, 0.0, 0.0));
  LocalisationOptions o = options();
  o.timeout_s = 0.05;  // wall clock
  MapLocaliser loc(o);
  run(loc, cloud, 0, 1.2);
  ASSERT_EQ(cloud.sent.size(), 1u);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  // The next frame gives request 1 up; request 2 goes out interval_s after request 1.
  LocalisationFrameStats stats;
  EXPECT_FALSE(loc.step(1'250'000'000, Vec3d::Zero(), std::nullopt, cloud, &stats).has_value());
  EXPECT_EQ(stats.timeouts, 1);
  EXPECT_NE(loc.status().find("asking again"), std::string::npos) << loc.status();
  EXPECT_FALSE(loc.step(2'000'000'000, Vec3d::Zero(), std::nullopt, cloud, &stats).has_value());
  ASSERT_EQ(cloud.sent.size(), 2u);
  // Request 1's late reply now arrives: ignored (two of them would otherwise place the filter).
  for (int k = 0; k < 2; ++k) cloud.ready.push_back({cloud.sent[0].seq, ok_result(T), 0, 0});
  stats = {};
  EXPECT_FALSE(loc.step(2'050'000'000, Vec3d::Zero(), std::nullopt, cloud, &stats).has_value());
  EXPECT_EQ(stats.replies, 0);
  // Then answers come again: request 2's, and the next one's.
  cloud.answer = true;
  cloud.script = {ok_result(T)};
  cloud.ready.push_back({cloud.sent[1].seq, ok_result(T), 0, 0});
  EXPECT_TRUE(run(loc, cloud, 2'100'000'000, 4.0).has_value()) << loc.status();
  EXPECT_EQ(cloud.sent.size(), 3u);
}

TEST(MapLocaliser, TheGnssPriorIsTheMedianOfTheWindowWithARadiusFromItsSigmas) {
  std::deque<io::GnssFix> fixes;
  for (int i = 0; i < 5; ++i) fixes.push_back({i * kSecond, Vec3d(100.0 + i, 50.0, 10.0), 1.5, 3.0});
  fixes[2].p_map.x() += 30.0;  // a multipath outlier
  LocalisationOptions o;
  o.gnss_sigmas = 3.0;
  o.gnss_margin_m = 2.0;
  const auto prior = gnss_prior(fixes, 4 * kSecond, 4.0, 0.4, o);
  ASSERT_TRUE(prior.has_value());
  EXPECT_NEAR(prior->centre_m.x(), 103.0, 1e-9);  // median of 100, 101, 132, 103, 104
  EXPECT_NEAR(prior->radius_m, 3.0 * 3.0 + 0.4 + 2.0, 1e-12);
  EXPECT_FALSE(gnss_prior(fixes, 20 * kSecond, 4.0, 0.4, o).has_value());  // none in the window
}

}  // namespace
}  // namespace mrvs::edge
