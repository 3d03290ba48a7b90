// link_probe: replays realistic ray-query batches against a running cloud_server, without
// the estimator, and measures the link: rays from the ground-truth cam0 poses of a
// generated sequence through random pixels towards the scene (true distance with a relative
// error, level from the shared resolution selector), one batch per frame at a fixed rate.
// Prints per-frame lines (--per-frame) and a summary of KEY: value lines.
// Exit codes: 0 done (even with timeouts), 1 set-up error, 2 usage error.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "mrvs/core/cli.h"
#include "mrvs/core/log.h"
#include "mrvs/core/stats.h"
#include "mrvs/edge/map_client.h"
#include "mrvs/sim/generator.h"
#include "mrvs/sim/rng.h"
#include "mrvs/voxel/resolution.h"
#include "mrvs_link.h"

namespace {

using mrvs::DurationNs;
using Clock = std::chrono::steady_clock;

struct Args {
  std::string sequence;
  mrvs::link::ParticipantOptions dds;
  std::string dds_profile;
  double rate_hz = 20.0;
  int rays = 200;
  int frames = 0;
  double timeout_ms = 0.0;
  double distance_error = 0.02;
  double map_wait_s = 10.0;
  std::int64_t seed = 1;
  bool per_frame = false;
  std::string log_level = "info";
};

void add_options(CLI::App& app, Args& a) {
  app.add_option("--sequence", a.sequence, "Generated sequence folder (dataset_simulator --out)")->required();
  app.add_option("--dds-profile", a.dds_profile, "Fast DDS profile (config/dds/*.xml)")->required();
  app.add_option("--dds-domain", a.dds.domain_id, "DDS domain id")
      ->capture_default_str()
      ->check(CLI::Range(0, 232));
  app.add_option("--dds-interface", a.dds.interface_address,
                 "This host's IPv4 address (overrides the profile)");
  app.add_option("--dds-peer", a.dds.peers,
                 "IPv4 address of the cloud host (repeatable; overrides the profile)");
  app.add_option("--rate", a.rate_hz, "Frames per second")
      ->capture_default_str()
      ->check(CLI::Range(0.1, 1000.0));
  app.add_option("--rays", a.rays, "Rays per frame (the paper: 200)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  app.add_option("--frames", a.frames, "Frames to send (0 = the sequence once; more frames replay it)")
      ->capture_default_str()
      ->check(CLI::Range(0, 10000000));
  app.add_option("--timeout-ms", a.timeout_ms, "Per-frame deadline, ms (0 = the frame interval)")
      ->capture_default_str();
  app.add_option("--distance-error", a.distance_error, "Relative error (1 sigma) of the initial distance d")
      ->capture_default_str();
  app.add_option("--map-wait", a.map_wait_s, "Seconds to wait for the cloud's map info")
      ->capture_default_str();
  app.add_option("--seed", a.seed, "Seed of the pixel choice and distance errors")->capture_default_str();
  app.add_flag("--per-frame", a.per_frame, "Print one line per frame");
  mrvs::add_log_level_option(app, a.log_level);
}

/// The rays of frame k (map-local, as the edge would send them).
/// Rays of probe frame k from the camera pose of sequence frame `pose_index` (the pixels and
/// distance errors are drawn per probe frame, so a replayed lap asks different rays).
std::vector<mrvs::voxel::RayQuery> frame_rays(const mrvs::sim::World& world, std::size_t k,
                                              std::size_t pose_index, const mrvs::link::MapInfo& info,
                                              const Args& a) {
  const mrvs::sim::CounterRng rng(static_cast<std::uint64_t>(a.seed), mrvs::sim::Stream::kImageNoise);
  const auto& cam = world.calibration.cameras[0];
  const mrvs::SE3d T_w_c = world.frame_pose(pose_index) * cam.T_b_c;
  const mrvs::SE3d& T_map_w = world.map.T_map_world;
  const double focal = 0.5 * (cam.model->fx() + cam.model->fy());
  std::vector<mrvs::voxel::RayQuery> rays;
  for (std::uint64_t i = 0; rays.size() < static_cast<std::size_t>(a.rays) && i < 20u * a.rays; ++i) {
    const mrvs::Vec2d uv(rng.uniform(0.0, cam.model->width() - 1.0, k, i, 0),
                         rng.uniform(0.0, cam.model->height() - 1.0, k, i, 1));
    auto bearing = cam.model->unproject(uv);
    if (!bearing.ok()) continue;
    const mrvs::Vec3d d_w = T_w_c.quaternion() * *bearing;
    auto hit = world.scene->intersect(T_w_c.translation().cast<float>(), d_w.cast<float>(), 300.0f);
    if (!hit) continue;  // sky
    const double range = hit->distance;
    const auto level = mrvs::voxel::select_level(info.resolutions, range * bearing->z(), focal);
    if (!level) continue;
    mrvs::voxel::RayQuery q;
    q.origin = ((T_map_w * T_w_c.translation()) - info.origin).cast<float>();
    q.direction = (T_map_w.quaternion() * d_w).cast<float>();
    q.initial_distance = static_cast<float>(range * (1.0 + a.distance_error * rng.normal(k, i, 2)));
    q.resolution = static_cast<float>(info.resolutions[*level]);
    rays.push_back(q);
  }
  return rays;
}

struct Totals {
  std::vector<double> rtt_ms;
  std::size_t frames = 0, rays = 0, hits = 0, timeouts = 0, refused = 0;
  std::size_t raw_up = 0, raw_down = 0, cdr_up = 0, cdr_down = 0;
};

void account(const std::vector<mrvs::voxel::RayQuery>& rays, const mrvs::edge::QueryReply& r, Totals& t) {
  ++t.frames;
  t.rays += rays.size();
  t.raw_up += 32 * rays.size();
  t.cdr_up += 4 + mrvs::wire::RayQueryBatch::getCdrSerializedSize(mrvs::link::encode_request(0, 0, 0, rays));
  if (r.outcome == mrvs::edge::QueryOutcome::kTimeout || r.outcome == mrvs::edge::QueryOutcome::kSendFailed) {
    ++t.timeouts;
    return;
  }
  if (r.outcome == mrvs::edge::QueryOutcome::kRefused) ++t.refused;
  t.rtt_ms.push_back(r.rtt_ns * 1e-6);
  std::vector<std::optional<Eigen::Vector3f>> hits(r.answers.size());
  for (std::size_t i = 0; i < r.answers.size(); ++i) {
    if (r.answers[i].hit) hits[i] = r.answers[i].point;
  }
  const std::size_t n_hits = static_cast<std::size_t>(
      std::count_if(hits.begin(), hits.end(), [](auto& h) { return h.has_value(); }));
  t.hits += n_hits;
  t.raw_down += 12 * n_hits;
  const auto request = mrvs::link::encode_request(0, 0, 0, rays);
  t.cdr_down += 4 + mrvs::wire::RayReplyBatch::getCdrSerializedSize(
                        mrvs::link::encode_reply(request, mrvs::link::RequestCheck{}, hits));
}

void print_summary(const Totals& t) {
  const double n = std::max<std::size_t>(t.frames, 1);
  fmt::print("FRAMES: {}\nRAYS_PER_FRAME: {:.1f}\nHITS_PER_FRAME: {:.1f}\nHIT_RATE: {:.3f}\n", t.frames,
             t.rays / n, t.hits / n, t.rays > 0 ? double(t.hits) / t.rays : 0.0);
  fmt::print("RAW_BYTES_UP_PER_FRAME: {:.0f}\nRAW_BYTES_DOWN_PER_FRAME: {:.0f}\n", t.raw_up / n,
             t.raw_down / n);
  fmt::print("SAMPLE_BYTES_UP_PER_FRAME: {:.0f}\nSAMPLE_BYTES_DOWN_PER_FRAME: {:.0f}\n", t.cdr_up / n,
             t.cdr_down / n);
  fmt::print("RTT_P50_MS: {:.3f}\nRTT_P95_MS: {:.3f}\nRTT_P99_MS: {:.3f}\nRTT_MAX_MS: {:.3f}\n",
             mrvs::quantile(t.rtt_ms, 0.5), mrvs::quantile(t.rtt_ms, 0.95), mrvs::quantile(t.rtt_ms, 0.99),
             mrvs::quantile(t.rtt_ms, 1.0));
  fmt::print("TIMEOUTS: {}\nREFUSED: {}\n", t.timeouts, t.refused);
}

int run(const Args& a) {
  auto request = mrvs::sim::load_generator_request(a.sequence);
  auto world =
      request.ok() ? mrvs::sim::build_world(*request) : mrvs::StatusOr<mrvs::sim::World>(request.status());
  if (!world.ok()) {
    fmt::print(stderr, "link_probe: error: {}\n", std::string(world.status().message()));
    return mrvs::kExitDataError;
  }
  mrvs::edge::MapClientOptions options;
  options.dds = a.dds;
  options.dds.profile_file = a.dds_profile;
  options.dds.name = "mrvs_link_probe";
  auto client = mrvs::edge::MapClient::create(options);
  if (!client.ok()) {
    fmt::print(stderr, "link_probe: error: {}\n", std::string(client.status().message()));
    return mrvs::kExitDataError;
  }
  const auto info = (*client)->wait_for_map_info(static_cast<DurationNs>(a.map_wait_s * 1e9));
  if (!info) {
    fmt::print(stderr, "link_probe: error: no map info from a cloud_server within {} s\n", a.map_wait_s);
    return mrvs::kExitDataError;
  }
  spdlog::info("map {} ({} levels), client id {}", info->map_id, info->resolutions.size(),
               (*client)->client_id());
  const std::size_t available = world->grid.camera_true_ns.size();
  const std::size_t frames = a.frames > 0 ? static_cast<std::size_t>(a.frames) : available;
  const auto period = std::chrono::nanoseconds(static_cast<std::int64_t>(1e9 / a.rate_hz));
  const DurationNs timeout = a.timeout_ms > 0 ? static_cast<DurationNs>(a.timeout_ms * 1e6) : period.count();
  Totals totals;
  const auto epoch_ns = [] {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::system_clock::now().time_since_epoch())
        .count();
  };
  const std::int64_t first_frame_epoch_ns = epoch_ns();
  const Clock::time_point start = Clock::now();
  for (std::size_t k = 0; k < frames; ++k) {
    std::this_thread::sleep_until(start + k * period);
    const std::size_t pose_index = k % available;
    const auto rays = frame_rays(*world, k, pose_index, *info, a);
    const auto reply = (*client)->query(rays, world->grid.camera_stamp_ns[pose_index], timeout);
    account(rays, reply, totals);
    if (a.per_frame) {
      fmt::print("frame {} rays {} outcome {} rtt_ms {:.3f}\n", k, rays.size(),
                 static_cast<int>(reply.outcome), reply.rtt_ns * 1e-6);
    }
  }
  print_summary(totals);
  // Wall-clock window of the frames, for restricting a packet capture to them.
  fmt::print("FIRST_FRAME_EPOCH_NS: {}\nLAST_FRAME_EPOCH_NS: {}\n", first_frame_epoch_ns, epoch_ns());
  const auto& s = (*client)->stats();
  fmt::print("STALE_REPLIES_DROPPED: {}\nFOREIGN_REPLIES_DROPPED: {}\n", s.stale_dropped, s.foreign_dropped);
  return mrvs::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Replays ray-query batches from a generated sequence against a cloud_server and measures the link.",
      "link_probe"};
  Args args;
  add_options(app, args);
  if (auto exit_code = mrvs::parse_command_line(app, argc, argv, args.log_level)) return *exit_code;
  return run(args);
}
