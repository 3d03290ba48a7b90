// localise_compare: the cloud's registration against PCL's on the same localisation requests
// (issue 30: PCL's registration module was the expected starting point; own code only where a
// measurement shows it is better). Reads the requests a localise_probe --dump wrote (their
// true T_map_odom from the simulator) and registers each with
//   ours            the Localiser (coarse branch and bound, 4-DoF fine stage, verdict);
//   fpfh_sac        FPFH + pcl::SampleConsensusPrerejective over the whole map, then GICP;
// and, from one start per request (the truth moved by --start-m along a direction that turns
// from request to request, and turned by +-start-deg), the fine methods:
//   ours_fine       the Localiser's fine stage alone (Localiser::refine);
//   gicp, ndt, point_to_plane   PCL's, 6-DoF, against the same map level.
// Per request one COMPARE line, then per method KEY: value lines: correct (within 10 cm and
// 2 deg of yaw and of tilt), precise (within 3 cm and 0.5 deg), the median error and the
// median and p95 time on one thread.
//
//   localise_compare --replay DUMPS --map MAP.mrvm --map-config config/map_indoor.yaml
//                    [--methods ours,fpfh_sac,ours_fine,gicp,ndt,point_to_plane]
// Exit codes: 0 done, 1 data error, 2 usage error.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <Eigen/Geometry>

#include "mrvs/config/yaml_document.h"
#include "mrvs/core/cli.h"
#include "mrvs/core/stats.h"
#include "mrvs/geometry/angles.h"
#include "mrvs/localise/localiser.h"
#include "mrvs/map/map_file.h"
#include "mrvs/tools/pcl_registration.h"
#include "mrvs/tools/request_dump.h"

