#pragma once
// Where the real EuRoC trajectories are (tests/data/euroc_groundtruth by default;
// configure with -DMRVS_SHARED_DIR=<path> to point elsewhere).
#include <filesystem>
#include <string>

namespace mrvs::test {

/// <MRVS_SHARED_DIR>/data/euroc_groundtruth/<name>, e.g. "V1_01_easy.txt".
inline std::filesystem::path euroc_groundtruth_file(const std::string& name) {
  return std::filesystem::path(MRVS_SHARED_DIR) / "data" / "euroc_groundtruth" / name;
}

}  // namespace mrvs::test
