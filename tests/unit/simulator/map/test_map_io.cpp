// PLY and T_map_world.yaml files of the prior map (simulator.md sections 1.7, 1.8).
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include "map_test_support.h"
#include "mrvs/geometry/so3.h"
#include "mrvs/sim/map_io.h"
#include "mrvs/sim/rng.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::sim {
namespace {

using test::read_bytes;

namespace fs = std::filesystem;

/// Points with awkward values (tiny, large, negative, many digits) from a fixed stream.
std::vector<MapPoint> example_points(std::size_t n) {
  const CounterRng rng(5, Stream::kMapNoise);
  std::vector<MapPoint> points(n);
  for (std::size_t i = 0; i < n; ++i) {
    points[i].position = Eigen::Vector3f(static_cast<float>(rng.uniform(-300.0, 300.0, i, 0)),
                                         static_cast<float>(rng.uniform(-1e-3, 1e-3, i, 1)),
                                         static_cast<float>(rng.normal(i, 2) * 3.0));
    points[i].intensity = static_cast<float>(rng.uniform(i, 3));
    points[i].face = static_cast<std::int32_t>(i % 7);
  }
  points[0].position = Eigen::Vector3f(1e-30f, -0.0f, 1e30f);
  points[0].intensity = 1.0f;
  return points;
}

void write_bytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

const char* const kBinaryHeader =
    "ply\n"
    "format binary_little_endian 1.0\n"
    "comment synthetic survey scan; generator 0.1.0; scene vicon_room; seed 7; frame world(R)\n"
    "element vertex 1000\n"
    "property float x\n"
    "property float y\n"
    "property float z\n"
    "property float intensity\n"
    "end_header\n";

const char* const kComment =
    "synthetic survey scan; generator 0.1.0; scene vicon_room; seed 7; frame world(R)";

TEST(MapPlyTest, BinaryHasTheSection17HeaderAnd16BytesPerPointAndRoundTripsExactly) {
  const mrvs::test::TempDir dir;
  const std::vector<MapPoint> points = example_points(1000);
  ASSERT_TRUE(write_ply(dir / "data.ply", points, kComment).ok());
  EXPECT_FALSE(fs::exists(dir / "data.ply.tmp"));
  const std::string bytes = read_bytes(dir / "data.ply");
  const std::string header = kBinaryHeader;
  ASSERT_EQ(bytes.substr(0, header.size()), header);
  EXPECT_EQ(bytes.size(), header.size() + 16 * points.size());
  // Little-endian float32 of the first point's x at the start of the data.
  float x = 0.0f;
  std::memcpy(&x, bytes.data() + header.size(), 4);  // this machine is little-endian
  EXPECT_EQ(x, points[0].position.x());

  auto back = read_ply_xyzi(dir / "data.ply");
  ASSERT_TRUE(back.ok()) << back.status();
  ASSERT_EQ(back->size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    ASSERT_EQ((*back)[i].position, points[i].position) << i;
    ASSERT_EQ((*back)[i].intensity, points[i].intensity) << i;
    ASSERT_EQ((*back)[i].face, -1);
  }
}

TEST(MapPlyTest, AsciiRoundTripsExactlyWithShortestDecimals) {
  const mrvs::test::TempDir dir;
  const std::vector<MapPoint> points = example_points(1000);
  ASSERT_TRUE(write_ply(dir / "data.ply", points, "line one\nline two", PlyFormat::kAscii).ok());
  const std::string bytes = read_bytes(dir / "data.ply");
  EXPECT_EQ(
      bytes.rfind("ply\nformat ascii 1.0\ncomment line one\ncomment line two\nelement vertex 1000\n", 0), 0u)
      << bytes.substr(0, 200);
  auto back = read_ply_xyzi(dir / "data.ply");
  ASSERT_TRUE(back.ok()) << back.status();
  ASSERT_EQ(back->size(), points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    // The shortest decimal form reads back to the same float (within print precision = exact).
    ASSERT_EQ((*back)[i].position, points[i].position) << i;
    ASSERT_EQ((*back)[i].intensity, points[i].intensity) << i;
  }
  EXPECT_GT(bytes.size(), 2 * 16 * points.size());  // ASCII is about 2.3x binary
}

TEST(MapPlyTest, EmptyMapAndForeignPropertyOrderAreRead) {
  const mrvs::test::TempDir dir;
  ASSERT_TRUE(write_ply(dir / "empty.ply", {}, "").ok());
  auto empty = read_ply_xyzi(dir / "empty.ply");
  ASSERT_TRUE(empty.ok()) << empty.status();
  EXPECT_TRUE(empty->empty());
  // Another writer's order, an extra float property and CRLF line ends.
  const fs::path other =
      dir.write("other.ply",
                "ply\r\nformat ascii 1.0\r\nelement vertex 2\r\nproperty float intensity\r\n"
                "property float z\r\nproperty float nx\r\nproperty float y\r\n"
                "property float x\r\nend_header\r\n0.5 3 9 2 1\r\n0.25 -3 9 -2 -1\r\n");
  auto points = read_ply_xyzi(other);
  ASSERT_TRUE(points.ok()) << points.status();
  ASSERT_EQ(points->size(), 2u);
  EXPECT_EQ((*points)[1].position, Eigen::Vector3f(-1.0f, -2.0f, -3.0f));
  EXPECT_EQ((*points)[1].intensity, 0.25f);
}

/// Expects reading `path` to fail with a message that names the file and contains `what`.
void expect_read_error(const fs::path& path, const std::string& what) {
  auto r = read_ply_xyzi(path);
  ASSERT_FALSE(r.ok()) << path;
  const std::string message(r.status().message());
  EXPECT_NE(message.find(path.string()), std::string::npos) << message;
  EXPECT_NE(message.find(what), std::string::npos) << message;
}

TEST(MapPlyTest, TruncatedOrOversizedDataIsAnErrorNamingTheFile) {
  const mrvs::test::TempDir dir;
  ASSERT_TRUE(write_ply(dir / "full.ply", example_points(100), kComment).ok());
  const std::string bytes = read_bytes(dir / "full.ply");
  write_bytes(dir / "cut.ply", bytes.substr(0, bytes.size() - 5));
  expect_read_error(dir / "cut.ply", "truncated");
  write_bytes(dir / "long.ply", bytes + "xyz");
  expect_read_error(dir / "long.ply", "unexpected");
  write_bytes(dir / "header_only.ply", bytes.substr(0, 60));
  expect_read_error(dir / "header_only.ply", "end_header");

  ASSERT_TRUE(write_ply(dir / "full.txt.ply", example_points(100), kComment, PlyFormat::kAscii).ok());
  const std::string text = read_bytes(dir / "full.txt.ply");
  write_bytes(dir / "cut.txt.ply", text.substr(0, text.size() - 40));
  expect_read_error(dir / "cut.txt.ply", "truncated");
  std::string bad = text;
  bad.replace(bad.find("end_header\n") + 11, 1, "q");
  write_bytes(dir / "bad.txt.ply", bad);
  expect_read_error(dir / "bad.txt.ply", "not a number");
  expect_read_error(dir / "missing.ply", "cannot open");
}

TEST(MapPlyTest, WrongHeadersAreErrorsNamingTheFile) {
  const mrvs::test::TempDir dir;
  const std::string body = "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n";
  const std::string good_tail = "property float intensity\nend_header\n1 2 3 0.5\n";
  expect_read_error(dir.write("a.ply", "plx\nformat ascii 1.0\n" + body + good_tail), "'ply'");
  expect_read_error(dir.write("b.ply", "ply\nformat binary_big_endian 1.0\n" + body + good_tail),
                    "binary_big_endian");
  expect_read_error(dir.write("c.ply", "ply\nformat ascii 1.0\n" + body + "end_header\n1 2 3\n"),
                    "intensity");
  expect_read_error(dir.write("d.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty double x\n"),
                    "float");
  expect_read_error(dir.write("e.ply", "ply\nformat ascii 1.0\nelement face 1\n"), "element vertex");
  expect_read_error(dir.write("f.ply", "ply\n" + body + good_tail), "format");
  expect_read_error(dir.write("g.ply", "ply\nformat ascii 1.0\nelement vertex -3\n"), "element vertex");
  expect_read_error(dir.write("h.ply", "ply\nformat ascii 1.0\n" + body + "property list uchar int i\n"),
                    "float");
}

TEST(MapPlyTest, WriteErrorsNameThePath) {
  const mrvs::test::TempDir dir;
  const fs::path path = dir / "no_such_folder" / "data.ply";
  const Status s = write_ply(path, example_points(3), kComment);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(std::string(s.message()).find(path.string()), std::string::npos) << s;
  EXPECT_FALSE(write_transform_yaml(path, SE3d()).ok());
}

TEST(MapTransformYamlTest, WritesTheMatrixExactly) {
  const mrvs::test::TempDir dir;
  const SE3d T(so3::exp_quat<double>(Vec3d(0.003, -0.007, 0.002)), Vec3d(0.05, -0.02, 0.01));
  ASSERT_TRUE(write_transform_yaml(dir / "T_map_world.yaml", T).ok());
  const YAML::Node node = YAML::LoadFile((dir / "T_map_world.yaml").string());
  ASSERT_EQ(node["T_map_world"]["rows"].as<int>(), 4);
  ASSERT_EQ(node["T_map_world"]["cols"].as<int>(), 4);
  const auto data = node["T_map_world"]["data"].as<std::vector<double>>();
  ASSERT_EQ(data.size(), 16u);
  const Mat4d m = T.matrix();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) EXPECT_EQ(data[static_cast<std::size_t>(4 * r + c)], m(r, c));
  }
  EXPECT_NEAR(node["rotation_angle_deg"].as<double>(), Vec3d(0.003, -0.007, 0.002).norm() * 180.0 / M_PI,
              1e-12);
  EXPECT_NEAR(node["translation_norm_m"].as<double>(), T.translation().norm(), 1e-15);
}

}  // namespace
}  // namespace mrvs::sim