namespace {

using mrvs::tools::PclMethod;

struct Args {
  std::string replay, map, map_config;
  std::vector<std::string> map_overrides;
  std::vector<std::string> methods{"ours", "fpfh_sac", "ours_fine", "gicp", "ndt", "point_to_plane"};
  double start_m = 0.2, start_deg = 5.0;
  int sac_iterations = 50000;
  std::string log_level = "warn";
};

/// Error of M (aligned submap -> map-local) against the truth: at the anchor, yaw, tilt.
struct Error {
  double m = 0.0, yaw_deg = 0.0, tilt_deg = 0.0;
  bool correct() const { return m <= 0.10 && yaw_deg <= 2.0 && tilt_deg <= 2.0; }
  bool precise() const { return m <= 0.03 && yaw_deg <= 0.5 && tilt_deg <= 0.5; }
};

Error error_of(const Eigen::Matrix4d& M, const Eigen::Matrix4d& truth) {
  const Eigen::Matrix3d d = M.topLeftCorner<3, 3>() * truth.topLeftCorner<3, 3>().transpose();
  const Eigen::Vector3d z = d * Eigen::Vector3d::UnitZ();
  Error e;
  e.m = (M.topRightCorner<3, 1>() - truth.topRightCorner<3, 1>()).norm();
  e.yaw_deg = std::abs(std::atan2(d(1, 0) - d(0, 1), d(0, 0) + d(1, 1))) * mrvs::kRadToDeg;
  e.tilt_deg = std::acos(std::clamp(z.z(), -1.0, 1.0)) * mrvs::kRadToDeg;
  return e;
}

/// Request i's fine start: the truth moved by start_m along a direction turning by the golden
/// angle from request to request, and turned by +-start_deg about the vertical.
Eigen::Matrix4d start_of(const Eigen::Matrix4d& truth, int i, const Args& a) {
  const double dir = 2.399963 * i;
  Eigen::Matrix4d s = truth;
  const double yaw = (i % 2 == 0 ? 1.0 : -1.0) * a.start_deg * mrvs::kDegToRad;
  s.topLeftCorner<3, 3>() =
      Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix() * truth.topLeftCorner<3, 3>();
  s.topRightCorner<3, 1>() += a.start_m * Eigen::Vector3d(std::cos(dir), std::sin(dir), 0.0);
  return s;
}

struct Tally {
  int runs = 0, answered = 0, correct = 0, precise = 0, wrong = 0;
  std::vector<double> err_m, err_deg, ms;
  void add(bool answer, const Error& e, double t_ms) {
    ++runs;
    ms.push_back(t_ms);
    if (!answer) return;
    ++answered;
    correct += e.correct();
    precise += e.precise();
    wrong += !e.correct();
    if (e.correct()) {
      err_m.push_back(e.m);
      err_deg.push_back(std::max(e.yaw_deg, e.tilt_deg));
    }
  }
};

struct Tools {
  std::shared_ptr<const mrvs::map::VoxelMap> map;
  std::optional<mrvs::localise::Localiser> localiser;
  std::optional<mrvs::tools::PclMap> pcl;
  mrvs::tools::PclOptions pcl_options;
};

mrvs::StatusOr<Tools> make_tools(const Args& a) {
  MRVS_ASSIGN_OR_RETURN(const auto doc,
                        mrvs::config::load_yaml_with_overrides(a.map_config, a.map_overrides));
  MRVS_ASSIGN_OR_RETURN(const auto lo,
                        mrvs::config::load_options<mrvs::localise::LocaliserOptions>(doc, "localise"));
  MRVS_ASSIGN_OR_RETURN(mrvs::map::VoxelMap vm, mrvs::map::load_voxel_map(a.map));
  Tools t;
  t.map = std::make_shared<const mrvs::map::VoxelMap>(std::move(vm));
  MRVS_ASSIGN_OR_RETURN(auto l, mrvs::localise::Localiser::create(t.map, lo));
  t.localiser.emplace(std::move(l));
  // PCL on the same data as ours: the fine level, the submap thinned to the same cell and count.
  t.pcl_options.map_level_m = lo.fine_resolution_m;
  t.pcl_options.voxel_m = lo.fine_voxel_m;
  t.pcl_options.max_points = lo.fine_max_points;
  t.pcl_options.inlier_m = lo.inlier_m;
  t.pcl_options.sac_iterations = a.sac_iterations;
  bool features = false;
  for (const auto& m : a.methods) features |= m == "fpfh_sac";
  MRVS_ASSIGN_OR_RETURN(auto p, mrvs::tools::PclMap::build(*t.map, t.pcl_options, features));
  t.pcl.emplace(std::move(p));
  fmt::print("SETUP_S_OURS: {:.2f}\nSETUP_S_PCL: {:.2f}\n", t.localiser->setup_s(), t.pcl->setup_s());
  return t;
}

/// One method on one request: whether it answered, its M, its time.
struct Outcome {
  bool answer = false;
  Eigen::Matrix4d M = Eigen::Matrix4d::Identity();
  double ms = 0.0;
  std::string note;
};

Outcome run_method(Tools& t, const std::string& method, const mrvs::tools::DumpedRequest& d,
                   const mrvs::tools::AlignedSubmap& s, const Eigen::Matrix4d& start) {
  const mrvs::Vec3d origin = t.map->origin;
  Outcome o;
  if (method == "ours" || method == "ours_fine") {
    const auto r = method == "ours"
                       ? t.localiser->localise(d.request)
                       : t.localiser->refine(d.request, mrvs::tools::T_m_o_from(start, s, d.request, origin));
    o.answer = r.status == mrvs::localisation::Status::kOk;
    o.M = mrvs::tools::M_from(r.T_m_o, s, d.request, origin);
    o.ms = r.time_ms;
    o.note = fmt::format("{} fitness {:.2f}", mrvs::localisation::status_name(r.status), r.fitness);
    return o;
  }
  const auto pm = mrvs::tools::pcl_method_from_name(method);
  const auto r = pm == PclMethod::kFpfhSac ? t.pcl->register_global(s) : t.pcl->register_fine(*pm, s, start);
  // PCL has no verdict: an answer is a converged registration putting as much of the submap on
  // the map as ours needs (localise.min_fitness).
  o.answer = r.converged && r.fitness >= t.localiser->options().min_fitness;
  o.M = r.M;
  o.ms = r.ms;
  o.note = fmt::format("{} fitness {:.2f}", r.converged ? "converged" : "not converged", r.fitness);
  return o;
}

int run(const Args& a) {
  for (const auto& m : a.methods) {
    if (m != "ours" && m != "ours_fine" && !mrvs::tools::pcl_method_from_name(m)) {
      fmt::print(
          stderr,
          "localise_compare: unknown method '{}' (ours, ours_fine, gicp, ndt, point_to_plane, fpfh_sac)\n",
          m);
      return mrvs::kExitUsageError;
    }
  }
  const std::vector<std::string> files = mrvs::tools::request_dump_files(a.replay);
  if (files.empty()) {
    fmt::print(stderr, "localise_compare: no req_*.txt under {} (write them with localise_probe --dump)\n",
               a.replay);
    return mrvs::kExitDataError;
  }
  auto tools = make_tools(a);
  if (!tools.ok())
    return fmt::print(stderr, "localise_compare: {}\n", std::string(tools.status().message())),
           mrvs::kExitUsageError;
  std::map<std::string, Tally> tally;
  for (std::size_t i = 0; i < files.size(); ++i) {
    const auto d = mrvs::tools::read_request_dump(files[i]);
    if (!d.ok())
      return fmt::print(stderr, "localise_compare: {}\n", std::string(d.status().message())),
             mrvs::kExitDataError;
    const auto s = mrvs::tools::align_submap(d->request, tools->pcl_options);
    const Eigen::Matrix4d truth = mrvs::tools::M_from(d->truth, s, d->request, tools->map->origin);
    const Eigen::Matrix4d start = start_of(truth, static_cast<int>(i), a);
    for (const auto& method : a.methods) {
      const Outcome o = run_method(*tools, method, *d, s, start);
      const Error e = error_of(o.M, truth);
      tally[method].add(o.answer, e, o.ms);
      fmt::print("COMPARE {} {} {} error {:.3f} m yaw {:.2f} tilt {:.2f} deg {:.0f} ms ({})\n", files[i],
                 method, o.answer ? (e.correct() ? "correct" : "WRONG") : "no answer", e.m, e.yaw_deg,
                 e.tilt_deg, o.ms, o.note);
    }
  }
  fmt::print("REQUESTS: {}\nSTART_OFFSET_M: {}\nSTART_OFFSET_DEG: {}\n", files.size(), a.start_m,
             a.start_deg);
  for (const auto& method : a.methods) {
    const Tally& t = tally[method];
    std::string k = method;
    std::transform(k.begin(), k.end(), k.begin(), [](unsigned char c) { return std::toupper(c); });
    fmt::print("{0}_ANSWERED: {1}\n{0}_CORRECT: {2}\n{0}_PRECISE: {3}\n{0}_WRONG: {4}\n", k, t.answered,
               t.correct, t.precise, t.wrong);
    fmt::print(
        "{0}_ERROR_M_MEDIAN: {1:.4f}\n{0}_ERROR_DEG_MEDIAN: {2:.3f}\n{0}_MS_MEDIAN: {3:.1f}\n{0}_MS_P95: "
        "{4:.1f}\n",
        k, mrvs::quantile(t.err_m, 0.5), mrvs::quantile(t.err_deg, 0.5), mrvs::quantile(t.ms, 0.5),
        mrvs::quantile(t.ms, 0.95));
  }
  return mrvs::kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Registers dumped localisation requests with the cloud's Localiser and with PCL's methods.",
               "localise_compare"};
  Args a;
  app.add_option("--replay", a.replay, "Folder of requests written by localise_probe --dump")
      ->required()
      ->check(CLI::ExistingDirectory);
  app.add_option("--map", a.map, "Voxel map (.mrvm) the requests were made against")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--map-config", a.map_config, "Cloud tuning file (config/map_indoor.yaml)")
      ->required()
      ->check(CLI::ExistingFile);
  app.add_option("--map-set", a.map_overrides, "Cloud option override, e.g. localise.inlier_m=0.08");
  app.add_option("--methods", a.methods, "Methods: ours, fpfh_sac, ours_fine, gicp, ndt, point_to_plane")
      ->delimiter(',');
  app.add_option("--start-m", a.start_m, "Fine methods start this far from the truth, m")
      ->check(CLI::Range(0.0, 10.0));
  app.add_option("--start-deg", a.start_deg, "... and turned by this, deg")->check(CLI::Range(0.0, 180.0));
  app.add_option("--sac-iterations", a.sac_iterations, "fpfh_sac: sample-consensus iterations")
      ->check(CLI::Range(1, 10000000));
  mrvs::add_log_level_option(app, a.log_level);
  if (auto exit_code = mrvs::parse_command_line(app, argc, argv, a.log_level)) return *exit_code;
  return run(a);
}
