// QueryEngine::query: retries (algorithm.md 2.4), in-view acceptance (decision 3), invalid
// input, unknown resolutions, map validation, thread safety.
#include <cmath>
#include <random>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "query_test_maps.h"

namespace mrvs::map::test {
namespace {

// The ray of the hand-made cases: along +x at y = z = 1e-4, inside the voxel row (i, 0, 0) of
// the 1 cm level. d = 2 m, R0 = 0.75 m: pass 1 covers [1.25, 2.75], a pass after a rejected
// hit [1.5, 2.5], a pass after a miss [0.875, 3.125].
constexpr float kOffAxis = 1e-4f;

RayQuery along_x(float distance = 2.0f) {
  RayQuery q;
  q.origin = Eigen::Vector3f(0.0f, kOffAxis, kOffAxis);
  q.direction = Eigen::Vector3f::UnitX();
  q.initial_distance = distance;
  q.resolution = 0.01f;
  return q;
}

/// A point in voxel (floor(x / 0.01), 0, 0) close to the ray (accepted).
Eigen::Vector3f good(float x) { return Eigen::Vector3f(x, 2e-4f, 1e-4f); }
/// A point in voxel (floor(x / 0.01), 0, 0) at the far corner: 1.39 cm from the ray, beyond
/// r + 0.5 * 2 / 458 = 1.218 cm (rejected).
Eigen::Vector3f bad(float x) { return Eigen::Vector3f(x, 0.0099f, 0.0099f); }

QueryResult run(const std::vector<Eigen::Vector3f>& points, const RayQuery& q = along_x(),
                const QueryOptions& options = {}) {
  const QueryEngine engine = make_engine(single_level_map(0.01, points), options);
  return engine.query(q);
}

TEST(Query, AcceptedFirstHitTakesOnePass) {
  const QueryResult r = run({good(1.305f), good(2.005f)});
  EXPECT_EQ(r.status, QueryStatus::kHit);
  EXPECT_EQ(r.passes, 1);
  EXPECT_EQ(r.level, 0);
  EXPECT_FALSE(r.refined);
  EXPECT_EQ(r.point, good(1.305f));
}

TEST(Query, RejectedFirstHitRetriesWithTwoThirdsOfTheRange) {
  // The bad point at 1.30 is in pass 1 only; pass 2 ([1.5, 2.5]) finds the good one at 2.0.
  const QueryResult r = run({bad(1.305f), good(2.005f)});
  EXPECT_EQ(r.status, QueryStatus::kHit);
  EXPECT_EQ(r.passes, 2);
  EXPECT_EQ(r.point, good(2.005f));
  // A bad point inside [1.5, 2.5] as well: rejected after two passes (the second one's point).
  const QueryResult twice = run({bad(1.305f), bad(1.805f), good(2.005f)});
  EXPECT_EQ(twice.status, QueryStatus::kRejected);
  EXPECT_EQ(twice.passes, 2);
  EXPECT_EQ(twice.point, bad(1.805f));
  // Rejected, and nothing at all in the shorter range: still rejected (pass 1's point).
  const QueryResult nothing = run({bad(1.305f)});
  EXPECT_EQ(nothing.status, QueryStatus::kRejected);
  EXPECT_EQ(nothing.passes, 2);
  EXPECT_EQ(nothing.point, bad(1.305f));
  // A good point behind the bad one but before 1.5 m is not seen by either pass.
  EXPECT_EQ(run({bad(1.265f), good(1.405f)}).status, QueryStatus::kRejected);
}

TEST(Query, MissRetriesWithOneAndAHalfTimesTheRange) {
  // Nothing in [1.25, 2.75]; pass 2 covers [0.875, 3.125].
  const QueryResult after = run({good(3.05f)});
  EXPECT_EQ(after.status, QueryStatus::kHit);
  EXPECT_EQ(after.passes, 2);
  EXPECT_EQ(after.point, good(3.05f));
  const QueryResult before = run({good(0.905f), good(3.05f)});
  EXPECT_EQ(before.status, QueryStatus::kHit);
  EXPECT_EQ(before.passes, 2);
  EXPECT_EQ(before.point, good(0.905f));
  const QueryResult miss = run({good(0.805f), good(3.205f)});
  EXPECT_EQ(miss.status, QueryStatus::kMiss);
  EXPECT_EQ(miss.passes, 2);
  const QueryResult rejected = run({bad(3.05f)});
  EXPECT_EQ(rejected.status, QueryStatus::kRejected);
  EXPECT_EQ(rejected.passes, 2);
  const QueryResult empty = run({});
  EXPECT_EQ(empty.status, QueryStatus::kMiss);
  EXPECT_EQ(empty.passes, 2);
}

TEST(Query, RetryRangesAreTwoThirdsAndOneAndAHalfOfR0) {
  // After a rejected hit at 1.30: [1.5, 2.5]. Voxel [1.49, 1.50) ends before, [2.51, 2.52)
  // starts after; [1.50, 1.51) and [2.49, 2.50) are inside.
  EXPECT_EQ(run({bad(1.305f), good(1.495f)}).status, QueryStatus::kRejected);
  EXPECT_EQ(run({bad(1.305f), good(2.515f)}).status, QueryStatus::kRejected);
  EXPECT_EQ(run({bad(1.305f), good(1.505f)}).status, QueryStatus::kHit);
  EXPECT_EQ(run({bad(1.305f), good(2.495f)}).status, QueryStatus::kHit);
  // After a miss: [0.875, 3.125].
  EXPECT_EQ(run({good(0.865f)}).status, QueryStatus::kMiss);
  EXPECT_EQ(run({good(3.135f)}).status, QueryStatus::kMiss);
  EXPECT_EQ(run({good(0.875f)}).status, QueryStatus::kHit);
  EXPECT_EQ(run({good(3.115f)}).status, QueryStatus::kHit);
  // Pass 1: [1.25, 2.75].
  EXPECT_EQ(run({good(1.255f)}).passes, 1);
  EXPECT_EQ(run({good(2.745f)}).passes, 1);
  EXPECT_EQ(run({good(1.245f)}).passes, 2);  // found by pass 2 just before pass 1's range
  EXPECT_EQ(run({good(1.245f)}).status, QueryStatus::kHit);
  EXPECT_EQ(run({good(2.765f)}).status, QueryStatus::kHit);  // and just after it
  EXPECT_EQ(run({good(2.755f)}).passes, 1);                  // voxel [2.75, 2.76) is entered at t_end exactly
  EXPECT_EQ(run({good(2.765f)}).passes, 2);
}

TEST(Query, SearchRangeStartsAtZeroForShortDistances) {
  // d = 0.3 < R0: pass 1 covers [0, 1.05].
  EXPECT_EQ(run({good(0.005f)}, along_x(0.3f)).status, QueryStatus::kHit);
  EXPECT_EQ(run({good(0.005f)}, along_x(0.3f)).passes, 1);
  EXPECT_EQ(run({good(0.005f)}, along_x(0.0f)).status, QueryStatus::kHit);
}

TEST(Query, InViewThresholdBoundary) {
  for (const double offset : {0.0, 0.5, 0.8}) {
    QueryOptions options;
    options.threshold_offset_px = offset;
    options.focal_length_px = 458.0;
    const RayQuery q = along_x(2.0f);
    const double threshold = 0.01 + offset * 2.0 / 458.0;
    for (const double margin : {-2e-6, 2e-6}) {
      // Point in voxel (200, 0, 0) on the diagonal away from the ray at distance threshold + margin.
      const double offset_yz = (threshold + margin) / std::sqrt(2.0);
      const Eigen::Vector3f p(2.005f, static_cast<float>(kOffAxis + offset_yz),
                              static_cast<float>(kOffAxis + offset_yz));
      const double actual = std::hypot(double(p.y()) - double(kOffAxis), double(p.z()) - double(kOffAxis));
      ASSERT_EQ(*voxel_of(p, 0.01), voxel::VoxelIndex(200, 0, 0));
      ASSERT_LT(std::abs(actual - threshold), 3e-6);
      ASSERT_EQ(actual < threshold, margin < 0);
      const QueryResult r = run({p}, q, options);
      EXPECT_EQ(r.status, margin < 0 ? QueryStatus::kHit : QueryStatus::kRejected)
          << "offset " << offset << " margin " << margin;
    }
  }
  // The threshold grows with d: the same off-ray point is rejected at d = 2 m, accepted at 4 m.
  const Eigen::Vector3f p = bad(2.005f);
  EXPECT_EQ(run({p}, along_x(2.0f)).status, QueryStatus::kRejected);
  RayQuery far = along_x(4.0f);
  far.origin.x() = -2.0f;  // same voxel at t = 4
  EXPECT_EQ(run({p}, far).status, QueryStatus::kHit);
}

TEST(Query, DirectionIsNormalisedByTheEngine) {
  RayQuery q = along_x();
  q.direction = Eigen::Vector3f(250.0f, 0.0f, 0.0f);
  const QueryResult r = run({good(2.005f)}, q);
  EXPECT_EQ(r.status, QueryStatus::kHit);
  EXPECT_EQ(r.passes, 1);
  q.direction = Eigen::Vector3f(1e-20f, 0.0f, 0.0f);
  EXPECT_EQ(run({good(2.005f)}, q).status, QueryStatus::kHit);
}

TEST(Query, InvalidRaysAndUnknownResolutions) {
  const QueryEngine engine = make_engine(single_level_map(0.01, {good(2.005f)}));
  const float nan = std::nanf("");
  const float inf = INFINITY;
  std::vector<RayQuery> invalid;
  for (int k = 0; k < 8; ++k) invalid.push_back(along_x());
  invalid[0].origin.y() = nan;
  invalid[1].origin.x() = inf;
  invalid[2].direction = Eigen::Vector3f::Zero();
  invalid[3].direction.z() = nan;
  invalid[4].direction.x() = -inf;
  invalid[5].initial_distance = -0.1f;
  invalid[6].initial_distance = nan;
  invalid[7].resolution = nan;
  for (const RayQuery& q : invalid) {
    const QueryResult r = engine.query(q);
    EXPECT_EQ(r.status, QueryStatus::kInvalidRay);
    EXPECT_EQ(r.passes, 0);
  }
  for (const float resolution : {0.02f, 0.0f, -0.01f, 0.01f * (1.0f + 2e-4f), 0.01f * (1.0f - 2e-4f)}) {
    RayQuery q = along_x();
    q.resolution = resolution;
    EXPECT_EQ(engine.query(q).status, QueryStatus::kUnknownResolution) << resolution;
  }
  for (const float resolution : {0.01f * (1.0f + 5e-5f), 0.01f * (1.0f - 5e-5f)}) {
    RayQuery q = along_x();
    q.resolution = resolution;
    EXPECT_EQ(engine.query(q).status, QueryStatus::kHit) << resolution;
  }
  // Rays from very far away are valid (their positions near the map are meaningless in
  // float/double, but the query must not misbehave).
  for (const float far : {1e10f, 1e30f, 3e38f}) {
    RayQuery q = along_x();
    q.origin = Eigen::Vector3f(far, far, far);
    q.direction = -q.origin;
    q.initial_distance = q.origin.norm() > 0 && std::isfinite(q.origin.norm()) ? q.origin.norm() : far;
    const QueryResult r = engine.query(q);
    EXPECT_NE(r.status, QueryStatus::kInvalidRay);
    EXPECT_GE(r.passes, 1);
    EXPECT_FALSE(engine.first_hit(0, q.origin, q.direction, 0.0f, far).has_value() &&
                 !std::isfinite(engine.first_hit(0, q.origin, q.direction, 0.0f, far)->t_entry));
  }
  // A default-constructed engine answers instead of crashing.
  const QueryEngine none;
  EXPECT_EQ(none.query(along_x()).status, QueryStatus::kUnknownResolution);
  EXPECT_FALSE(none.first_hit(0, Eigen::Vector3f::Zero(), Eigen::Vector3f::UnitX(), 0.0f, 1.0f).has_value());
}

TEST(Query, LevelsAreSelectedByResolution) {
  auto map = std::make_shared<VoxelMap>();
  for (const double r : {0.01, 0.02, 0.03}) {
    MapLevel level;
    level.resolution = r;
    // Level k holds a point at x = 1.7 + 0.1 k on the ray.
    level.points.push_back(MapPoint{good(static_cast<float>(1.705 + 10 * (r - 0.01)))});
    map->levels.push_back(level);
  }
  const QueryEngine engine = make_engine(map);
  for (int k = 0; k < 3; ++k) {
    RayQuery q = along_x();
    q.resolution = 0.01f * static_cast<float>(k + 1);
    const QueryResult r = engine.query(q);
    EXPECT_EQ(r.status, QueryStatus::kHit);
    EXPECT_EQ(r.level, k);
    EXPECT_EQ(r.point, map->levels[static_cast<std::size_t>(k)].points[0].position);
  }
}

TEST(Query, CreateRejectsInvalidMapsAndOptions) {
  EXPECT_FALSE(QueryEngine::create(nullptr, {}).ok());
  // Two points in one voxel.
  const auto twice = single_level_map(0.01, {good(1.001f), good(1.009f)});
  const Status dup = QueryEngine::create(twice, {}).status();
  EXPECT_FALSE(dup.ok());
  EXPECT_NE(dup.message().find("points 0 and 1"), absl::string_view::npos) << dup;
  EXPECT_NE(dup.message().find("(100, 0, 0)"), absl::string_view::npos) << dup;
  // Non-finite point.
  const auto nan_map = single_level_map(0.01, {good(1.0f), Eigen::Vector3f(0.0f, std::nanf(""), 0.0f)});
  const Status nan_status = QueryEngine::create(nan_map, {}).status();
  EXPECT_NE(nan_status.message().find("point 1"), absl::string_view::npos) << nan_status;
  // Index beyond 21 bits.
  EXPECT_FALSE(QueryEngine::create(single_level_map(0.01, {Eigen::Vector3f(20000.0f, 0.0f, 0.0f)}), {}).ok());
  // Levels not strictly increasing; resolution not positive.
  auto unsorted = std::make_shared<VoxelMap>();
  unsorted->levels.resize(2);
  unsorted->levels[0].resolution = 0.02;
  unsorted->levels[1].resolution = 0.02;
  const Status order = QueryEngine::create(unsorted, {}).status();
  EXPECT_NE(order.message().find("strictly increasing"), absl::string_view::npos) << order;
  EXPECT_FALSE(QueryEngine::create(single_level_map(0.0, {}), {}).ok());
  EXPECT_FALSE(QueryEngine::create(single_level_map(NAN, {}), {}).ok());
  // Options outside their ranges.
  QueryOptions options;
  options.search_range_m = 0.0;
  const Status bad_options = QueryEngine::create(single_level_map(0.01, {}), options).status();
  EXPECT_NE(bad_options.message().find("search_range_m"), absl::string_view::npos) << bad_options;
  // Empty maps and levels are fine.
  EXPECT_TRUE(QueryEngine::create(std::make_shared<VoxelMap>(), {}).ok());
  EXPECT_TRUE(QueryEngine::create(single_level_map(0.01, {}), {}).ok());
}

TEST(Query, EngineKeepsTheMapAndOptions) {
  auto map = single_level_map(0.01, {good(2.005f)});
  QueryOptions options;
  options.search_range_m = 1.5;
  const QueryEngine engine = make_engine(map, options);
  EXPECT_EQ(&engine.map(), map.get());
  EXPECT_EQ(engine.options(), options);
  EXPECT_GT(engine.index_memory_bytes(), 0u);
  const QueryEngine copy = engine;  // copies share the index
  EXPECT_EQ(&copy.map(), map.get());
  EXPECT_EQ(copy.query(along_x()).point, good(2.005f));
}

/// Random rays at a random map's clusters, through all three levels, with refinement.
std::vector<RayQuery> random_queries(const VoxelMap& map, int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> where(-1.5f, 1.5f);
  std::uniform_real_distribution<float> noise(0.9f, 1.1f);
  std::uniform_int_distribution<std::size_t> level(0, map.levels.size() - 1);
  std::vector<RayQuery> queries;
  for (int i = 0; i < count; ++i) {
    const MapLevel& l = map.levels[level(rng)];
    std::uniform_int_distribution<std::size_t> pick(0, l.points.size() - 1);
    RayQuery q;
    q.origin = Eigen::Vector3f(where(rng), where(rng), where(rng));
    const Eigen::Vector3f to = l.points[pick(rng)].position - q.origin;
    q.direction = to;
    q.initial_distance = to.norm() * noise(rng);
    q.resolution = static_cast<float>(l.resolution);
    queries.push_back(q);
  }
  return queries;
}

bool same(const QueryResult& a, const QueryResult& b) {
  return a.status == b.status && a.point == b.point && a.level == b.level && a.passes == b.passes &&
         a.refined == b.refined;
}

TEST(Query, TwoThreadsGiveTheSameResultsAsOne) {
  const auto map = std::make_shared<VoxelMap>(random_map({0.01, 0.03, 0.0625}, 0.8, 80, 4000, 31));
  QueryOptions options;
  options.refine_plane_intersection = true;
  const QueryEngine engine = make_engine(map, options);
  const std::vector<RayQuery> queries = random_queries(*map, 20000, 3);
  std::vector<QueryResult> serial;
  QueryCounters counters;
  for (const RayQuery& q : queries) serial.push_back(engine.query(q, &counters));
  EXPECT_EQ(counters.rays, queries.size());
  EXPECT_GE(counters.passes, counters.rays);
  EXPECT_GT(counters.refined, 0u);
  int hits = 0;
  for (const QueryResult& r : serial) hits += r.status == QueryStatus::kHit ? 1 : 0;
  EXPECT_GT(hits, 2000);

  std::vector<QueryResult> a(queries.size());
  std::vector<QueryResult> b(queries.size());
  const QueryEngine copy = engine;
  std::thread ta([&] {
    for (std::size_t i = 0; i < queries.size(); ++i) a[i] = engine.query(queries[i]);
  });
  std::thread tb([&] {
    for (std::size_t i = queries.size(); i-- > 0;) b[i] = copy.query(queries[i]);
  });
  ta.join();
  tb.join();
  for (std::size_t i = 0; i < queries.size(); ++i) {
    ASSERT_TRUE(same(a[i], serial[i])) << i;
    ASSERT_TRUE(same(b[i], serial[i])) << i;
  }
}

}  // namespace
}  // namespace mrvs::map::test
