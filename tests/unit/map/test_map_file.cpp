// The .mrvm file: checksum function, exact round trip, every corruption rejected by name.
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "map_test_util.h"
#include "mrvs/map/map_file.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::map {
namespace {

using ::testing::HasSubstr;

TEST(Fnv1a64, KnownVectorsAndIncremental) {
  EXPECT_EQ(fnv1a_64("", 0), 0xcbf29ce484222325ull);
  EXPECT_EQ(fnv1a_64("a", 1), 0xaf63dc4c8601ec8cull);
  EXPECT_EQ(fnv1a_64("foobar", 6), 0x85944171f73967e8ull);
  const std::string text = "multi-resolution voxel map";
  EXPECT_EQ(fnv1a_64(text.data() + 5, text.size() - 5, fnv1a_64(text.data(), 5)),
            fnv1a_64(text.data(), text.size()));
  // One flipped bit changes the hash.
  std::string flipped = text;
  flipped[3] ^= 0x10;
  EXPECT_NE(fnv1a_64(flipped.data(), flipped.size()), fnv1a_64(text.data(), text.size()));
}

/// A valid map with awkward float values (negative zero, subnormal, large).
VoxelMap sample_map() {
  VoxelMap map;
  map.origin = Vec3d(332017.0, 4140023.0, -12.5);
  map.raw_point_count = 123456789;
  map.description = "test map\nline two; UTF-8: \xc3\xa9t\xc3\xa9";
  const std::vector<double> resolutions = {0.01, 0.02, 0.03};
  for (std::size_t l = 0; l < resolutions.size(); ++l) {
    MapLevel level;
    level.resolution = resolutions[l];
    for (int i = 0; i < 200; ++i) {
      MapPoint p;
      const float r = static_cast<float>(resolutions[l]);
      p.position =
          Eigen::Vector3f(r * (static_cast<float>(i) + 0.37f), -r * (static_cast<float>(i % 7) + 0.5f),
                          r * 0.25f + 1e-7f * static_cast<float>(i));
      p.intensity = static_cast<float>(i) * 1.1f - 50.0f;
      p.saliency = 1e3f / static_cast<float>(i + 1);
      level.points.push_back(p);
    }
    map.levels.push_back(level);
  }
  map.levels[0].points[0].intensity = -0.0f;
  map.levels[0].points[1].saliency = std::numeric_limits<float>::denorm_min();
  map.levels[0].points[2].intensity = 3.0e38f;
  return map;
}

TEST(MapFile, RoundTripIsExact) {
  mrvs::test::TempDir dir;
  const VoxelMap map = sample_map();
  ASSERT_TRUE(save_voxel_map(dir / "m.mrvm", map).ok());
  const std::string bytes = test::read_bytes(dir / "m.mrvm");
  EXPECT_EQ(bytes.size(), map_file_size(map));
  EXPECT_EQ(bytes.size(), 56u + 16u * 3u + map.description.size() + 20u * 600u + 8u);
  EXPECT_EQ(bytes.substr(0, 8), std::string("MRVMAP\r\n"));
  EXPECT_EQ(bytes[8], 1);  // version 1, little-endian
  EXPECT_EQ(bytes[9], 0);

  auto loaded = load_voxel_map(dir / "m.mrvm");
  ASSERT_TRUE(loaded.ok()) << loaded.status();
  EXPECT_EQ(std::memcmp(loaded->origin.data(), map.origin.data(), sizeof(double) * 3), 0);
  EXPECT_EQ(loaded->raw_point_count, map.raw_point_count);
  EXPECT_EQ(loaded->description, map.description);
  ASSERT_EQ(loaded->levels.size(), map.levels.size());
  for (std::size_t l = 0; l < map.levels.size(); ++l) {
    EXPECT_EQ(loaded->levels[l].resolution, map.levels[l].resolution);
    ASSERT_EQ(loaded->levels[l].points.size(), map.levels[l].points.size());
    for (std::size_t i = 0; i < map.levels[l].points.size(); ++i) {
      EXPECT_TRUE(test::same_bits(loaded->levels[l].points[i], map.levels[l].points[i])) << l << " " << i;
    }
  }
  EXPECT_TRUE(std::signbit(loaded->levels[0].points[0].intensity));
  // Serialising the loaded map gives the same bytes.
  EXPECT_TRUE(*serialize_voxel_map(*loaded) == bytes);
}

/// Rewrites the checksum after a deliberate change, so only the semantic checks can catch it.
std::string with_checksum(std::string bytes) {
  const std::uint64_t h = fnv1a_64(bytes.data(), bytes.size() - 8);
  for (int b = 0; b < 8; ++b)
    bytes[bytes.size() - 8 + static_cast<std::size_t>(b)] = static_cast<char>((h >> (8 * b)) & 0xff);
  return bytes;
}

void put_u64(std::string& bytes, std::size_t offset, std::uint64_t v) {
  for (int b = 0; b < 8; ++b)
    bytes[offset + static_cast<std::size_t>(b)] = static_cast<char>((v >> (8 * b)) & 0xff);
}
void put_u32(std::string& bytes, std::size_t offset, std::uint32_t v) {
  for (int b = 0; b < 4; ++b)
    bytes[offset + static_cast<std::size_t>(b)] = static_cast<char>((v >> (8 * b)) & 0xff);
}
template <class T>
void put(std::string& bytes, std::size_t offset, T v) {
  std::memcpy(bytes.data() + offset, &v, sizeof(v));
}

class CorruptMapFile : public ::testing::Test {
 protected:
  void SetUp() override {
    map_ = sample_map();
    auto bytes = serialize_voxel_map(map_);
    ASSERT_TRUE(bytes.ok());
    good_ = *bytes;
    points_offset_ = 56 + 16 * 3 + map_.description.size();
  }
  /// Loads `bytes` from a file named "bad.mrvm"; returns the error message ("" if it loaded).
  std::string load_error(const std::string& bytes) {
    test::write_bytes(dir_ / "bad.mrvm", bytes);
    auto map = load_voxel_map(dir_ / "bad.mrvm");
    EXPECT_FALSE(map.ok());
    if (map.ok()) return "";
    const std::string msg(map.status().message());
    EXPECT_THAT(msg, HasSubstr("bad.mrvm"));
    return msg;
  }
  mrvs::test::TempDir dir_;
  VoxelMap map_;
  std::string good_;
  std::size_t points_offset_ = 0;
};

TEST_F(CorruptMapFile, FlippedBytesFailTheChecksum) {
  for (const std::size_t offset : {std::size_t{30}, std::size_t{50}, std::size_t{60}, points_offset_ - 3,
                                   points_offset_ + 7, good_.size() / 2, good_.size() - 9}) {
    std::string bytes = good_;
    bytes[offset] ^= 0x01;
    EXPECT_THAT(load_error(bytes), HasSubstr("checksum mismatch")) << offset;
  }
  for (const std::size_t offset : {good_.size() - 8, good_.size() - 1}) {
    std::string bytes = good_;
    bytes[offset] ^= 0x80;
    EXPECT_THAT(load_error(bytes), HasSubstr("checksum mismatch")) << offset;
  }
}

TEST_F(CorruptMapFile, FlippedHeaderCountsAreCaught) {
  std::string bytes = good_;
  bytes[16] ^= 0x04;  // level count 3 -> 7: levels 3 to 6 read text and points as counts
  EXPECT_THAT(load_error(bytes), HasSubstr("the header is corrupt"));
  bytes = good_;
  bytes[16] ^= 0x01;  // level count 3 -> 2
  EXPECT_THAT(load_error(bytes), HasSubstr("unexpected bytes"));
  bytes = good_;
  bytes[56 + 8] ^= 0x01;  // level 0 count 200 -> 201
  EXPECT_THAT(load_error(bytes), HasSubstr("(20 bytes missing)"));
  bytes = good_;
  bytes[56 + 8] ^= 0x08;  // 200 -> 192: 160 bytes too many
  EXPECT_THAT(load_error(bytes), HasSubstr("160 unexpected bytes"));
}

TEST_F(CorruptMapFile, TruncatedAtSeveralLengths) {
  EXPECT_THAT(load_error(""), HasSubstr("not a .mrvm"));
  for (const std::size_t length :
       {std::size_t{5}, std::size_t{10}, std::size_t{30}, std::size_t{56}, std::size_t{70}, points_offset_,
        points_offset_ + 21, good_.size() - 8, good_.size() - 1}) {
    const std::string msg = load_error(good_.substr(0, length));
    EXPECT_THAT(msg, HasSubstr("truncated")) << length;
    EXPECT_THAT(msg, HasSubstr("bytes missing")) << length;
    if (length >= 56 + 48) {
      EXPECT_THAT(msg, HasSubstr(fmt::format("({} bytes missing)", good_.size() - length))) << length;
    }
  }
}

TEST_F(CorruptMapFile, WrongMagicAndFutureVersion) {
  std::string bytes = good_;
  bytes[0] = 'X';
  EXPECT_THAT(load_error(bytes), HasSubstr("not a .mrvm map file"));
  EXPECT_THAT(load_error("ply\nformat ascii 1.0\n"), HasSubstr("not a .mrvm map file"));
  bytes = good_;
  bytes[6] = '\n';  // text-mode conversion of CR LF
  bytes.erase(7, 1);
  EXPECT_THAT(load_error(bytes), HasSubstr("not a .mrvm map file"));
  bytes = with_checksum([&] {
    std::string b = good_;
    put_u32(b, 8, 2);
    return b;
  }());
  const std::string msg = load_error(bytes);
  EXPECT_THAT(msg, HasSubstr("unsupported .mrvm format version 2"));
  EXPECT_THAT(msg, HasSubstr("reads version 1"));
}

TEST_F(CorruptMapFile, NonFiniteValuesWithAValidChecksum) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::string bytes = good_;
  put(bytes, points_offset_ + 20 * 5 + 4, nan);  // level 0 point 5, y
  EXPECT_THAT(load_error(with_checksum(bytes)), HasSubstr("level 0 (0.01 m) point 5: invalid position"));
  bytes = good_;
  put(bytes, points_offset_ + 20 * 250 + 12,
      std::numeric_limits<float>::infinity());  // level 1 point 50, intensity
  EXPECT_THAT(load_error(with_checksum(bytes)), HasSubstr("level 1 (0.02 m) point 50: invalid intensity"));
  bytes = good_;
  put(bytes, points_offset_ + 20 * 7 + 16, -1.0f);
  EXPECT_THAT(load_error(with_checksum(bytes)), HasSubstr("invalid saliency (negative)"));
  bytes = good_;
  put(bytes, 24 + 8, std::numeric_limits<double>::quiet_NaN());  // origin y
  EXPECT_THAT(load_error(with_checksum(bytes)), HasSubstr("origin"));
}

