// read_point_cloud: PLY / PCD encodings, field names, double precision, errors.
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "map_test_util.h"
#include "mrvs/map/point_cloud_io.h"
#include "mrvs/sim/map_io.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::map {
namespace {

using test::Field;
using ::testing::HasSubstr;

const std::vector<Field> kXyziFloat = {
    {"float", "x"}, {"float", "y"}, {"float", "z"}, {"float", "intensity"}};

std::vector<std::vector<double>> small_rows() {
  return {{0.5, -1.25, 2.0, 0.75}, {1.0, 2.0, 3.0, 10.0}, {-4.5, 0.125, 8.0, 0.0}, {7.0, 7.5, -7.0, 255.0}};
}

/// Expects `cloud` to hold exactly `rows` (x, y, z, intensity; float-representable values).
void expect_rows(const RawCloud& cloud, const std::vector<std::vector<double>>& rows) {
  ASSERT_EQ(cloud.size(), rows.size());
  ASSERT_EQ(cloud.intensities.size(), rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(cloud.positions[i].x(), rows[i][0]) << i;
    EXPECT_EQ(cloud.positions[i].y(), rows[i][1]) << i;
    EXPECT_EQ(cloud.positions[i].z(), rows[i][2]) << i;
    EXPECT_EQ(cloud.intensities[i], static_cast<float>(rows[i][3])) << i;
  }
}

class PlyFormats : public ::testing::TestWithParam<std::string> {};

TEST_P(PlyFormats, FloatXyzIntensityReadExactly) {
  mrvs::test::TempDir dir;
  test::write_ply(dir / "c.ply", GetParam(), kXyziFloat, small_rows());
  auto cloud = read_point_cloud(dir / "c.ply");
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  expect_rows(*cloud, small_rows());
  EXPECT_EQ(cloud->intensity_field, "intensity");
  EXPECT_EQ(cloud->source, (dir / "c.ply").string());
  EXPECT_TRUE(cloud->warnings.empty());
}

TEST_P(PlyFormats, DoubleUtmCoordinatesKeepMillimetres) {
  // A UTM-like cloud around (332000, 4140000, 20): float32 would round the northing to 0.25 m.
  std::vector<std::vector<double>> rows;
  for (int i = 0; i < 50; ++i) {
    rows.push_back(
        {332000.0 + 0.001 * i + 0.0004, 4140000.0 + 0.003 * i + 0.0007, 20.0 + 0.0011 * i, 0.01 * i});
  }
  mrvs::test::TempDir dir;
  const std::vector<Field> fields = {
      {"double", "x"}, {"double", "y"}, {"double", "z"}, {"float", "intensity"}};
  test::write_ply(dir / "utm.ply", GetParam(), fields, rows);
  auto cloud = read_point_cloud(dir / "utm.ply");
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  ASSERT_EQ(cloud->size(), rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) {
    // Binary: bit-exact doubles. ASCII: the shortest round-trip text, also exact.
    EXPECT_EQ(cloud->positions[i].x(), rows[i][0]);
    EXPECT_EQ(cloud->positions[i].y(), rows[i][1]);
    EXPECT_EQ(cloud->positions[i].z(), rows[i][2]);
  }
  // The millimetre offsets survive: neighbours differ by exactly what was written.
  EXPECT_NEAR(cloud->positions[1].y() - cloud->positions[0].y(), 0.003, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(Map, PlyFormats,
                         ::testing::Values("ascii", "binary_little_endian", "binary_big_endian"));

class IntensityNames : public ::testing::TestWithParam<std::string> {};

TEST_P(IntensityNames, CommonIntensityFieldNamesAreAccepted) {
  mrvs::test::TempDir dir;
  const std::vector<Field> fields = {{"float", "x"}, {"float", "y"}, {"float", "z"}, {"float", GetParam()}};
  test::write_ply(dir / "c.ply", "binary_little_endian", fields, small_rows());
  auto cloud = read_point_cloud(dir / "c.ply");
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  expect_rows(*cloud, small_rows());
  EXPECT_EQ(cloud->intensity_field, GetParam());
}

INSTANTIATE_TEST_SUITE_P(Map, IntensityNames,
                         ::testing::Values("intensity", "scalar_intensity", "scalar_Intensity", "reflectance",
                                           "i"));

TEST(PointCloudIo, IntegerIntensityAndExtraFields) {
  mrvs::test::TempDir dir;
  const std::vector<Field> fields = {{"float", "nx"},   {"double", "x"}, {"float", "ny"},
                                     {"double", "y"},   {"double", "z"}, {"ushort", "reflectance"},
                                     {"uchar", "flags"}};
  const std::vector<std::vector<double>> rows = {{0.1, 1.5, 0.2, 2.5, 3.5, 60000, 7},
                                                 {0.3, -1.0, 0.4, -2.0, -3.0, 12, 9}};
  test::write_ply(dir / "c.ply", "binary_little_endian", fields, rows);
  auto cloud = read_point_cloud(dir / "c.ply");
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  ASSERT_EQ(cloud->size(), 2u);
  EXPECT_EQ(cloud->positions[0], Vec3d(1.5, 2.5, 3.5));
  EXPECT_EQ(cloud->positions[1], Vec3d(-1.0, -2.0, -3.0));
  EXPECT_EQ(cloud->intensities[0], 60000.0f);
  EXPECT_EQ(cloud->intensities[1], 12.0f);
}

TEST(PointCloudIo, UcharIntensityIsConverted) {
  mrvs::test::TempDir dir;
  const std::vector<Field> fields = {{"float", "x"}, {"float", "y"}, {"float", "z"}, {"uchar", "intensity"}};
  test::write_ply(dir / "c.ply", "ascii", fields, {{1, 2, 3, 200}, {4, 5, 6, 17}});
  auto cloud = read_point_cloud(dir / "c.ply");
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  ASSERT_EQ(cloud->size(), 2u);
  EXPECT_EQ(cloud->intensities[0], 200.0f);
  EXPECT_EQ(cloud->intensities[1], 17.0f);
}

TEST(PointCloudIo, RgbFallsBackToGray) {
  mrvs::test::TempDir dir;
  const std::vector<Field> fields = {{"float", "x"},   {"float", "y"},     {"float", "z"},
                                     {"uchar", "red"}, {"uchar", "green"}, {"uchar", "blue"}};
  test::write_ply(dir / "c.ply", "binary_little_endian", fields,
                  {{1, 2, 3, 30, 60, 90}, {4, 5, 6, 255, 255, 255}});
  auto cloud = read_point_cloud(dir / "c.ply");
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  ASSERT_EQ(cloud->size(), 2u);
  EXPECT_FLOAT_EQ(cloud->intensities[0], 60.0f);
  EXPECT_FLOAT_EQ(cloud->intensities[1], 255.0f);
  EXPECT_THAT(cloud->intensity_field, HasSubstr("gray"));
}

TEST(PointCloudIo, FloatRgbFieldsFallBackToGray) {
  mrvs::test::TempDir dir;
  const std::vector<Field> fields = {{"float", "x"},   {"float", "y"},     {"float", "z"},
                                     {"float", "red"}, {"float", "green"}, {"float", "blue"}};
  test::write_ply(dir / "c.ply", "ascii", fields, {{1, 2, 3, 0.25, 0.5, 0.75}});
  auto cloud = read_point_cloud(dir / "c.ply");
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  EXPECT_FLOAT_EQ(cloud->intensities[0], 0.5f);
}

TEST(PointCloudIo, NoIntensityIsAnErrorNamingFileAndFields) {
  mrvs::test::TempDir dir;
  const std::vector<Field> fields = {{"float", "x"}, {"float", "y"}, {"float", "z"}, {"float", "nx"}};
  test::write_ply(dir / "plain.ply", "ascii", fields, {{1, 2, 3, 0}});
  auto cloud = read_point_cloud(dir / "plain.ply");
  ASSERT_FALSE(cloud.ok());
  const std::string msg(cloud.status().message());
  EXPECT_THAT(msg, HasSubstr("plain.ply"));
  EXPECT_THAT(msg, HasSubstr("no intensity"));
  EXPECT_THAT(msg, HasSubstr("x, y, z, normal_x"));  // PCL renames nx
  EXPECT_THAT(msg, HasSubstr("reflectance"));
}

TEST(PointCloudIo, MissingCoordinateIsAnError) {
  mrvs::test::TempDir dir;
  test::write_ply(dir / "c.ply", "ascii", {{"float", "x"}, {"float", "y"}, {"float", "intensity"}},
                  {{1, 2, 3}});
  auto cloud = read_point_cloud(dir / "c.ply");
  ASSERT_FALSE(cloud.ok());
  EXPECT_THAT(std::string(cloud.status().message()), HasSubstr("no 'z' field"));
}

TEST(PointCloudIo, NonFinitePointsAreDroppedAndCounted) {
  mrvs::test::TempDir dir;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<std::vector<double>> rows = {
      {1, 2, 3, 0.5}, {nan, 2, 3, 0.5}, {4, 5, 6, 0.25}, {1, inf, 3, 1}, {1, 2, 3, nan}};
  for (const char* format : {"binary_little_endian", "ascii"}) {
    test::write_ply(dir / "c.ply", format, kXyziFloat, rows);
    auto cloud = read_point_cloud(dir / "c.ply");
    ASSERT_TRUE(cloud.ok()) << format << ": " << cloud.status();
    ASSERT_EQ(cloud->size(), 2u) << format;
    EXPECT_EQ(cloud->positions[1], Vec3d(4, 5, 6));
    ASSERT_EQ(cloud->warnings.size(), 1u) << format;
    EXPECT_THAT(cloud->warnings[0], HasSubstr("dropped 3 of 5 points"));
  }
  test::write_ply(dir / "c.ply", "binary_little_endian", kXyziFloat, {{nan, 0, 0, 1}});
  auto none = read_point_cloud(dir / "c.ply");
  ASSERT_FALSE(none.ok());
  EXPECT_THAT(std::string(none.status().message()), HasSubstr("no finite point"));
}

TEST(PointCloudIo, PlyWithAFaceElementAfterTheVertices) {
  mrvs::test::TempDir dir;
  test::write_ply(dir / "m.ply", "ascii", kXyziFloat, small_rows(),
                  "element face 1\nproperty list uchar int vertex_indices\n");
  // Append the face row.
  test::write_bytes(dir / "m.ply", test::read_bytes(dir / "m.ply") + "3 0 1 2\n");
  auto cloud = read_point_cloud(dir / "m.ply");
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  expect_rows(*cloud, small_rows());
}

TEST(PointCloudIo, SimulatorBinaryPly) {
  mrvs::test::TempDir dir;
  std::vector<sim::MapPoint> points;
  for (int i = 0; i < 1000; ++i) {
    sim::MapPoint p;
    p.position = Eigen::Vector3f(0.013f * i - 3.0f, 0.5f * std::sin(0.1f * i), 1.0f + 0.001f * i);
    p.intensity = 0.001f * static_cast<float>(i % 997);
    points.push_back(p);
  }
  ASSERT_TRUE(sim::write_ply(dir / "data.ply", points, "synthetic survey scan; test").ok());
  auto cloud = read_point_cloud(dir / "data.ply");
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  ASSERT_EQ(cloud->size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    EXPECT_EQ(cloud->positions[i], points[i].position.cast<double>());
    EXPECT_EQ(cloud->intensities[i], points[i].intensity);
  }
}

class PcdEncodings : public ::testing::TestWithParam<std::string> {};

TEST_P(PcdEncodings, PointXyziReadExactly) {
  mrvs::test::TempDir dir;
  const std::vector<Field> fields = {{"F4", "x"}, {"F4", "y"}, {"F4", "z"}, {"F4", "intensity"}};
  test::write_pcd(dir / "c.pcd", GetParam(), fields, small_rows());
  auto cloud = read_point_cloud(dir / "c.pcd");
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  expect_rows(*cloud, small_rows());
}

TEST_P(PcdEncodings, DoubleXyzAndIntegerReflectance) {
  mrvs::test::TempDir dir;
  const std::vector<Field> fields = {
      {"F8", "x"}, {"F8", "y"}, {"F8", "z"}, {"U2", "reflectance"}, {"F4", "ring"}};
  const std::vector<std::vector<double>> rows = {{332000.0012, 4140000.0047, 20.0003, 1234, 5},
                                                 {332100.5, 4140200.25, 21.125, 7, 6}};
  test::write_pcd(dir / "c.pcd", GetParam(), fields, rows);
  auto cloud = read_point_cloud(dir / "c.pcd");
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  ASSERT_EQ(cloud->size(), 2u);
  EXPECT_EQ(cloud->positions[0], Vec3d(332000.0012, 4140000.0047, 20.0003));
  EXPECT_EQ(cloud->positions[1], Vec3d(332100.5, 4140200.25, 21.125));
  EXPECT_EQ(cloud->intensities[0], 1234.0f);
  EXPECT_EQ(cloud->intensity_field, "reflectance");
}

INSTANTIATE_TEST_SUITE_P(Map, PcdEncodings, ::testing::Values("ascii", "binary", "binary_compressed"));

TEST(PointCloudIo, PcdPackedRgbFallsBackToGray) {
  mrvs::test::TempDir dir;
  const std::vector<Field> fields = {{"F4", "x"}, {"F4", "y"}, {"F4", "z"}, {"U4", "rgb"}};
  const double rgb = static_cast<double>((30u << 16) | (60u << 8) | 90u);
  test::write_pcd(dir / "c.pcd", "binary", fields, {{1, 2, 3, rgb}});
  auto cloud = read_point_cloud(dir / "c.pcd");
  ASSERT_TRUE(cloud.ok()) << cloud.status();
  EXPECT_FLOAT_EQ(cloud->intensities[0], 60.0f);
}

// ------------------------------------------------------------------ errors

std::string error_of(const std::filesystem::path& path) {
  auto cloud = read_point_cloud(path);
  EXPECT_FALSE(cloud.ok()) << path;
  return cloud.ok() ? "" : std::string(cloud.status().message());
}

TEST(PointCloudIoErrors, MissingFileAndUnknownExtension) {
  mrvs::test::TempDir dir;
  EXPECT_THAT(error_of(dir / "nothing.ply"), HasSubstr("nothing.ply' does not exist"));
  dir.write("cloud.xyz", "1 2 3\n");
  const std::string msg = error_of(dir / "cloud.xyz");
  EXPECT_THAT(msg, HasSubstr("cloud.xyz"));
  EXPECT_THAT(msg, HasSubstr("unknown extension '.xyz'"));
  // Upper-case extensions are fine.
  test::write_ply(dir / "UP.PLY", "ascii", kXyziFloat, small_rows());
  EXPECT_TRUE(read_point_cloud(dir / "UP.PLY").ok());
}

TEST(PointCloudIoErrors, NotAPly) {
  mrvs::test::TempDir dir;
  dir.write("junk.ply", "this is not a ply file\nat all\n");
  EXPECT_THAT(error_of(dir / "junk.ply"), HasSubstr("junk.ply"));
  dir.write("empty.ply", "");
  EXPECT_THAT(error_of(dir / "empty.ply"), HasSubstr("empty.ply"));
  dir.write("bad.ply",
            "ply\nformat binary_middle_endian 1.0\nelement vertex 1\nproperty float x\nend_header\n");
  EXPECT_THAT(error_of(dir / "bad.ply"), HasSubstr("unsupported PLY format"));
}

TEST(PointCloudIoErrors, TruncatedBinaryPlyAtSeveralLengths) {
  mrvs::test::TempDir dir;
  std::vector<std::vector<double>> rows(100, {1.0, 2.0, 3.0, 0.5});
  test::write_ply(dir / "full.ply", "binary_little_endian", kXyziFloat, rows);
  const std::string bytes = test::read_bytes(dir / "full.ply");
  const std::size_t header = bytes.size() - 100 * 16;
  for (const std::size_t cut :
       {std::size_t{10}, header - 3, header, header + 1, header + 800, bytes.size() - 1}) {
    test::write_bytes(dir / "cut.ply", bytes.substr(0, cut));
    const std::string msg = error_of(dir / "cut.ply");
    EXPECT_THAT(msg, HasSubstr("cut.ply")) << cut;
    EXPECT_THAT(msg, HasSubstr("truncated")) << cut;
    if (cut >= header) {
      EXPECT_THAT(msg, HasSubstr(fmt::format("({} bytes missing)", bytes.size() - cut))) << cut;
    }
  }
}

TEST(PointCloudIoErrors, TruncatedAsciiPly) {
  mrvs::test::TempDir dir;
  test::write_ply(dir / "full.ply", "ascii", kXyziFloat, small_rows());
  const std::string bytes = test::read_bytes(dir / "full.ply");
  test::write_bytes(dir / "cut.ply", bytes.substr(0, bytes.size() - 12));
  const std::string msg = error_of(dir / "cut.ply");
  EXPECT_THAT(msg, HasSubstr("cut.ply"));
  EXPECT_THAT(msg, HasSubstr("truncated"));
}

TEST(PointCloudIoErrors, ZeroPoints) {
  mrvs::test::TempDir dir;
  test::write_ply(dir / "zero.ply", "binary_little_endian", kXyziFloat, {});
  EXPECT_THAT(error_of(dir / "zero.ply"), HasSubstr("zero points"));
  test::write_pcd(dir / "zero.pcd", "binary", {{"F4", "x"}, {"F4", "y"}, {"F4", "z"}, {"F4", "intensity"}},
                  {});
  EXPECT_THAT(error_of(dir / "zero.pcd"), HasSubstr("zero points"));
}

TEST(PointCloudIoErrors, AbsurdVertexCountDoesNotAllocate) {
  mrvs::test::TempDir dir;
  dir.write("huge.ply",
            "ply\nformat binary_little_endian 1.0\nelement vertex 999999999999\nproperty float x\nproperty "
            "float y\n"
            "property float z\nproperty float intensity\nend_header\n0123456789abcdef");
  EXPECT_THAT(error_of(dir / "huge.ply"), HasSubstr("999999999999"));
  dir.write(
      "huge.pcd",
      "VERSION 0.7\nFIELDS x y z intensity\nSIZE 4 4 4 4\nTYPE F F F F\nCOUNT 1 1 1 1\nWIDTH 999999999999\n"
      "HEIGHT 1\nPOINTS 999999999999\nDATA binary\n0123456789abcdef");
  EXPECT_THAT(error_of(dir / "huge.pcd"), HasSubstr("999999999999"));
}

TEST(PointCloudIoErrors, TruncatedPcd) {
  mrvs::test::TempDir dir;
  const std::vector<Field> fields = {{"F4", "x"}, {"F4", "y"}, {"F4", "z"}, {"F4", "intensity"}};
  std::vector<std::vector<double>> rows(50, {1.0, 2.0, 3.0, 0.5});
  for (const char* data : {"ascii", "binary", "binary_compressed"}) {
    test::write_pcd(dir / "full.pcd", data, fields, rows);
    const std::string bytes = test::read_bytes(dir / "full.pcd");
    // ASCII: a missing final newline is harmless, so cut at least a whole line.
    for (const std::size_t missing :
         {std::size_t{std::string(data) == "ascii" ? 11u : 1u}, std::size_t{17}, std::size_t{300}}) {
      test::write_bytes(dir / "cut.pcd", bytes.substr(0, bytes.size() - missing));
      const std::string msg = error_of(dir / "cut.pcd");
      EXPECT_THAT(msg, HasSubstr("cut.pcd")) << data << " " << missing;
      EXPECT_THAT(msg, HasSubstr("truncated")) << data << " " << missing;
    }
  }
}

}  // namespace
}  // namespace mrvs::map

namespace mrvs::map {
namespace {

TEST(PointCloudIoErrors, RandomCorruptionNeverCrashes) {
  mrvs::test::TempDir dir;
  std::vector<std::vector<double>> rows;
  for (int i = 0; i < 40; ++i) rows.push_back({0.1 * i, -0.2 * i, 0.3, 0.01 * i});
  const std::vector<Field> ply_fields = {
      {"float", "x"}, {"double", "y"}, {"float", "z"}, {"uchar", "intensity"}};
  const std::vector<Field> pcd_fields = {{"F4", "x"}, {"F4", "y"}, {"F4", "z"}, {"F4", "intensity"}};
  std::vector<std::pair<std::string, std::string>> originals;  // extension, bytes
  for (const char* format : {"ascii", "binary_little_endian", "binary_big_endian"}) {
    test::write_ply(dir / "o.ply", format, ply_fields, rows);
    originals.emplace_back(".ply", test::read_bytes(dir / "o.ply"));
  }
  for (const char* data : {"ascii", "binary", "binary_compressed"}) {
    test::write_pcd(dir / "o.pcd", data, pcd_fields, rows);
    originals.emplace_back(".pcd", test::read_bytes(dir / "o.pcd"));
  }
  const char* seed = std::getenv("MRVS_MAP_FUZZ_SEED");  // another seed for a longer run by hand
  std::uint64_t state = seed != nullptr ? std::strtoull(seed, nullptr, 10) : 12345;
  auto next = [&state] {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return state >> 33;
  };
  // MRVS_MAP_FUZZ_TRIALS=5000 for a longer run by hand.
  const char* env = std::getenv("MRVS_MAP_FUZZ_TRIALS");
  const int trials = env != nullptr ? std::atoi(env) : 150;
  int loaded = 0;
  for (const auto& [ext, bytes] : originals) {
    for (int trial = 0; trial < trials; ++trial) {
      std::string corrupt = bytes;
      const int flips = 1 + static_cast<int>(next() % 4);
      for (int f = 0; f < flips; ++f) {
        corrupt[next() % corrupt.size()] = static_cast<char>(next() & 0xff);
      }
      if (next() % 4 == 0) corrupt.resize(next() % corrupt.size());
      test::write_bytes(dir / ("c" + ext), corrupt);
      auto cloud = read_point_cloud(dir / ("c" + ext));  // must return, ok or not
      if (cloud.ok()) {
        ++loaded;
        EXPECT_EQ(cloud->positions.size(), cloud->intensities.size());
        for (const Vec3d& p : cloud->positions) EXPECT_TRUE(p.allFinite());
      } else {
        EXPECT_THAT(std::string(cloud.status().message()), HasSubstr("c" + ext));
      }
    }
  }
  EXPECT_GT(loaded, 0);  // flips in the data part leave valid files
}

}  // namespace
}  // namespace mrvs::map
