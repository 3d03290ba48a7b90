// The EuRoC writers produce files the project's reader takes back unchanged.
#include <fstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "mrvs/io/dataset.h"
#include "mrvs/io/trajectory_io.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::io {
namespace {

using ::testing::HasSubstr;

constexpr TimestampNs kT0 = 1403715273262142976;

std::vector<ImuSample> imu_samples(int n) {
  std::vector<ImuSample> out;
  for (int k = 0; k < n; ++k) {
    // Values with long expansions to check exact text round trips.
    out.push_back({kT0 + TimestampNs{k} * 5'000'000, Vec3d(0.1 / 3 * k, -1e-7 * k, 2.0 / 7),
                   Vec3d(9.80665 + 1e-9 * k, -0.3 * k, 1.0 / 9)});
  }
  return out;
}

TEST(EurocWriters, ImuCsvRoundTripsExactly) {
  const test::TempDir dir;
  const auto samples = imu_samples(500);
  ASSERT_TRUE(write_euroc_imu_csv(dir / "imu0/data.csv", samples).ok());
  Warnings warnings;
  auto back = read_euroc_imu_csv(dir / "imu0/data.csv", {}, &warnings);
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_TRUE(warnings.empty());
  ASSERT_EQ(back->size(), samples.size());
  for (std::size_t i = 0; i < samples.size(); ++i) {
    EXPECT_EQ((*back)[i].t_ns, samples[i].t_ns);
    EXPECT_EQ((*back)[i].gyro_radps, samples[i].gyro_radps) << i;
    EXPECT_EQ((*back)[i].accel_mps2, samples[i].accel_mps2) << i;
  }
}

TEST(EurocWriters, ImageCsvRoundTripsWithFileNames) {
  const test::TempDir dir;
  std::vector<ImageRecord> records;
  for (int k = 0; k < 20; ++k) {
    const TimestampNs t = kT0 + TimestampNs{k} * 50'000'000;
    records.push_back({t, dir / "cam0/data" / (std::to_string(t) + ".png")});
    dir.write("cam0/data/" + std::to_string(t) + ".png", "");
  }
  ASSERT_TRUE(write_euroc_image_csv(dir / "cam0/data.csv", records).ok());
  auto back = read_euroc_image_csv(dir / "cam0/data.csv", dir / "cam0/data", /*check_files=*/true);
  ASSERT_TRUE(back.ok()) << back.status();
  ASSERT_EQ(back->size(), records.size());
  for (std::size_t i = 0; i < records.size(); ++i) {
    EXPECT_EQ((*back)[i].t_ns, records[i].t_ns);
    EXPECT_EQ((*back)[i].path.filename(), records[i].path.filename());
  }
}

TEST(EurocWriters, GroundTruthUsesTheRealHeader) {
  const test::TempDir dir;
  std::vector<GroundTruthState> states(3);
  for (int k = 0; k < 3; ++k) states[k].t_ns = kT0 + k;
  ASSERT_TRUE(write_euroc_groundtruth(dir / "gt.csv", states).ok());
  std::ifstream in(dir / "gt.csv");
  std::string header;
  std::getline(in, header);
  EXPECT_THAT(header,
              ::testing::StartsWith("#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], "));
  auto back = read_euroc_groundtruth(dir / "gt.csv");
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->size(), 3u);
}

TEST(EurocWriters, RefuseUnorderedOrNonFiniteData) {
  const test::TempDir dir;
  auto samples = imu_samples(5);
  samples[3].t_ns = samples[2].t_ns;
  Status s = write_euroc_imu_csv(dir / "imu.csv", samples);
  ASSERT_FALSE(s.ok());
  EXPECT_THAT(std::string(s.message()), HasSubstr("entry 3"));
  samples = imu_samples(5);
  samples[1].gyro_radps.x() = std::nan("");
  s = write_euroc_imu_csv(dir / "imu.csv", samples);
  ASSERT_FALSE(s.ok());
  EXPECT_THAT(std::string(s.message()), HasSubstr("non-finite"));
  EXPECT_FALSE(std::filesystem::exists(dir / "imu.csv"));
}

}  // namespace
}  // namespace mrvs::io
