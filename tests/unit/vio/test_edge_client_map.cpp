// edge_client against cloud_server over Fast DDS on loopback, as two processes (CTest runs in
// a private network namespace when root): the paper's two-stage update on a short realistic
// clip beats plain VIO, the link figures stay within the paper's budget, and a cloud killed
// mid-run leaves a client that finishes as plain VIO and uses the map again after a restart.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>

#include "mrvs/eval/trajectory_eval.h"
#include "mrvs/io/trajectory_io.h"
#include "mrvs/test/generated_sequence.h"
#include "mrvs/test/run_tool.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::edge {
namespace {

namespace fs = std::filesystem;
using mrvs::test::quoted;
using mrvs::test::value_of;

constexpr int kDomain = 93;  // neither the demo's (42) nor the link tests' (91)

/// V1_01, 24 s from its still start, realistic preset; its map built once.
struct MappedClip {
  fs::path sequence;
  fs::path map;
};

const MappedClip& clip() {
  static const MappedClip c = [] {
    MappedClip out;
    // The survey at the simulator's own density (the unit-test sequences thin it out).
    sim::GeneratorRequest request =
        mrvs::test::indoor_sequence_request("V1_01_easy.txt", 0.0, 24.0, "realistic");
    sim::SimulatorOptions dense = sim::default_options(sim::SceneProfile::kIndoor);
    EXPECT_TRUE(sim::apply_preset("realistic", sim::SceneProfile::kIndoor, dense).ok());
    request.options.map = dense.map;
    auto p = mrvs::test::generated_sequence("vio_v101_24s_realistic_mapped", request);
    EXPECT_TRUE(p.ok()) << p.status();
    if (!p.ok()) return out;
    out.sequence = *p;
    out.map = *p / "map.mrvm";
    if (!fs::exists(out.map)) {
      const fs::path partial = *p / "map.mrvm.partial";
      const auto r = mrvs::test::run_tool(
          MRVS_MAP_BUILDER, "--input " + quoted(*p / "mav0/pointcloud0/data.ply") + " --config " +
                                quoted(fs::path(MRVS_CONFIG_DIR) / "map_indoor.yaml") + " --out " +
                                quoted(partial) + " --log-level warn");
      EXPECT_EQ(r.exit_code, 0) << r.output;
      if (r.exit_code == 0) fs::rename(partial, out.map);
    }
    return out;
  }();
  return c;
}

fs::path profile() { return fs::path(MRVS_SOURCE_DIR) / "config/dds/loopback.xml"; }

std::unique_ptr<mrvs::test::BackgroundTool> start_server(const fs::path& log) {
  return std::make_unique<mrvs::test::BackgroundTool>(
      MRVS_CLOUD_SERVER,
      "--map " + quoted(clip().map) + " --dds-profile " + quoted(profile()) + " --dds-domain " +
          std::to_string(kDomain) + " --config " + quoted(fs::path(MRVS_CONFIG_DIR) / "map_indoor.yaml") +
          " --stats-period 0 --log-level warn",
      log);
}

/// edge_client's arguments on `sequence` (default: the clip) with the test's DDS profile and domain.
std::string client_args(const fs::path& out, const std::string& extra, const fs::path& sequence = {}) {
  return "--dataset " + quoted(sequence.empty() ? clip().sequence : sequence) + " --config " +
         quoted(fs::path(MRVS_CONFIG_DIR) / "euroc.yaml") + " --output " + quoted(out) +
         " --threads 1 --dds-profile " + quoted(profile()) + " --dds-domain " + std::to_string(kDomain) +
         " " + extra;
}

mrvs::test::RunResult edge_client(const fs::path& out, const std::string& extra,
                                  const fs::path& sequence = {}) {
  return mrvs::test::run_tool(MRVS_EDGE_CLIENT, client_args(out, extra, sequence));
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// K of the client's newest progress line "frame K/N (...)"; 0 before the first.
int progress_frame(const std::string& log) {
  static const std::regex line(R"(\] frame (\d+)/\d+ \()");
  int k = 0;
  for (auto it = std::sregex_iterator(log.begin(), log.end(), line); it != std::sregex_iterator(); ++it) {
    k = std::stoi((*it)[1].str());
  }
  return k;
}

/// Polls `done` on the client's log until it holds; false if the client exited first or
/// `timeout_s` passed.
template <typename Done>
bool wait_for_log(mrvs::test::BackgroundTool& client, const fs::path& log, Done done,
                  double timeout_s = 300.0) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (std::chrono::steady_clock::now() < until) {
    if (done(read_text(log))) return true;
    if (!client.running()) return done(read_text(log));
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return false;
}

/// Unaligned ATE RMSE (m): with the map the estimate is in the map frame.
double ate_raw(const fs::path& estimate) {
  auto est = io::read_tum_trajectory(estimate);
  auto gt = io::read_trajectory(clip().sequence / "mav0/state_groundtruth_estimate0/data.csv");
  if (!est.ok() || !gt.ok()) return 1e9;
  auto assoc = eval::associate(*est, *gt, eval::AssociationOptions{});
  if (!assoc.ok()) return 1e9;
  auto ate = eval::compute_ate(*assoc, eval::Alignment{});
  return ate.ok() ? ate->position_m.rmse : 1e9;
}

TEST(EdgeClientMap, TheMapOverDdsBeatsPlainVioWithinThePaperBudget) {
  ASSERT_FALSE(clip().map.empty());
  const mrvs::test::TempDir dir;
  // The paper's protocol (the ablation gt_noisy): both start from the ground truth plus 2 cm.
  const std::string paper = " --set estimator.alignment.source=gt_noisy";
  const auto plain = edge_client(dir / "plain.txt", "--no-map --log-level warn --progress 0" + paper);
  ASSERT_EQ(plain.exit_code, 0) << plain.output;
  auto server = start_server(dir / "server.log");
  const auto with_map = edge_client(dir / "map.txt", "--map-wait 20 --log-level warn --progress 0" + paper);
  server->stop();
  ASSERT_EQ(with_map.exit_code, 0) << with_map.output;
  const double e_plain = ate_raw(dir / "plain.txt"), e_map = ate_raw(dir / "map.txt");
  RecordProperty("ate_plain_m", std::to_string(e_plain));
  RecordProperty("ate_map_m", std::to_string(e_map));
  EXPECT_LT(e_map, 0.04);
  EXPECT_LT(e_map, 0.8 * e_plain) << "plain " << e_plain << " map " << e_map;
  // The link: answered, one ray per feature (at most 200), the paper's payload budget.
  EXPECT_GT(value_of(with_map.output, "MAP_REQUESTS"), 100.0) << with_map.output;
  EXPECT_LT(value_of(with_map.output, "FRAMES_WITHOUT_MAP"), 0.05 * value_of(with_map.output, "FRAMES"));
  EXPECT_GT(value_of(with_map.output, "ACCEPTED_PER_FRAME"), 1.0);
  EXPECT_LE(value_of(with_map.output, "RAYS_PER_FRAME_MAX"), 200.0);
  EXPECT_LE(value_of(with_map.output, "PAYLOAD_BYTES_PER_FRAME_MAX"), 200.0 * 44.0 + 25.0);
  EXPECT_GT(value_of(with_map.output, "RTT_MS_MEDIAN"), 0.0);
  for (const char* key : {"D_SELECTION_MS_MEDIAN", "E_RAYS_MS_MEDIAN"}) {
    EXPECT_GE(value_of(with_map.output, key), 0.0) << key;
  }
}

TEST(EdgeClientMap, ACloudKilledMidRunLeavesPlainVioAndIsUsedAgainAfterARestart) {
  ASSERT_FALSE(clip().map.empty());
  const mrvs::test::TempDir dir;
  auto server = start_server(dir / "server1.log");
  const fs::path log = dir / "client.log";
  mrvs::test::BackgroundTool client(
      MRVS_EDGE_CLIENT,
      client_args(dir / "traj.txt",
                  "--map-wait 20 --log-level info --progress 0.05 --set estimator.alignment.source=gt_noisy"),
      log);
  // The outage is counted in the client's frames, not in wall time (how fast the client runs
  // depends on the machine's load): the cloud dies at frame 160 of 480, well after the
  // initialisation, and comes back after the client has gone 60 frames without it.
  constexpr int kKillAt = 160, kOutageFrames = 60;
  ASSERT_TRUE(wait_for_log(client, log, [&](const std::string& s) { return progress_frame(s) >= kKillAt; }))
      << read_text(log);
  server->kill_now();
  const int killed_at = progress_frame(read_text(log));
  ASSERT_TRUE(wait_for_log(client, log, [&](const std::string& s) {
    return s.find("no answer from the cloud") != std::string::npos &&
           progress_frame(s) >= killed_at + kOutageFrames;
  })) << read_text(log);
  server = start_server(dir / "server2.log");
  const int restarted_at = progress_frame(read_text(log));
  const auto until = std::chrono::steady_clock::now() + std::chrono::minutes(5);
  while (client.running() && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const int exit_code = client.stop();  // -1 if it had to be stopped
  server->stop();
  const std::string out = read_text(log);
  ASSERT_EQ(exit_code, 0) << out;
  ASSERT_LT(restarted_at, 400) << "the client ran ahead of the test: too few frames left after the restart\n"
                               << out;
  EXPECT_NE(out.find("the cloud answers again"), std::string::npos) << out;
  const double frames = value_of(out, "FRAMES");
  RecordProperty("killed_at_frame", killed_at);
  RecordProperty("restarted_at_frame", restarted_at);
  RecordProperty("frames_without_map", std::to_string(value_of(out, "FRAMES_WITHOUT_MAP")));
  EXPECT_EQ(frames, 480.0);
  // Every frame of the outage asked and went on without an answer.
  EXPECT_GE(value_of(out, "FRAMES_WITHOUT_MAP"), 0.8 * (restarted_at - killed_at)) << out;
  EXPECT_LT(value_of(out, "FRAMES_WITHOUT_MAP"), 0.9 * frames);
  EXPECT_GT(value_of(out, "POSES"), 0.9 * frames);
  EXPECT_LT(ate_raw(dir / "traj.txt"), 0.08);
}

/// The clip as a user has it: no ground-truth folder (the rest linked, not copied).
fs::path clip_without_groundtruth(const fs::path& dir) {
  const fs::path mav0 = dir / "no_gt/mav0";
  fs::create_directories(mav0);
  for (const char* sensor : {"cam0", "cam1", "imu0"})
    fs::create_directory_symlink(clip().sequence / "mav0" / sensor, mav0 / sensor);
  return dir / "no_gt";
}

/// Unaligned ATE RMSE (m) of the part of `estimate` from `from_ns` on.
double ate_raw_from(const fs::path& estimate, TimestampNs from_ns) {
  auto est = io::read_tum_trajectory(estimate);
  if (!est.ok()) return 1e9;
  io::Trajectory tail;
  for (const auto& p : *est) {
    if (p.t_ns >= from_ns) tail.push_back(p);
  }
  const fs::path part = estimate.string() + ".tail";
  if (!io::write_tum_trajectory(part, tail).ok()) return 1e9;
  return ate_raw(part);
}

/// The clip without its ground-truth folder against a running cloud_server, in real time, from
/// the map (the product's default): edge_client's run, its trajectory in dir/traj.txt.
mrvs::test::RunResult run_from_the_map(const fs::path& dir, const std::string& extra) {
  const fs::path sequence = clip_without_groundtruth(dir);
  auto server = start_server(dir / "server.log");
  auto run = edge_client(dir / "traj.txt", "--map-wait 20 --realtime --log-level info --progress 0 " + extra,
                         sequence);
  server->stop();
  return run;
}

// The product's default (no ground truth at run time): the client finds itself in the map
// through the cloud's localisation service and ends in the map frame, near the truth.
TEST(EdgeClientMap, WithoutGroundTruthTheCloudPlacesTheClientInItsMap) {
  ASSERT_FALSE(clip().map.empty());
  const mrvs::test::TempDir dir;
  const auto run = run_from_the_map(dir.path(), "");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_EQ(run.output.find("ground truth read"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("TRAJECTORY_FRAME: map"), std::string::npos) << run.output;
  EXPECT_EQ(value_of(run.output, "LOCALISED"), 1.0) << run.output;
  RecordProperty("localised_after_s", std::to_string(value_of(run.output, "LOCALISED_AFTER_S")));
  RecordProperty("request_bytes", std::to_string(value_of(run.output, "LOCALISATION_REQUEST_BYTES")));
  EXPECT_GT(value_of(run.output, "LOCALISATION_REQUEST_BYTES"), 0.0);
  EXPECT_LT(value_of(run.output, "LOCALISATION_REQUEST_BYTES"), 65536.0);
  EXPECT_EQ(value_of(run.output, "POSES_NEVER_IN_MAP_FRAME"), 0.0);
  // Every pose, those before the answer included, in the map frame and near the truth.
  const double ate = ate_raw(dir / "traj.txt");
  RecordProperty("ate_m", std::to_string(ate));
  EXPECT_LT(ate, 0.05) << run.output;
  EXPECT_LT(
      ate_raw_from(dir / "traj.txt", static_cast<TimestampNs>(value_of(run.output, "LOCALISED_AT_T_NS"))),
      0.05);
}

// A filter restart mid-run (the IMU missing for 0.2 s, after the first lock): the new filter run
// starts in a new odometry frame and the cloud places it again, searching near where the first
// run ended; every pose ends in the map frame, near the truth.
TEST(EdgeClientMap, AfterARestartTheCloudPlacesTheClientAgain) {
  ASSERT_FALSE(clip().map.empty());
  const mrvs::test::TempDir dir;
  const auto run = run_from_the_map(dir.path(), "--imu-outage 16 0.2");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_EQ(value_of(run.output, "FILTER_RUNS"), 2.0) << run.output;
  EXPECT_EQ(value_of(run.output, "LOCALISED_RUNS"), 2.0) << run.output;
  // The second run is searched near where the first, placed one ended, not anywhere.
  EXPECT_NE(run.output.find("of where the last run ended"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("TRAJECTORY_FRAME: map"), std::string::npos) << run.output;
  EXPECT_EQ(value_of(run.output, "POSES_NEVER_IN_MAP_FRAME"), 0.0) << run.output;
  const std::string per_run = "LOCALISED_AFTER_S_PER_RUN: ";
  const std::size_t at = run.output.find(per_run);
  if (at != std::string::npos)
    RecordProperty("localised_after_s_per_run",
                   run.output.substr(at + per_run.size(), run.output.find('\n', at) - at - per_run.size()));
  // Where each run was placed (IMU time): two instants, the second after the first.
  const std::string key = "LOCALISED_AT_T_NS_PER_RUN: ";
  const std::size_t k = run.output.find(key);
  ASSERT_NE(k, std::string::npos) << run.output;
  long long first = 0, second = 0;
  ASSERT_EQ(std::sscanf(run.output.c_str() + k + key.size(), "%lld,%lld", &first, &second), 2) << run.output;
  EXPECT_GT(second, first + 1'000'000'000LL);
  const double ate = ate_raw(dir / "traj.txt");
  RecordProperty("ate_m", std::to_string(ate));
  EXPECT_LT(ate, 0.05) << run.output;
}

// A cloud that never answers: the client says so, runs plain VIO to the end and writes every
// pose in its odometry frame.
TEST(EdgeClientMap, ADeadCloudEndsAsPlainVio) {
  const mrvs::test::TempDir dir;
  const fs::path sequence = clip_without_groundtruth(dir.path());
  const auto run = edge_client(dir / "traj.txt", "--map-wait 1 --log-level info --progress 0", sequence);
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("no map from the cloud"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("never placed the filter in its map"), std::string::npos) << run.output;
  EXPECT_NE(run.output.find("TRAJECTORY_FRAME: odometry"), std::string::npos) << run.output;
  EXPECT_EQ(value_of(run.output, "LOCALISED"), 0.0);
  EXPECT_EQ(value_of(run.output, "FRAMES_SKIPPED"), 0.0);
  EXPECT_GT(value_of(run.output, "POSES"), 0.9 * value_of(run.output, "FRAMES"));
}

}  // namespace
}  // namespace mrvs::edge