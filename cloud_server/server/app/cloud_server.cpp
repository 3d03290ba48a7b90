// cloud_server: loads a voxel map (.mrvm) and answers ray-query batches from edge clients
// over Fast DDS until SIGINT/SIGTERM (or --max-requests). Exit codes: 0 stopped cleanly,
// 1 map or DDS set-up error, 2 usage error.
//
//   cloud_server --map build/demo/V1_01_sim.mrvm --dds-profile config/dds/loopback.xml
//                [--config config/map_indoor.yaml] [--set query.search_range_m=1.0]
//                [--no-localisation]
// With the map it serves ray queries and (unless --no-localisation) the localisation service
// (design/localisation.md), tuned by the config's `localise` section.
#include <pthread.h>
#include <signal.h>

#include <atomic>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include "mrvs/cloud/ray_server.h"
#include "mrvs/config/options.h"
#include "mrvs/core/cli.h"
#include "mrvs/core/log.h"
#include "mrvs/localise/localiser.h"
#include "mrvs/map/map_file.h"

namespace {

struct Args {
  std::string map;
  std::string config;
  std::vector<std::string> overrides;
  mrvs::link::ParticipantOptions dds;
  std::string dds_profile;
  double stats_period_s = 10.0;
  std::uint64_t max_requests = 0;
  bool no_localisation = false;
  std::string log_level = "info";
};

void add_options(CLI::App& app, Args& a) {
  app.add_option("--map", a.map, "Voxel map to serve (.mrvm, from map_builder)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--dds-profile", a.dds_profile,
                 "Fast DDS profile (config/dds/loopback.xml, two_hosts.xml, ...)")
      ->required();
  app.add_option("--dds-domain", a.dds.domain_id, "DDS domain id (the edge must use the same)")
      ->capture_default_str()
      ->check(CLI::Range(0, 232));
  app.add_option("--dds-interface", a.dds.interface_address,
                 "This host's IPv4 address: the only interface used (overrides the profile)");
  app.add_option("--dds-peer", a.dds.peers,
                 "IPv4 address of an edge host (repeatable; overrides the profile)");
  app.add_option("--config", a.config,
                 "YAML file whose 'query' section tunes the query engine (config/map_*.yaml)")
      ->check(CLI::ExistingFile);
  app.add_option("--set", a.overrides,
                 "Override a query or localise option, e.g. --set query.search_range_m=1.0");
  app.add_flag("--no-localisation", a.no_localisation, "Serve ray queries only (no localisation service)");
  app.add_option("--stats-period", a.stats_period_s,
                 "Seconds between per-client counter logs (0 = only at exit)")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  app.add_option("--max-requests", a.max_requests,
                 "Stop after answering this many requests (0 = until a signal)")
      ->capture_default_str();
  mrvs::add_log_level_option(app, a.log_level);
}

struct ServerOptions {
  mrvs::map::QueryOptions query;
  mrvs::localise::LocaliserOptions localise;
};

mrvs::StatusOr<ServerOptions> load_server_options(const Args& a) {
  MRVS_ASSIGN_OR_RETURN(const mrvs::config::YamlDocument doc,
                        mrvs::config::load_yaml_with_overrides(a.config, a.overrides));
  ServerOptions o;
  MRVS_ASSIGN_OR_RETURN(o.query, mrvs::config::load_options<mrvs::map::QueryOptions>(doc, "query"));
  MRVS_ASSIGN_OR_RETURN(o.localise,
                        mrvs::config::load_options<mrvs::localise::LocaliserOptions>(doc, "localise"));
  return o;
}

/// The localiser over `map`, or nullptr with --no-localisation.
mrvs::StatusOr<std::shared_ptr<const mrvs::localise::Localiser>> make_localiser(
    const Args& a, std::shared_ptr<const mrvs::map::VoxelMap> map,
    const mrvs::localise::LocaliserOptions& o) {
  if (a.no_localisation) {
    spdlog::info("localisation service off (--no-localisation)");
    return std::shared_ptr<const mrvs::localise::Localiser>();
  }
  spdlog::info("localise options:\n{}", mrvs::config::options_to_yaml(o, "localise"));
  MRVS_ASSIGN_OR_RETURN(mrvs::localise::Localiser localiser,
                        mrvs::localise::Localiser::create(std::move(map), o));
  spdlog::info("localisation service ready ({:.1f} s to index the {} m level)", localiser.setup_s(),
               o.fine_resolution_m);
  return std::make_shared<const mrvs::localise::Localiser>(std::move(localiser));
}

mrvs::StatusOr<std::unique_ptr<mrvs::cloud::RayServer>> make_server(const Args& a) {
  MRVS_ASSIGN_OR_RETURN(const ServerOptions server_options, load_server_options(a));
  const mrvs::map::QueryOptions& query = server_options.query;
  spdlog::info("query options:\n{}", mrvs::config::options_to_yaml(query, "query"));
  MRVS_ASSIGN_OR_RETURN(mrvs::map::VoxelMap map, mrvs::map::load_voxel_map(a.map));
  MRVS_ASSIGN_OR_RETURN(const std::string bytes, mrvs::map::serialize_voxel_map(map, a.map));
  mrvs::cloud::RayServerOptions options;
  options.dds = a.dds;
  options.dds.profile_file = a.dds_profile;
  options.dds.name = "mrvs_cloud_server";
  options.map_id = std::filesystem::path(a.map).filename().string();
  options.map_checksum = mrvs::map::fnv1a_64(bytes.data(), bytes.size());
  options.stats_period_ns = static_cast<mrvs::DurationNs>(a.stats_period_s * 1e9);
  options.max_requests = a.max_requests;
  for (std::size_t i = 0; i < map.levels.size(); ++i) {
    spdlog::info("level {}: {} m, {} points", i, map.levels[i].resolution, map.levels[i].points.size());
  }
  const auto shared = std::make_shared<const mrvs::map::VoxelMap>(std::move(map));
  MRVS_ASSIGN_OR_RETURN(options.localiser, make_localiser(a, shared, server_options.localise));
  MRVS_ASSIGN_OR_RETURN(mrvs::map::QueryEngine engine, mrvs::map::QueryEngine::create(shared, query));
  return mrvs::cloud::RayServer::create(std::move(engine), options);
}

int run(const Args& a) {
  // SIGINT/SIGTERM are taken by a dedicated thread (sigwait), not by a signal handler.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGINT);
  sigaddset(&signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);  // inherited by every thread made from here
  auto server = make_server(a);
  if (!server.ok()) {
    fmt::print(stderr, "cloud_server: error: {}\n", std::string(server.status().message()));
    return mrvs::kExitDataError;
  }
  std::atomic<bool> finished{false};
  std::thread signal_thread([&signals, &finished, s = server->get()] {
    int signal = 0;
    sigwait(&signals, &signal);
    if (!finished) spdlog::info("signal {}: stopping", signal);
    s->stop();
  });
  spdlog::info("serving {} (DDS domain {}, profile {})", a.map, a.dds.domain_id, a.dds_profile);
  const mrvs::Status status = (*server)->run();
  finished = true;
  pthread_kill(signal_thread.native_handle(), SIGTERM);  // release the waiting thread if run() ended itself
  signal_thread.join();
  fmt::print("REQUESTS_ANSWERED: {}\n", (*server)->requests_answered());
  if (!status.ok()) {
    fmt::print(stderr, "cloud_server: error: {}\n", std::string(status.message()));
    return mrvs::kExitDataError;
  }
  return mrvs::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Serves a multi-resolution voxel map to edge clients: ray-query batches in, points out, over Fast DDS.",
      "cloud_server"};
  Args args;
  add_options(app, args);
  if (auto exit_code = mrvs::parse_command_line(app, argc, argv, args.log_level)) return *exit_code;
  return run(args);
}
