// GNSS fixes (mav0/gnss0): the CSV writer and reader round trip exactly, bad rows and bad
// sensor.yaml files are errors naming file and line, and the EuRoC dataset reader adds the
// stream when the folder has it and opens sequences without it unchanged.
#include <cmath>
#include <fstream>
#include <string>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "euroc_fixture.h"
#include "mrvs/io/dataset.h"
#include "mrvs/io/gnss.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::io {
namespace {

using ::testing::HasSubstr;

constexpr TimestampNs kT0 = 1544590803000000000;

std::string message(const Status& s) { return std::string(s.message()); }

StatusOr<std::unique_ptr<DatasetReader>> open(const std::filesystem::path& path) {
  DatasetOptions options;
  options.path = path;
  return open_dataset("euroc", options);
}

std::vector<GnssFix> gnss_fixes(int n, TimestampNs t0 = kT0, DurationNs period = 1'000'000'000) {
  std::vector<GnssFix> out;
  for (int k = 0; k < n; ++k) {
    // Values with long expansions to check exact text round trips.
    out.push_back({t0 + TimestampNs{k} * period, Vec3d(123.0 / 7 * k, -0.1 * k - 1e-9, 2.0 / 3 + 1.7),
                   1.5 + k / 3.0, 3.0 + 1e-7 * k});
  }
  return out;
}

/// A gnss0/sensor.yaml as the simulator writes it (antenna 0.3 m behind, 0.25 m above).
std::string sensor_yaml(const std::string& extra = "") {
  return "%YAML:1.0\n"
         "# General sensor definitions.\n"
         "sensor_type: gnss\n"
         "comment: test receiver\n"
         "\n"
         "# Sensor extrinsics wrt. the body-frame.\n"
         "T_BS:\n"
         "  cols: 4\n"
         "  rows: 4\n"
         "  data: [1.0, 0.0, 0.0, -0.3,\n"
         "         0.0, 1.0, 0.0, 0.0,\n"
         "         0.0, 0.0, 1.0, 0.25,\n"
         "         0.0, 0.0, 0.0, 1.0]\n"
         "rate_hz: 1.0\n"
         "sigma_horizontal_m: 1.5\n"
         "sigma_vertical_m: 3.0\n" +
         extra;
}

std::string csv_text(const std::vector<GnssFix>& fixes) {
  std::string text = std::string(kGnssCsvHeader) + "\n";
  for (const GnssFix& f : fixes) {
    text += fmt::format("{},{},{},{},{},{}\n", f.t_ns, f.p_map.x(), f.p_map.y(), f.p_map.z(),
                        f.sigma_horizontal_m, f.sigma_vertical_m);
  }
  return text;
}

void overwrite(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

TEST(GnssCsv, WriterAndReaderRoundTripExactly) {
  const test::TempDir dir;
  const auto fixes = gnss_fixes(300);
  ASSERT_TRUE(write_euroc_gnss_csv(dir / "gnss0/data.csv", fixes).ok());
  std::ifstream in(dir / "gnss0/data.csv");
  std::string header;
  std::getline(in, header);
  EXPECT_EQ(header, "#timestamp [ns],p_x [m],p_y [m],p_z [m],sigma_horizontal [m],sigma_vertical [m]");
  Warnings warnings;
  auto back = read_euroc_gnss_csv(dir / "gnss0/data.csv", {}, &warnings);
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_TRUE(warnings.empty());
  ASSERT_EQ(back->size(), fixes.size());
  for (std::size_t i = 0; i < fixes.size(); ++i) {
    EXPECT_EQ((*back)[i].t_ns, fixes[i].t_ns);
    EXPECT_EQ((*back)[i].p_map, fixes[i].p_map) << i;
    EXPECT_EQ((*back)[i].sigma_horizontal_m, fixes[i].sigma_horizontal_m) << i;
    EXPECT_EQ((*back)[i].sigma_vertical_m, fixes[i].sigma_vertical_m) << i;
  }
}

TEST(GnssCsv, ReaderTakesCrlfBlanksAndDropsExactDuplicates) {
  const test::TempDir dir;
  const auto path = dir.write("data.csv", std::string(kGnssCsvHeader) +
                                              "\r\n1000, 1.5, -2, 3e2, 1.5, 3\r\n1000,1.5,-2,300,1.5,3\r\n"
                                              "2000, 1, 2, 3, 0.5, 0.25\r\n");
  Warnings warnings;
  auto fixes = read_euroc_gnss_csv(path, {}, &warnings);
  ASSERT_TRUE(fixes.ok()) << fixes.status();
  ASSERT_EQ(fixes->size(), 2u);
  EXPECT_EQ((*fixes)[0].p_map, Vec3d(1.5, -2.0, 300.0));
  EXPECT_EQ((*fixes)[1].sigma_vertical_m, 0.25);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_THAT(warnings[0], HasSubstr(path.string() + ":3: duplicate of line 2, dropped"));
}

TEST(GnssCsv, BadRowsNameFileLineAndField) {
  const test::TempDir dir;
  const std::string good = csv_text(gnss_fixes(5));
  const auto path = dir / "data.csv";
  // A non-numeric position (line 4 = fix 2).
  std::string text = good;
  const std::string p_y = fmt::format("{}", gnss_fixes(5)[2].p_map.y());
  text.replace(text.find("," + p_y + ","), p_y.size() + 2, ",-O.2,");
  overwrite(path, text);
  auto a = read_euroc_gnss_csv(path);
  ASSERT_FALSE(a.ok());
  EXPECT_EQ(message(a.status()),
            path.string() + ":4: field 3 ('p_y [m]'): '-O.2' is not a number; fix or delete this line");
  // A missing field (line 3).
  overwrite(path, std::string(kGnssCsvHeader) + "\n1,2,3,4,1.5,3\n2,2,3,4,1.5\n");
  auto b = read_euroc_gnss_csv(path);
  ASSERT_FALSE(b.ok());
  EXPECT_EQ(b.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(message(b.status()), HasSubstr(path.string() + ":3: expected 6 comma-separated fields"));
  EXPECT_THAT(message(b.status()), HasSubstr("found 5"));
  // A sigma that is not > 0.
  overwrite(path, std::string(kGnssCsvHeader) + "\n1,2,3,4,1.5,3\n2,2,3,4,0,3\n");
  auto c = read_euroc_gnss_csv(path);
  ASSERT_FALSE(c.ok());
  EXPECT_EQ(message(c.status()),
            path.string() +
                ":3: field 5 ('sigma_horizontal [m]'): 0 is not > 0 (a standard deviation "
                "in metres); fix or delete this line");
  // Out of time order.
  overwrite(path, std::string(kGnssCsvHeader) + "\n5,2,3,4,1.5,3\n4,2,3,4,1.5,3\n");
  auto d = read_euroc_gnss_csv(path);
  ASSERT_FALSE(d.ok());
  EXPECT_THAT(message(d.status()), HasSubstr(path.string() + ":3: timestamp 4 ns is not after"));
  ReadPolicy sort;
  sort.sort_out_of_order = true;
  auto sorted = read_euroc_gnss_csv(path, sort);
  ASSERT_TRUE(sorted.ok()) << sorted.status();
  EXPECT_EQ(sorted->front().t_ns, 4);
  // Only a header.
  overwrite(path, std::string(kGnssCsvHeader) + "\n");
  auto e = read_euroc_gnss_csv(path);
  ASSERT_FALSE(e.ok());
  EXPECT_THAT(message(e.status()), HasSubstr(path.string() + ": no data rows"));
  // A missing file.
  auto f = read_euroc_gnss_csv(dir / "nowhere.csv");
  ASSERT_FALSE(f.ok());
  EXPECT_EQ(f.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(message(f.status()), HasSubstr("nowhere.csv"));
}

TEST(GnssCsv, TruncatedFileIsDataLossNamingTheLastLine) {
  const test::TempDir dir;
  const std::string good = csv_text(gnss_fixes(5));
  const auto path = dir / "data.csv";
  // Cut inside the fourth row (file line 5), after its timestamp and first value.
  const std::string row4 = fmt::format("{},", gnss_fixes(5)[3].t_ns);
  overwrite(path, good.substr(0, good.find(row4) + row4.size() + 3));
  auto a = read_euroc_gnss_csv(path);
  ASSERT_FALSE(a.ok());
  EXPECT_EQ(a.status().code(), absl::StatusCode::kDataLoss);
  EXPECT_THAT(message(a.status()), HasSubstr(path.string() + ":5: expected 6 comma-separated fields"));
  EXPECT_THAT(message(a.status()), HasSubstr("does not end in a newline"));
  // Cut after the last field of the last row: read, with a warning naming the line.
  overwrite(path, good.substr(0, good.size() - 1));
  Warnings warnings;
  auto b = read_euroc_gnss_csv(path, {}, &warnings);
  ASSERT_TRUE(b.ok()) << b.status();
  EXPECT_EQ(b->size(), 5u);
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_THAT(warnings[0], HasSubstr(path.string() + ":6: the file does not end in a newline"));
}

TEST(GnssCsv, WriterRefusesUnorderedNonFiniteOrNonPositiveSigmas) {
  const test::TempDir dir;
  auto fixes = gnss_fixes(5);
  fixes[3].t_ns = fixes[2].t_ns;
  Status s = write_euroc_gnss_csv(dir / "data.csv", fixes);
  ASSERT_FALSE(s.ok());
  EXPECT_THAT(message(s), HasSubstr("entry 3"));
  fixes = gnss_fixes(5);
  fixes[1].p_map.z() = std::nan("");
  s = write_euroc_gnss_csv(dir / "data.csv", fixes);
  ASSERT_FALSE(s.ok());
  EXPECT_THAT(message(s), HasSubstr("non-finite"));
  fixes = gnss_fixes(5);
  fixes[4].sigma_vertical_m = 0.0;
  s = write_euroc_gnss_csv(dir / "data.csv", fixes);
  ASSERT_FALSE(s.ok());
  EXPECT_THAT(message(s), HasSubstr("entry 4"));
  EXPECT_THAT(message(s), HasSubstr("sigmas must be > 0"));
  EXPECT_FALSE(std::filesystem::exists(dir / "data.csv"));
}

TEST(GnssSensorYaml, ReadsTheLeverArmRateAndSigmas) {
  const test::TempDir dir;
  auto sensor = read_gnss_sensor_yaml(dir.write("sensor.yaml", sensor_yaml("correlation_time_s: 30.0\n")));
  ASSERT_TRUE(sensor.ok()) << sensor.status();
  EXPECT_EQ(sensor->comment, "test receiver");
  EXPECT_EQ(sensor->T_b_antenna.translation(), Vec3d(-0.3, 0.0, 0.25));
  EXPECT_TRUE(sensor->T_b_antenna.quaternion().isApprox(Quatd::Identity()));
  EXPECT_EQ(sensor->rate_hz, 1.0);
  EXPECT_EQ(sensor->sigma_horizontal_m, 1.5);
  EXPECT_EQ(sensor->sigma_vertical_m, 3.0);
  EXPECT_EQ(sensor->correlation_time_s, 30.0);
  // Only T_BS and rate_hz are required.
  auto minimal = read_gnss_sensor_yaml(
      dir.write("minimal.yaml",
                "T_BS:\n  cols: 4\n  rows: 4\n  data: [1, 0, 0, 1, 0, 1, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1]\n"
                "rate_hz: 10\n"));
  ASSERT_TRUE(minimal.ok()) << minimal.status();
  EXPECT_EQ(minimal->T_b_antenna.translation(), Vec3d(1.0, 2.0, 3.0));
  EXPECT_EQ(minimal->rate_hz, 10.0);
  EXPECT_EQ(minimal->sigma_horizontal_m, 0.0);
}

TEST(GnssSensorYaml, ErrorsNameFileLineAndKeyAllAtOnce) {
  const test::TempDir dir;
  std::string text = sensor_yaml();
  text.replace(text.find("sensor_type: gnss"), 17, "sensor_type: imu");
  text.replace(text.find("rate_hz: 1.0"), 12, "rate_hz: -1");
  text.replace(text.find("0.0, 0.0, 1.0, 0.25"), 19, "0.0, 0.0, 2.0, 0.25");  // not a rotation
  const auto path = dir.write("sensor.yaml", text);
  auto bad = read_gnss_sensor_yaml(path);
  ASSERT_FALSE(bad.ok());
  const std::string m = message(bad.status());
  EXPECT_THAT(m, HasSubstr(path.string() + ":3:14: key 'sensor_type': expected 'gnss'"));
  EXPECT_THAT(m, HasSubstr(path.string() + ":14:10: key 'rate_hz': expected a number > 0, got '-1'"));
  EXPECT_THAT(m, HasSubstr(path.string() + ":10:9: key 'T_BS': the rotation block is not a rotation matrix"));
  auto missing = read_gnss_sensor_yaml(dir.write("missing.yaml", "sensor_type: gnss\n"));
  ASSERT_FALSE(missing.ok());
  EXPECT_THAT(message(missing.status()), HasSubstr("key 'T_BS': missing"));
  EXPECT_THAT(message(missing.status()), HasSubstr("key 'rate_hz': missing"));
  auto syntax = read_gnss_sensor_yaml(dir.write("syntax.yaml", "rate_hz: [1\n"));
  ASSERT_FALSE(syntax.ok());
  EXPECT_THAT(message(syntax.status()), HasSubstr("syntax.yaml"));
  EXPECT_FALSE(read_gnss_sensor_yaml(dir / "nowhere.yaml").ok());
}

TEST(EurocDatasetGnss, RealEurocLayoutWithoutGnssOpensUnchanged) {
  test::TempDir dir;
  const auto d = open(test_fixture::write_euroc_sequence(dir, {}));
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_FALSE((*d)->has_gnss());
  EXPECT_TRUE((*d)->gnss().empty());
  EXPECT_FALSE((*d)->T_b_gnss().has_value());
  EXPECT_FALSE((*d)->summary().gnss.has_value());
  EXPECT_TRUE((*d)->warnings().empty());
  EXPECT_THAT((*d)->summary().describe(), HasSubstr("gnss: none"));
}

TEST(EurocDatasetGnss, ReadsTheGnssStreamAndItsLeverArm) {
  test::TempDir dir;
  const test_fixture::EurocSpec spec;
  const auto seq = test_fixture::write_euroc_sequence(dir, spec, "outdoor");
  // 10 Hz fixes on the IMU stamps of the 0.5 s fixture.
  const auto fixes = gnss_fixes(5, test_fixture::imu_t_ns(spec, 0), 100'000'000);
  ASSERT_TRUE(write_euroc_gnss_csv(seq / "mav0/gnss0/data.csv", fixes).ok());
  std::string yaml = sensor_yaml();
  yaml.replace(yaml.find("rate_hz: 1.0"), 12, "rate_hz: 10.0");
  dir.write("outdoor/mav0/gnss0/sensor.yaml", yaml);
  const auto d = open(seq);
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_TRUE((*d)->warnings().empty()) << (*d)->warnings().front();
  ASSERT_TRUE((*d)->has_gnss());
  ASSERT_EQ((*d)->gnss().size(), 5u);
  EXPECT_EQ((*d)->gnss()[2].p_map, fixes[2].p_map);
  ASSERT_TRUE((*d)->T_b_gnss().has_value());
  EXPECT_EQ((*d)->T_b_gnss()->translation(), Vec3d(-0.3, 0.0, 0.25));
  const DatasetSummary& s = (*d)->summary();
  ASSERT_TRUE(s.gnss.has_value());
  EXPECT_EQ(s.gnss->count, 5u);
  EXPECT_NEAR(s.gnss->rate_hz, 10.0, 1e-9);
  EXPECT_EQ(s.gnss->nominal_period_ns, 100'000'000);
  EXPECT_EQ(s.gnss->gap_count, 0u);
  EXPECT_THAT(s.describe(), HasSubstr("gnss0: 5 samples"));
  EXPECT_THAT(s.describe(), HasSubstr("gnss0 antenna in the body frame: [-0.300, 0.000, 0.250] m"));
}

TEST(EurocDatasetGnss, ProblemsNameTheFile) {
  test::TempDir dir;
  const test_fixture::EurocSpec spec;
  const auto seq = test_fixture::write_euroc_sequence(dir, spec);
  // A gnss0 folder without data.csv: a warning, no GNSS.
  std::filesystem::create_directories(seq / "mav0/gnss0");
  auto empty = open(seq);
  ASSERT_TRUE(empty.ok()) << empty.status();
  EXPECT_FALSE((*empty)->has_gnss());
  ASSERT_EQ((*empty)->warnings().size(), 1u);
  EXPECT_THAT((*empty)->warnings()[0], HasSubstr("gnss0 exists but has no data.csv"));
  // Fixes without sensor.yaml: the lever arm is unknown.
  ASSERT_TRUE(write_euroc_gnss_csv(seq / "mav0/gnss0/data.csv", gnss_fixes(3)).ok());
  auto no_yaml = open(seq);
  ASSERT_FALSE(no_yaml.ok());
  EXPECT_EQ(no_yaml.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(message(no_yaml.status()),
              HasSubstr("GNSS calibration " + (seq / "mav0/gnss0/sensor.yaml").string() + " does not exist"));
  // A bad row.
  dir.write("MH_test/mav0/gnss0/sensor.yaml", sensor_yaml());
  overwrite(seq / "mav0/gnss0/data.csv", std::string(kGnssCsvHeader) + "\n1,2,3\n");
  auto bad = open(seq);
  ASSERT_FALSE(bad.ok());
  EXPECT_THAT(message(bad.status()),
              HasSubstr((seq / "mav0/gnss0/data.csv").string() + ":2: expected 6 comma-separated fields"));
}

}  // namespace
}  // namespace mrvs::io