TEST_F(CorruptMapFile, ResolutionsMustBePositiveAndIncreasing) {
  std::string bytes = good_;
  put(bytes, 56 + 16, 0.01);  // level 1 resolution = level 0's
  EXPECT_THAT(load_error(with_checksum(bytes)), HasSubstr("increase strictly"));
  bytes = good_;
  put(bytes, 56, -0.01);
  EXPECT_THAT(load_error(with_checksum(bytes)), HasSubstr("not a positive number"));
}

TEST_F(CorruptMapFile, TwoPointsInOneVoxel) {
  std::string bytes = good_;
  // Level 0 point 1 := point 0 shifted inside the same 1 cm voxel.
  float x0 = 0.0f, y0 = 0.0f, z0 = 0.0f;
  std::memcpy(&x0, bytes.data() + points_offset_, 4);
  std::memcpy(&y0, bytes.data() + points_offset_ + 4, 4);
  std::memcpy(&z0, bytes.data() + points_offset_ + 8, 4);
  put(bytes, points_offset_ + 20, x0 + 0.001f);
  put(bytes, points_offset_ + 24, y0);
  put(bytes, points_offset_ + 28, z0);
  EXPECT_THAT(load_error(with_checksum(bytes)), HasSubstr("has two points in voxel"));
  // The check can be skipped.
  test::write_bytes(dir_ / "dup.mrvm", with_checksum(bytes));
  MapCheckOptions quick;
  quick.check_one_point_per_voxel = false;
  EXPECT_TRUE(load_voxel_map(dir_ / "dup.mrvm", quick).ok());
}

