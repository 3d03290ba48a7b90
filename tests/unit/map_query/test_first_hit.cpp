// QueryEngine::first_hit against a brute-force dense sampling of the ray (steps << r).
#include <cmath>
#include <random>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>

#include "query_test_maps.h"

namespace mrvs::map::test {
namespace {

/// Tally of one comparison run.
struct Tally {
  int rays = 0;
  int hits = 0;          ///< rays where both found the same voxel
  int misses = 0;        ///< rays where neither found anything
  int corner_clips = 0;  ///< DDA hit a voxel the sampling stepped over (chord < step)
};

/// first_hit vs sample_first_hit. The DDA may report a voxel the samples missed only when the
/// ray's chord in it is shorter than the sampling step (a corner clip); it may never skip a
/// voxel the samples found (unless the ray only touches it, chord ~ 0).
::testing::AssertionResult compare(const QueryEngine& engine, int level, const ReferenceLevel& reference,
                                   const Eigen::Vector3f& o, const Eigen::Vector3f& v, float t_start,
                                   float t_end, Tally* tally) {
  const double r = reference.resolution();
  const double step = r / 64.0;
  const Segment s = make_segment(o, v, t_start, t_end);
  const std::optional<VoxelHit> hit = engine.first_hit(level, o, v, t_start, t_end);
  const std::optional<SampledHit> sampled = sample_first_hit(reference, s, step);
  ++tally->rays;
  const std::string ray = fmt::format("level {} origin ({}, {}, {}) direction ({}, {}, {}) t [{}, {}]", level,
                                      o.x(), o.y(), o.z(), v.x(), v.y(), v.z(), t_start, t_end);
  if (!hit) {
    if (!sampled) {
      ++tally->misses;
      return ::testing::AssertionSuccess();
    }
    const double c = chord(s, sampled->voxel, r);
    if (c < 1e-9) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure()
           << ray << ": DDA missed voxel (" << sampled->voxel.transpose() << ") with chord " << c;
  }
  const std::optional<voxel::VoxelIndex> hv =
      voxel_of(engine.map().levels[static_cast<std::size_t>(level)].points[hit->point_index].position, r);
  double entry_h = 0.0;
  const double chord_h = chord(s, *hv, r, &entry_h);
  if (chord_h < -1e-9) {
    return ::testing::AssertionFailure() << ray << ": DDA hit voxel (" << hv->transpose()
                                         << ") that the segment does not cross (gap " << -chord_h << ")";
  }
  const double expected_t = std::max(s.t_start, entry_h);
  if (std::abs(hit->t_entry - expected_t) > 1e-5 + 1e-6 * std::abs(expected_t)) {
    return ::testing::AssertionFailure()
           << ray << ": t_entry " << hit->t_entry << ", expected " << expected_t;
  }
  if (sampled && sampled->voxel == *hv) {
    ++tally->hits;
    return ::testing::AssertionSuccess();
  }
  if (chord_h <= step) {
    // Earlier than the sampled hit (or no sampled hit): only a corner clip is allowed.
    double entry_s = 0.0;
    if (!sampled || (chord(s, sampled->voxel, r, &entry_s), std::max(s.t_start, entry_s) >= expected_t)) {
      ++tally->corner_clips;
      return ::testing::AssertionSuccess();
    }
  }
  return ::testing::AssertionFailure()
         << ray << ": DDA hit voxel (" << hv->transpose() << ") chord " << chord_h << ", sampling hit "
         << (sampled ? fmt::format("({}, {}, {})", sampled->voxel.x(), sampled->voxel.y(), sampled->voxel.z())
                     : std::string("none"));
}

/// Random unit-ish direction with exact zeros and negative zeros now and then.
Eigen::Vector3f random_direction(std::mt19937_64& rng) {
  std::normal_distribution<float> n(0.0f, 1.0f);
  std::uniform_int_distribution<int> pick(0, 19);
  std::uniform_int_distribution<int> axis(0, 2);
  Eigen::Vector3f v(n(rng), n(rng), n(rng));
  const int kind = pick(rng);
  if (kind == 0) v[axis(rng)] = 0.0f;
  if (kind == 1) v[axis(rng)] = -0.0f;
  if (kind == 2) {  // axis-aligned
    const int a = axis(rng);
    const float value = v[a];
    v.setZero();
    v[a] = value;
  }
  if (kind == 3) v *= 1e-3f;  // not normalised
  if (v.norm() == 0.0f) v = Eigen::Vector3f::UnitX();
  return v;
}

/// Every other ray is aimed near a random stored point of `level` (within 2 voxels), the
/// others go in random directions.
Eigen::Vector3f ray_direction(std::mt19937_64& rng, const Eigen::Vector3f& origin, const MapLevel& level) {
  std::bernoulli_distribution aimed(0.5);
  if (!aimed(rng) || level.points.empty()) return random_direction(rng);
  std::uniform_int_distribution<std::size_t> pick(0, level.points.size() - 1);
  std::uniform_real_distribution<float> jitter(-2.0f, 2.0f);
  const Eigen::Vector3f target =
      level.points[pick(rng)].position +
      static_cast<float>(level.resolution) * Eigen::Vector3f(jitter(rng), jitter(rng), jitter(rng));
  const Eigen::Vector3f v = target - origin;
  return v.norm() > 0.0f ? v : Eigen::Vector3f::UnitZ();
}

std::shared_ptr<VoxelMap> shared_random_map() {
  return std::make_shared<VoxelMap>(random_map({0.01, 0.03, 0.0625}, 0.8, 80, 4000, 7));
}

TEST(FirstHit, MatchesDenseSamplingOnRandomRaysForEveryLevel) {
  const auto map = shared_random_map();
  const QueryEngine engine = make_engine(map);
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<float> where(-1.0f, 1.0f);
  std::uniform_real_distribution<float> start(0.0f, 0.5f);
  std::uniform_real_distribution<float> length(0.0f, 2.5f);
  for (int level = 0; level < 3; ++level) {
    const ReferenceLevel reference(map->levels[static_cast<std::size_t>(level)]);
    Tally tally;
    for (int i = 0; i < 2500; ++i) {
      const Eigen::Vector3f o(where(rng), where(rng), where(rng));
      const Eigen::Vector3f v = ray_direction(rng, o, map->levels[static_cast<std::size_t>(level)]);
      const float t0 = start(rng);
      ASSERT_TRUE(compare(engine, level, reference, o, v, t0, t0 + length(rng), &tally));
    }
    // The comparison means something: many hits and misses, few corner clips.
    EXPECT_GT(tally.hits, tally.rays / 5) << "level " << level;
    EXPECT_GT(tally.misses, tally.rays / 20) << "level " << level;
    EXPECT_LT(tally.corner_clips, tally.rays / 20) << "level " << level;
  }
}

TEST(FirstHit, RandomMapHasNegativeIndicesAndSeveralLevels) {
  const auto map = shared_random_map();
  ASSERT_EQ(map->levels.size(), 3u);
  for (const MapLevel& level : map->levels) {
    int negative = 0;
    for (const MapPoint& p : level.points)
      negative += voxel_of(p.position, level.resolution)->minCoeff() < 0 ? 1 : 0;
    EXPECT_GT(negative, static_cast<int>(level.points.size()) / 2);
  }
}

TEST(FirstHit, AxisAlignedRaysOnVoxelBoundariesAndCentres) {
  // r = 1/16 m: boundaries are exact in binary, so rays run exactly on voxel faces and edges.
  const auto map = std::make_shared<VoxelMap>(random_map({0.0625}, 1.0, 40, 2000, 3));
  const QueryEngine engine = make_engine(map);
  const ReferenceLevel reference(map->levels[0]);
  std::mt19937_64 rng(5);
  std::uniform_int_distribution<int> half_cell(-40, 40);
  std::uniform_int_distribution<int> axis(0, 2);
  std::bernoulli_distribution negative(0.5);
  Tally tally;
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3f o(half_cell(rng) * 0.03125f, half_cell(rng) * 0.03125f, half_cell(rng) * 0.03125f);
    Eigen::Vector3f v = Eigen::Vector3f::Zero();
    v[axis(rng)] = negative(rng) ? -1.0f : 1.0f;
    ASSERT_TRUE(compare(engine, 0, reference, o, v, 0.0f, 2.5f, &tally));
  }
  EXPECT_GT(tally.hits, 300);
  EXPECT_EQ(tally.corner_clips, 0);
}

TEST(FirstHit, DiagonalRaysThroughVoxelCorners) {
  // Rays along (1, 1, 1) through exact voxel corners: every step is a triple tie.
  const auto map = std::make_shared<VoxelMap>(random_map({0.0625}, 1.0, 40, 3000, 4));
  const QueryEngine engine = make_engine(map);
  const ReferenceLevel reference(map->levels[0]);
  std::mt19937_64 rng(6);
  std::uniform_int_distribution<int> cell(-16, 16);
  std::uniform_int_distribution<int> sign(0, 1);
  Tally tally;
  for (int i = 0; i < 2000; ++i) {
    const Eigen::Vector3f o(cell(rng) * 0.0625f, cell(rng) * 0.0625f, cell(rng) * 0.0625f);
    const Eigen::Vector3f v(sign(rng) ? 1.0f : -1.0f, sign(rng) ? 1.0f : -1.0f, sign(rng) ? 1.0f : -1.0f);
    ASSERT_TRUE(compare(engine, 0, reference, o, v, 0.0f, 2.0f, &tally));
  }
  EXPECT_GT(tally.hits + tally.corner_clips, 100);
}

TEST(FirstHit, RayStartingInsideAnOccupiedVoxelReturnsIt) {
  const auto map = shared_random_map();
  const QueryEngine engine = make_engine(map);
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> inside(0.05, 0.95);
  for (std::size_t level = 0; level < map->levels.size(); ++level) {
    const MapLevel& l = map->levels[level];
    for (std::size_t i = 0; i < l.points.size(); i += 7) {
      const voxel::VoxelIndex v = *voxel_of(l.points[i].position, l.resolution);
      const Eigen::Vector3f start =
          point_in_voxel(v, l.resolution, Eigen::Vector3d(inside(rng), inside(rng), inside(rng)));
      const Eigen::Vector3f dir = random_direction(rng);
      // From t = 0 at the start point, and from t = 1.5 with the origin moved back along the ray.
      const std::optional<VoxelHit> a = engine.first_hit(static_cast<int>(level), start, dir, 0.0f, 1.0f);
      ASSERT_TRUE(a.has_value());
      EXPECT_EQ(a->point_index, i);
      EXPECT_EQ(a->t_entry, 0.0f);
      const Eigen::Vector3f back = start - 1.5f * dir.normalized();
      if (voxel_of(back + 1.5f * dir.normalized(), l.resolution) != v) continue;  // float rounding at a face
      const std::optional<VoxelHit> b = engine.first_hit(static_cast<int>(level), back, dir, 1.5f, 3.0f);
      ASSERT_TRUE(b.has_value());
      EXPECT_EQ(b->point_index, i);
      EXPECT_FLOAT_EQ(b->t_entry, 1.5f);
    }
  }
}

TEST(FirstHit, RangeLimitsAreInclusiveOfTheEntryAtTEnd) {
  // One occupied voxel [0.5, 0.51) x [0, 0.01) x [0, 0.01), ray along +x at y = z = 0.005.
  const auto map = single_level_map(0.01, {Eigen::Vector3f(0.505f, 0.005f, 0.005f)});
  const QueryEngine engine = make_engine(map);
  const Eigen::Vector3f o(0.0f, 0.005f, 0.005f);
  const Eigen::Vector3f x = Eigen::Vector3f::UnitX();
  // Entry at t = 0.5, exit at 0.51.
  ASSERT_TRUE(engine.first_hit(0, o, x, 0.0f, 0.5001f).has_value());
  EXPECT_NEAR(engine.first_hit(0, o, x, 0.0f, 0.5001f)->t_entry, 0.5f, 1e-6f);
  EXPECT_FALSE(engine.first_hit(0, o, x, 0.0f, 0.4999f).has_value());
  EXPECT_NEAR(engine.first_hit(0, o, x, 0.5099f, 1.0f)->t_entry, 0.5099f, 1e-6f);  // t_start inside
  EXPECT_FALSE(engine.first_hit(0, o, x, 0.5101f, 1.0f).has_value());              // t_start past it
  // Backwards along -x from beyond the voxel.
  const Eigen::Vector3f o2(1.0f, 0.005f, 0.005f);
  EXPECT_NEAR(engine.first_hit(0, o2, -x, 0.0f, 0.4901f)->t_entry, 0.49f, 1e-6f);
  EXPECT_FALSE(engine.first_hit(0, o2, -x, 0.0f, 0.4899f).has_value());
  // Exact binary boundaries (r = 1/16): a voxel entered exactly at t_end counts.
  const auto exact = single_level_map(0.0625, {Eigen::Vector3f(0.53125f, 0.03125f, 0.03125f)});
  const QueryEngine engine3 = make_engine(exact);
  const Eigen::Vector3f o3(0.0f, 0.03125f, 0.03125f);
  ASSERT_TRUE(engine3.first_hit(0, o3, x, 0.0f, 0.5f).has_value());
  EXPECT_EQ(engine3.first_hit(0, o3, x, 0.0f, 0.5f)->t_entry, 0.5f);
  EXPECT_FALSE(engine3.first_hit(0, o3, x, 0.0f, std::nextafter(0.5f, 0.0f)).has_value());
  EXPECT_EQ(engine3.first_hit(0, Eigen::Vector3f(1.0f, 0.03125f, 0.03125f), -x, 0.0f, 0.4375f)->t_entry,
            0.4375f);
  // An earlier voxel is skipped when t_start is past it.
  const auto two = single_level_map(
      0.01, {Eigen::Vector3f(0.205f, 0.005f, 0.005f), Eigen::Vector3f(0.505f, 0.005f, 0.005f)});
  const QueryEngine engine2 = make_engine(two);
  EXPECT_EQ(engine2.first_hit(0, o, x, 0.0f, 1.0f)->point_index, 0u);
  EXPECT_EQ(engine2.first_hit(0, o, x, 0.3f, 1.0f)->point_index, 1u);
  // Invalid segments.
  EXPECT_FALSE(engine.first_hit(0, o, x, 1.0f, 0.0f).has_value());
  EXPECT_FALSE(engine.first_hit(1, o, x, 0.0f, 1.0f).has_value());
  EXPECT_FALSE(engine.first_hit(-1, o, x, 0.0f, 1.0f).has_value());
  EXPECT_FALSE(engine.first_hit(0, o, Eigen::Vector3f::Zero(), 0.0f, 1.0f).has_value());
}

TEST(FirstHit, RandomSegmentEndsAgreeWithSamplingNearTheirLimits) {
  // Segments that end (or start) within a few sampling steps of an occupied voxel's faces.
  const auto map = shared_random_map();
  const QueryEngine engine = make_engine(map);
  const MapLevel& l = map->levels[0];
  const ReferenceLevel reference(l);
  std::mt19937_64 rng(17);
  std::uniform_real_distribution<double> inside(0.1, 0.9);
  std::uniform_real_distribution<float> near(-2e-4f, 2e-4f);
  Tally tally;
  for (std::size_t i = 0; i < l.points.size(); i += 5) {
    const voxel::VoxelIndex v = *voxel_of(l.points[i].position, l.resolution);
    const Eigen::Vector3d target =
        (v.cast<double>() + Eigen::Vector3d(inside(rng), inside(rng), inside(rng))) * 0.01;
    const Eigen::Vector3f dir = random_direction(rng);
    const Eigen::Vector3f o = (target - 0.7 * dir.cast<double>().normalized()).cast<float>();
    double entry = 0.0;
    const Segment s = make_segment(o, dir, 0.0f, 2.0f);
    chord(s, v, 0.01, &entry);
    const float t_edge = static_cast<float>(entry) + near(rng);
    ASSERT_TRUE(compare(engine, 0, reference, o, dir, 0.0f, t_edge, &tally));  // t_end near the entry
    ASSERT_TRUE(compare(engine, 0, reference, o, dir, t_edge, 2.0f, &tally));  // t_start near it
  }
  EXPECT_GT(tally.hits, tally.rays / 4);
}

TEST(FirstHit, LongRaysAcrossManyEmptyBricksOfAWideMap) {
  // Points 8 km apart make the brick box too large for a dense bitmap: the hash table alone
  // answers. Clusters near the origin; rays of ~20 m cross hundreds of empty bricks.
  VoxelMap wide = random_map({0.01}, 6.0, 300, 2000, 21);
  wide.levels[0].points.push_back(MapPoint{Eigen::Vector3f(-4000.0f, -4000.0f, -4000.0f)});
  wide.levels[0].points.push_back(MapPoint{Eigen::Vector3f(4000.0f, 4000.0f, 4000.0f)});
  const auto map = std::make_shared<VoxelMap>(std::move(wide));
  const QueryEngine engine = make_engine(map);
  const ReferenceLevel reference(map->levels[0]);
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<float> where(-7.0f, 7.0f);
  Tally tally;
  for (int i = 0; i < 800; ++i) {
    const Eigen::Vector3f o(where(rng), where(rng), where(rng));
    ASSERT_TRUE(compare(engine, 0, reference, o, ray_direction(rng, o, map->levels[0]), 0.0f, 15.0f, &tally));
  }
  EXPECT_GT(tally.hits, 100);
  EXPECT_GT(tally.misses, 100);
}

}  // namespace
}  // namespace mrvs::map::test
