// The edge's side of the localisation: when it asks (after first_request_s, with enough
// points, one request in flight), what it sends (points relative to the anchor, grouped by
// viewpoint, a prior from GNSS), and which answers it trusts: an "ok" alone is not enough, two
// agreeing answers from independent data are; a disagreeing or ambiguous answer makes it ask
// again with more data; stale replies are ignored; an unanswered request is asked again.
#include <deque>
#include <random>
#include <thread>

#include <gtest/gtest.h>

#include "mrvs/edge/global_alignment.h"
#include "mrvs/edge/map_localiser.h"
#include "mrvs/geometry/angles.h"
#include "mrvs/test/numeric_jacobian.h"

namespace mrvs::edge {
namespace {

constexpr TimestampNs kSecond = 1'000'000'000;
constexpr TimestampNs kMillisecond = 1'000'000;

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
  o.min_dense_pairs = 1;  // the walls of these tests slide along with the camera
  return o;
}

/// One frame at t, s seconds into a run: 30 new points of a wall seen from a camera moving
/// along it, then the localiser's step with the given prior.
std::optional<Alignment> see_wall_and_step(MapLocaliser& loc, ScriptedCloud& cloud, TimestampNs t, double s,
                                           const std::optional<localisation::PriorRegion>& prior,
                                           LocalisationFrameStats* stats) {
  std::vector<Vec3d> pts;
  for (int i = 0; i < 30; ++i) pts.emplace_back(3.0, 0.1 * i + s, 0.05 * (i % 7));
  loc.add_points(t, pts, Vec3d(0.0, s, 1.0));
  return loc.step(t, Vec3d(0.0, s, 1.0), prior, cloud, stats);
}

/// Feeds 30 new points a frame (a wall seen from moving cameras) at 20 Hz from t0 for `seconds`,
/// stepping the localiser; the accepted alignment, if any.
std::optional<Alignment> run(MapLocaliser& loc, ScriptedCloud& cloud, TimestampNs t0, double seconds,
                             LocalisationFrameStats* total = nullptr) {
  std::optional<Alignment> accepted;
  for (TimestampNs t = t0; t < t0 + static_cast<TimestampNs>(seconds * kSecond); t += kSecond / 20) {
    LocalisationFrameStats stats;
    if (auto a = see_wall_and_step(loc, cloud, t, to_seconds(t - t0), std::nullopt, &stats)) accepted = a;
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

// Each submap point carries its cell's mean brightness (0 where nothing in it had one); a
// track not seen in a frame keeps the brightness it was last seen with.
TEST(MapLocaliser, TheRequestCarriesEachCellsMeanBrightness) {
  ScriptedCloud cloud;
  LocalisationOptions o = options();  // 5 cm cells
  MapLocaliser loc(o);
  const TimestampNs t0 = 10 * kSecond;
  for (TimestampNs t = t0; t <= t0 + kSecond; t += kSecond / 20) {
    std::vector<Vec3d> pts;
    std::vector<std::uint8_t> grey;
    for (int i = 0; i < 30; ++i) {
      pts.emplace_back(3.0, 0.2 * i + 0.12, 0.12);  // cell i: 100 + i, and in cell 0 also 120
      grey.push_back(static_cast<std::uint8_t>(100 + i));
    }
    pts.emplace_back(3.0, 0.13, 0.13);
    grey.push_back(120);
    pts.emplace_back(3.0, -1.0, 0.1);  // a cell without brightness
    grey.push_back(0);
    loc.add_points(t, pts, Vec3d(0.0, 0.0, 1.0), grey);
    // A track seen with brightness 60 in the first frame only, then without.
    loc.set_track_point(7, t, Vec3d(3.0, 6.5, 0.1), Vec3d(0.0, 0.0, 1.0), t == t0 ? 60.0f : 0.0f);
    LocalisationFrameStats stats;
    loc.step(t, Vec3d(0.0, 0.0, 1.0), std::nullopt, cloud, &stats);
  }
  ASSERT_EQ(cloud.sent.size(), 1u);
  const localisation::Request& q = cloud.sent[0];
  ASSERT_EQ(q.brightness.size(), q.points.size());
  ASSERT_EQ(q.points.size(), 32u);
  for (std::size_t k = 0; k < q.points.size(); ++k) {
    const Vec3d p = q.points[k].cast<double>() + q.anchor_o;
    const int brightness = q.brightness[k];
    if (std::abs(p.y() - 6.5) < 0.01) {
      EXPECT_EQ(brightness, 60) << k;  // the track kept its last seen brightness
    } else if (p.y() < 0.0) {
      EXPECT_EQ(brightness, 0) << k;  // not known
    } else {
      const int cell = static_cast<int>(std::lround((p.y() - 0.12) / 0.2));
      EXPECT_EQ(brightness, cell == 0 ? 110 : 100 + cell) << k;  // cell 0: (100 + 120) / 2
    }
  }
}

// A submap is dated from the run's first frame when its window reaches back before it: with
// a 3 s window, the answers at 1, 2 and 3 s all hold the first second's data and none is
// independent of the first; the one at 4 s is (its data begins at 1 s).
TEST(MapLocaliser, AnswersInARunsFirstSecondsShareTheirDataAndAreNotIndependent) {
  const SE3d T(Quatd(Eigen::AngleAxisd(0.2, Vec3d::UnitZ())), Vec3d(1.0, 2.0, 0.0));
  LocalisationOptions o = options();
  o.window_s = 3.0;
  {
    ScriptedCloud cloud;
    cloud.script = {ok_result(T), ok_result(T), ok_result(T)};
    MapLocaliser loc(o);
    EXPECT_FALSE(run(loc, cloud, 0, 3.9).has_value()) << loc.status();
    EXPECT_EQ(cloud.sent.size(), 3u);
    EXPECT_TRUE(cloud.script.empty());  // all three answered
  }
  ScriptedCloud cloud;
  cloud.script = {ok_result(T), ok_result(T), ok_result(T), ok_result(T)};
  MapLocaliser loc(o);
  const auto a = run(loc, cloud, 0, 5.0);
  ASSERT_TRUE(a.has_value()) << loc.status();
  EXPECT_EQ(cloud.sent.size(), 4u);
  EXPECT_EQ(cloud.sent.back().stamp_ns, 4 * kSecond);
}

TEST(MapLocaliser, TheAgreeingAnswersAreCombinedByTheirCovariances) {
  ScriptedCloud cloud;
  const SE3d T1(Quatd(Eigen::AngleAxisd(0.3 * kDegToRad, Vec3d::UnitZ())), Vec3d(1.00, 2.0, 0.0));
  const SE3d T2(Quatd(Eigen::AngleAxisd(-0.3 * kDegToRad, Vec3d::UnitZ())), Vec3d(1.02, 2.0, 0.01));
  cloud.script = {ok_result(T1), ok_result(T2)};
  LocalisationOptions o = options();
  o.agree_floor_m = 0.0;  // no drift between the submaps: the plain mean of equal covariances
  o.agree_floor_deg = 0.0;
  MapLocaliser loc(o);
  const auto a = run(loc, cloud, 0, 5.0);
  ASSERT_TRUE(a.has_value()) << loc.status();
  // Brute force: both placements [position; yaw] of the newest anchor x, each with its answer's
  // covariance moved from its own anchor to x, combined by information.
  const Vec3d x_o = cloud.sent[1].anchor_o;
  const Mat6d c = ok_result(T1).covariance;
  Eigen::Matrix4d info = Eigen::Matrix4d::Zero();
  Eigen::Vector4d sum = Eigen::Vector4d::Zero();
  const SE3d Ts[2] = {T1, T2};
  for (int k = 0; k < 2; ++k) {
    Eigen::Vector4d z;
    z << Ts[k] * x_o, yaw_of(Ts[k]) - yaw_of(T2);
    const Eigen::Matrix4d W =
        position_yaw_covariance(c, Ts[k] * cloud.sent[k].anchor_o, Ts[k] * x_o).inverse();
    info += W;
    sum += W * z;
  }
  const Eigen::Vector4d mean = info.inverse() * sum;
  EXPECT_MATRIX_NEAR(a->T_m_o * x_o, Vec3d(mean.head<3>()), 1e-9);
  EXPECT_NEAR(yaw_of(a->T_m_o) - yaw_of(T2), mean(3), 1e-9);
  EXPECT_LT(std::abs(yaw_of(a->T_m_o)), 0.3 * kDegToRad);  // between the two
  EXPECT_MATRIX_NEAR(a->anchor_m, Vec3d(a->T_m_o * x_o), 1e-12);
  const Eigen::Matrix4d fused = info.inverse();
  EXPECT_NEAR(a->covariance(0, 0), fused(0, 0), 1e-12);
  EXPECT_NEAR(a->covariance(5, 5), fused(3, 3), 1e-12);
  EXPECT_LT(a->covariance(0, 0), c(0, 0));
  EXPECT_EQ(a->from_ns, cloud.sent[0].stamp_ns - kSecond);  // both submaps' data: from the first's start
  // With the floors, the older answer weighs less: the fused yaw leans to the newer one's.
  ScriptedCloud cloud2;
  cloud2.script = {ok_result(T1), ok_result(T2)};
  MapLocaliser floored(options());
  const auto b = run(floored, cloud2, 0, 5.0);
  ASSERT_TRUE(b.has_value()) << floored.status();
  EXPECT_LT(yaw_of(b->T_m_o), -0.1 * kDegToRad);
  EXPECT_GT(yaw_of(b->T_m_o), -0.3 * kDegToRad);
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
    EXPECT_EQ(a->ambiguity, 0.3);  // the ok answer's verdict (the two are combined)
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

// What walks through the view is left out of the submap: a cell of dense points needs points
// from min_dense_pairs stereo pairs, and a person moving 1.3 m/s between pairs 0.25 s apart
// never puts two pairs' points in one 5 cm cell, while a wall does.
TEST(MapLocaliser, PointsOfAMovingPersonAreLeftOutOfTheSubmap) {
  LocalisationOptions o = options();
  o.min_dense_pairs = 2;
  MapLocaliser loc(o);
  for (int k = 0; k < 4; ++k) {
    const TimestampNs t = k * kSecond / 4;
    std::vector<Vec3d> pts;
    for (int i = 0; i < 40; ++i) pts.emplace_back(3.0, 0.05 * i + 0.01, 0.02);      // the wall, still
    for (int i = 0; i < 10; ++i) pts.emplace_back(1.5, 0.33 * k, 0.05 * i + 0.01);  // a person, walking
    loc.add_points(t, pts, Vec3d::Zero());
  }
  const auto q = loc.build_request(kSecond, Vec3d::Zero());
  ASSERT_TRUE(q.has_value());
  ASSERT_EQ(q->points.size(), 40u);
  for (const auto& p : q->points) EXPECT_NEAR(p.x(), 3.0f, 0.03f) << "a person's point was sent";
  // With min_dense_pairs 1 the person is in it.
  o.min_dense_pairs = 1;
  MapLocaliser all(o);
  for (int k = 0; k < 4; ++k) {
    std::vector<Vec3d> pts;
    for (int i = 0; i < 40; ++i) pts.emplace_back(3.0, 0.05 * i + 0.01, 0.02);
    for (int i = 0; i < 10; ++i) pts.emplace_back(1.5, 0.33 * k, 0.05 * i + 0.01);
    all.add_points(k * kSecond / 4, pts, Vec3d::Zero());
  }
  const auto with_person = all.build_request(kSecond, Vec3d::Zero());
  ASSERT_TRUE(with_person.has_value());
  EXPECT_EQ(with_person->points.size(), 80u);
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

/// Tracking after the lock: frames from t0 for `seconds` (points as run()), the given prior on
/// every request, every fix applied (as the filter's gate would); the pose fixes step() returned.
std::vector<Alignment> track(MapLocaliser& loc, ScriptedCloud& cloud, TimestampNs t0, double seconds,
                             const localisation::PriorRegion& prior) {
  std::vector<Alignment> fixes;
  for (TimestampNs t = t0; t < t0 + static_cast<TimestampNs>(seconds * kSecond); t += kSecond / 20) {
    LocalisationFrameStats stats;
    if (auto a = see_wall_and_step(loc, cloud, t, to_seconds(t - t0), prior, &stats)) {
      fixes.push_back(*a);
      EXPECT_FALSE(loc.note_fix(true));
    }
  }
  return fixes;
}

TEST(MapLocaliser, OncePlacedItAsksForAPoseFixEveryTrackIntervalWithItsPrior) {
  ScriptedCloud cloud;
  const SE3d T(Quatd(Eigen::AngleAxisd(0.3, Vec3d::UnitZ())), Vec3d(1.0, 2.0, 0.0));
  cloud.script = {ok_result(T), ok_result(T)};
  LocalisationOptions o = options();
  o.track_interval_s = 2.0;
  MapLocaliser loc(o);
  const auto a = run(loc, cloud, 0, 5.0);
  ASSERT_TRUE(a.has_value()) << loc.status();
  const TimestampNs lock = cloud.sent.back().stamp_ns;
  loc.start_tracking(lock);
  EXPECT_TRUE(loc.tracking());
  EXPECT_TRUE(loc.active());
  // The first fix window_s (1 s) after the lock (it checks the lock): new data from the lock on.
  EXPECT_TRUE(loc.gathering(lock + kSecond / 2));
  // In the map frame now: an ok answer is a fix, an ambiguous or refused one is not.
  const SE3d fix(Quatd(Eigen::AngleAxisd(0.002, Vec3d::UnitZ())), Vec3d(0.02, -0.01, 0.0));
  localisation::Result refused;
  refused.status = localisation::Status::kTooLittleStructure;
  cloud.script = {ok_result(fix), ok_result(fix, 0.95), refused, ok_result(fix)};
  const localisation::PriorRegion prior{Vec3d(5.0, 6.0, 1.0), 1.2};
  const std::vector<Alignment> fixes = track(loc, cloud, lock + kSecond / 20, 8.1, prior);
  // After an applied fix the next one comes track_interval_s (2 s) later, after any other
  // answer window_s (1 s) later: at 1 (ok), 3 (ambiguous), 4 (refused), 5 (ok), 7 s.
  const double at[] = {1.0, 3.0, 4.0, 5.0, 7.0};
  ASSERT_EQ(cloud.sent.size(), 7u);
  // Between an applied fix (at 5 s) and window_s before the next request (8 s: the one at 7 s
  // is unanswered), nothing is gathered.
  EXPECT_FALSE(loc.gathering(cloud.sent[5].stamp_ns + kSecond / 2));
  EXPECT_FALSE(loc.wants_dense(cloud.sent[5].stamp_ns + kSecond / 2));
  EXPECT_TRUE(loc.gathering(cloud.sent[6].stamp_ns));
  for (std::size_t k = 2; k < cloud.sent.size(); ++k) {
    EXPECT_NEAR(to_seconds(cloud.sent[k].stamp_ns - lock), at[k - 2], 0.051) << k;
    ASSERT_TRUE(cloud.sent[k].prior.has_value());
    EXPECT_EQ(cloud.sent[k].prior->centre_m, prior.centre_m);
    EXPECT_EQ(cloud.sent[k].prior->radius_m, prior.radius_m);
    // Only the last window_s of data: the wall's points seen in it lie from 1 m behind the
    // anchor (y = 0.1 i + s, the anchor at y = s) on; older ones would lie farther back.
    ASSERT_FALSE(cloud.sent[k].points.empty());
    for (const auto& p : cloud.sent[k].points) EXPECT_GE(p.y(), -1.0 - 1e-4) << k;
  }
  ASSERT_EQ(fixes.size(), 2u);
  for (const Alignment& f : fixes) {
    EXPECT_MATRIX_NEAR(f.T_m_o.translation(), fix.translation(), 1e-12);
    EXPECT_LE(f.from_ns, f.t_ns - static_cast<TimestampNs>(0.99 * kSecond));
  }
}

TEST(MapLocaliser, WithoutATrackIntervalItStopsAskingOncePlaced) {
  ScriptedCloud cloud;
  cloud.script = {ok_result(SE3d()), ok_result(SE3d())};
  MapLocaliser loc(options());  // track_interval_s 0
  ASSERT_TRUE(run(loc, cloud, 0, 5.0).has_value()) << loc.status();
  loc.start_tracking(3 * kSecond);
  EXPECT_FALSE(loc.active());
  EXPECT_FALSE(loc.gathering(10 * kSecond));
  cloud.script = {ok_result(SE3d())};
  EXPECT_TRUE(track(loc, cloud, 3 * kSecond, 10.0, {}).empty());
  EXPECT_EQ(cloud.sent.size(), 2u);
  // A restart forgets the tracking: it localises again from scratch.
  loc.reset();
  EXPECT_FALSE(loc.tracking());
  EXPECT_TRUE(loc.active());
  EXPECT_TRUE(loc.gathering(20 * kSecond));
}

TEST(MapLocaliser, PoseFixesRefusedInARowDoubtTheLockAndItSearchesAgain) {
  ScriptedCloud cloud;
  cloud.script = {ok_result(SE3d()), ok_result(SE3d())};
  LocalisationOptions o = options();
  o.track_interval_s = 2.0;
  o.doubt_after_refusals = 3;
  MapLocaliser loc(o);
  ASSERT_TRUE(run(loc, cloud, 0, 5.0).has_value()) << loc.status();
  loc.start_tracking(3 * kSecond);
  // A first fix applied ends the probation; two refusals, then an applied fix: the count
  // starts over.
  EXPECT_FALSE(loc.note_fix(true));
  EXPECT_FALSE(loc.note_fix(false));
  EXPECT_FALSE(loc.note_fix(false));
  EXPECT_FALSE(loc.note_fix(true));
  EXPECT_FALSE(loc.note_fix(false));
  EXPECT_FALSE(loc.note_fix(false));
  EXPECT_TRUE(loc.tracking());
  // The third in a row: doubted, back to the search (no prior, two agreeing answers needed).
  EXPECT_TRUE(loc.note_fix(false));
  EXPECT_FALSE(loc.tracking());
  EXPECT_NE(loc.status().find("doubted"), std::string::npos) << loc.status();
  const std::size_t before = cloud.sent.size();
  cloud.script = {ok_result(SE3d()), ok_result(SE3d())};
  EXPECT_TRUE(run(loc, cloud, 20 * kSecond, 5.0).has_value()) << loc.status();
  EXPECT_EQ(cloud.sent.size(), before + 2);
  EXPECT_FALSE(cloud.sent.back().prior.has_value());
  // On probation (no fix applied since the lock), the first refusal doubts it.
  loc.start_tracking(30 * kSecond);
  EXPECT_TRUE(loc.note_fix(false));
  EXPECT_NE(loc.status().find("first pose fix"), std::string::npos) << loc.status();
  // With doubt_after_refusals 0 it never doubts.
  o.doubt_after_refusals = 0;
  MapLocaliser trusting(o);
  trusting.start_tracking(0);
  for (int k = 0; k < 10; ++k) EXPECT_FALSE(trusting.note_fix(false));
  EXPECT_TRUE(trusting.tracking());
}

/// A car driving at `speed` along a turning path for 8 s; the odometry frame is the map frame
/// turned by `yaw` and moved (its heading in the map unknown to the edge). Returns the map-frame
/// body positions every 0.1 s and the odometry track of the same instants.
std::pair<std::vector<Vec3d>, std::deque<OdometrySample>> drive(double speed, double turn_rate, double yaw,
                                                                const Vec3d& offset) {
  std::vector<Vec3d> p_m;
  std::deque<OdometrySample> track;
  const SE3d T_o_m(Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Vec3d::UnitZ())), offset);
  Vec3d p(500.0, -200.0, 3.0);
  double heading = 0.3;
  for (int k = 0; k <= 80; ++k) {
    p_m.push_back(p);
    track.push_back({k * 100 * kMillisecond, T_o_m * p});
    p += 0.1 * speed * Vec3d(std::cos(heading), std::sin(heading), 0.0);
    heading += 0.1 * turn_rate;
  }
  return {p_m, track};
}

/// Each fix bounds where the body is now by its error bound plus the distance driven since (the
/// odometry frame keeps distances whatever its heading): checked on random drives with errors
/// up to the bound, the true anchor is always inside the prior, and the prior is the newest
/// fix's sphere (the smallest).
TEST(MapLocaliser, TheGnssPriorHoldsTheMovingBodyWhateverTheOdometryHeading) {
  LocalisationOptions o;
  o.gnss_sigmas = 3.0;
  o.gnss_margin_m = 2.0;
  const double lever = 0.4, sh = 1.5, sv = 3.0;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 100; ++trial) {
    const auto [p_m, track] = drive(12.0 * std::abs(u(rng)), 0.3 * u(rng), M_PI * u(rng),
                                    Vec3d(100 * u(rng), 100 * u(rng), u(rng)));
    std::deque<io::GnssFix> fixes;  // 1 Hz, the antenna off by up to the bound in any direction
    for (int k = 0; k <= 70; k += 10) {
      const Vec3d err = Vec3d(u(rng), u(rng), u(rng)).normalized() * 3.0 * sv * std::abs(u(rng));
      fixes.push_back({k * 100 * kMillisecond, p_m[static_cast<std::size_t>(k)] + err, sh, sv});
    }
    const TimestampNs now = 78 * 100 * kMillisecond;
    const auto prior = gnss_prior(fixes, track, now, track[78].p_o, 6.0, lever, o);
    ASSERT_TRUE(prior.has_value());
    EXPECT_LE((p_m[78] - prior->centre_m).norm(), prior->radius_m) << trial;
    EXPECT_EQ(prior->centre_m, fixes.back().p_map) << trial;
    EXPECT_NEAR(prior->radius_m, 3.0 * sv + lever + (track[78].p_o - track[70].p_o).norm() + 2.0, 1e-9);
  }
}

TEST(MapLocaliser, TheGnssPriorDropsAnOutlierAndNeedsAFixTheTrackCovers) {
  LocalisationOptions o;
  o.gnss_sigmas = 3.0;
  o.gnss_margin_m = 2.0;
  const auto [p_m, track] = drive(10.0, 0.0, 1.0, Vec3d(5.0, 6.0, 0.0));
  std::deque<io::GnssFix> fixes;
  for (int k = 0; k <= 70; k += 10)
    fixes.push_back({k * 100 * kMillisecond, p_m[static_cast<std::size_t>(k)], 1.5, 3.0});
  fixes.back().p_map.y() += 40.0;  // the newest fix a multipath outlier
  const TimestampNs now = 78 * 100 * kMillisecond;
  const auto prior = gnss_prior(fixes, track, now, track[78].p_o, 6.0, 0.4, o);
  ASSERT_TRUE(prior.has_value());
  EXPECT_EQ(prior->centre_m, fixes[6].p_map);  // the newest fix that agrees with the others
  EXPECT_LE((p_m[78] - prior->centre_m).norm(), prior->radius_m);
  // Two fixes that contradict each other: a region around both still holds the body.
  const std::deque<io::GnssFix> two(fixes.end() - 2, fixes.end());
  const auto both = gnss_prior(two, track, now, track[78].p_o, 6.0, 0.4, o);
  ASSERT_TRUE(both.has_value());
  EXPECT_LE((p_m[78] - both->centre_m).norm(), both->radius_m);
  EXPECT_LE((fixes.back().p_map - both->centre_m).norm(), both->radius_m);
  // Fixes older than the window, or before the track began (a new run): no prior.
  EXPECT_FALSE(gnss_prior(fixes, track, 20 * kSecond, track[78].p_o, 6.0, 0.4, o).has_value());
  const std::deque<OdometrySample> late(track.end() - 5, track.end());
  EXPECT_FALSE(gnss_prior(fixes, late, now, track[78].p_o, 6.0, 0.4, o).has_value());
}

// After a restart from a placed pose: the new run lies within the radius plus the lost motion
// plus its path of where the last run ended, whatever its unknown heading. Checked on random
// walks: the true position is always inside the region.
TEST(MapLocaliser, TheRestartPriorHoldsTheNewRunWhateverItsHeading) {
  LocalisationOptions o;
  o.restart_radius_m = 0.5;
  const RunEnd end{Vec3d(3.0, -2.0, 1.0), 1.2, 10 * kSecond};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    // Lost motion over the 0.3 s gap at no more than the speed, then a walk of 20 steps.
    Vec3d p = end.p_m + Vec3d(u(rng), u(rng), u(rng)).normalized() * 1.2 * 0.3 * std::abs(u(rng));
    double path = 0.0;
    for (int k = 0; k < 20; ++k) {
      const Vec3d step = Vec3d(u(rng), u(rng), 0.2 * u(rng)) * 0.1;
      p += step;
      path += step.norm();
      const auto prior = restart_prior(end, 10 * kSecond + 300 * kMillisecond, path, o);
      ASSERT_TRUE(prior.has_value());
      EXPECT_EQ(prior->centre_m, end.p_m);
      EXPECT_LE((p - prior->centre_m).norm(), prior->radius_m);
    }
  }
  EXPECT_NEAR(restart_prior(end, 12 * kSecond, 1.0, o)->radius_m, 0.5 + 1.2 * 2.0 + 1.0, 1e-12);
  // A run that ended unplaced hands its reached radius on: the next run's region contains it.
  const auto reached = restart_prior(end, 12 * kSecond, 3.0, o);
  const RunEnd chained{reached->centre_m, 0.5, 20 * kSecond, reached->radius_m};
  const auto next = restart_prior(chained, 21 * kSecond, 2.0, o);
  EXPECT_EQ(next->centre_m, end.p_m);
  EXPECT_NEAR(next->radius_m, reached->radius_m + 0.5 + 0.5 * 1.0 + 2.0, 1e-12);
  o.restart_radius_m = 0.0;  // off
  EXPECT_FALSE(restart_prior(end, 12 * kSecond, 1.0, o).has_value());
}

TEST(MapLocaliser, TheTighterPriorIsTheSmallerOne) {
  const localisation::PriorRegion small{Vec3d(1.0, 0.0, 0.0), 2.0};
  const localisation::PriorRegion large{Vec3d(0.0, 5.0, 0.0), 20.0};
  EXPECT_EQ(tighter(small, large)->centre_m, small.centre_m);
  EXPECT_EQ(tighter(large, small)->centre_m, small.centre_m);
  EXPECT_EQ(tighter(std::nullopt, large)->radius_m, 20.0);
  EXPECT_EQ(tighter(small, std::nullopt)->radius_m, 2.0);
  EXPECT_FALSE(tighter(std::nullopt, std::nullopt).has_value());
}

}  // namespace
}  // namespace mrvs::edge