TEST_F(CorruptMapFile, AbsurdCountsAreRejectedBeforeAllocating) {
  std::string bytes = good_;
  put_u32(bytes, 16, 1'000'000'000);  // level count
  EXPECT_THAT(load_error(bytes), HasSubstr("level count 1000000000 is out of range"));
  bytes = good_;
  put_u32(bytes, 16, 0);
  EXPECT_THAT(load_error(bytes), HasSubstr("level count 0"));
  bytes = good_;
  put_u32(bytes, 20, 0xffffffffu);  // description length
  EXPECT_THAT(load_error(bytes), HasSubstr("description length"));
  bytes = good_;
  put_u64(bytes, 56 + 8, std::uint64_t{1} << 62);  // level 0 count
  EXPECT_THAT(load_error(bytes), HasSubstr("declares 4611686018427387904 points"));
  bytes = good_;
  put_u64(bytes, 56 + 8, 3'000'000'000ull);  // within the limit but far beyond the file
  EXPECT_THAT(load_error(bytes), HasSubstr("bytes missing"));
  bytes = good_;
  put_u64(bytes, 48, 10);  // raw point count below a level's count
  EXPECT_THAT(load_error(with_checksum(bytes)), HasSubstr("more than the raw cloud"));
  bytes = good_;
  put_u32(bytes, 12, 1);  // flags
  EXPECT_THAT(load_error(bytes), HasSubstr("unknown header flags"));
}

TEST_F(CorruptMapFile, RandomCorruptionIsAlwaysRejected) {
  std::uint64_t state = 777;
  auto next = [&state] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return state >> 33;
  };
  for (int trial = 0; trial < 300; ++trial) {
    std::string bytes = good_;
    const int flips = 1 + static_cast<int>(next() % 3);
    for (int f = 0; f < flips; ++f) bytes[next() % bytes.size()] ^= static_cast<char>(1 + next() % 255);
    if (trial % 3 == 0) bytes.resize(next() % bytes.size());
    auto map = parse_voxel_map(bytes, "fuzz.mrvm");
    ASSERT_FALSE(map.ok()) << "trial " << trial;
    EXPECT_THAT(std::string(map.status().message()), HasSubstr("fuzz.mrvm"));
  }
}

TEST_F(CorruptMapFile, TrailingBytes) {
  EXPECT_THAT(load_error(good_ + "xyz"), HasSubstr("3 unexpected bytes"));
}

TEST(MapFile, MissingFileAndInvalidMapsAreNotWritten) {
  mrvs::test::TempDir dir;
  auto missing = load_voxel_map(dir / "none.mrvm");
  ASSERT_FALSE(missing.ok());
  EXPECT_THAT(std::string(missing.status().message()), HasSubstr("none.mrvm"));

  VoxelMap bad = sample_map();
  bad.levels[1].points[3].position.z() = std::nanf("");
  const Status s = save_voxel_map(dir / "bad.mrvm", bad);
  ASSERT_FALSE(s.ok());
  EXPECT_THAT(std::string(s.message()), HasSubstr("bad.mrvm"));
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.mrvm"));

  VoxelMap unsorted = sample_map();
  std::swap(unsorted.levels[0], unsorted.levels[2]);
  EXPECT_FALSE(save_voxel_map(dir / "u.mrvm", unsorted).ok());
  VoxelMap empty;
  EXPECT_FALSE(save_voxel_map(dir / "e.mrvm", empty).ok());
}

TEST(MapFile, SaveReplacesAnExistingFileAtomically) {
  mrvs::test::TempDir dir;
  VoxelMap map = sample_map();
  ASSERT_TRUE(save_voxel_map(dir / "m.mrvm", map).ok());
  map.description = "second";
  ASSERT_TRUE(save_voxel_map(dir / "m.mrvm", map).ok());
  auto loaded = load_voxel_map(dir / "m.mrvm");
  ASSERT_TRUE(loaded.ok());
  EXPECT_EQ(loaded->description, "second");
  int files = 0;
  for ([[maybe_unused]] const auto& entry : std::filesystem::directory_iterator(dir.path())) ++files;
  EXPECT_EQ(files, 1);  // no temporary left behind
}

}  // namespace
}  // namespace mrvs::map
