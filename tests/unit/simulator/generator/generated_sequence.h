#pragma once
// Short sequences generated once per test binary and shared by the generator tests.
#include <filesystem>
#include <map>
#include <string>

#include "mrvs/sim/generator.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::sim::test {

/// The shared indoor request: V1_01_easy, preset easy, options from indoor_fixture.yaml
/// (1 s window, 3 cm map without noise). A duration or start >= 0 replaces the file's.
GeneratorRequest indoor_request(const std::filesystem::path& out, double duration_s = -1.0,
                                double start_s = -1.0);

/// The sequence CTest generated for this request (fixture sim_generated), or empty
/// when the test runs outside CTest (then the test generates its own).
std::filesystem::path shared_indoor_sequence();

/// The shared outdoor GNSS request: the outdoor profile, preset easy, options from
/// outdoor_gnss_fixture.yaml (1 s window, 20 Hz GNSS with outliers, misaligned coarse map).
GeneratorRequest outdoor_gnss_request(const std::filesystem::path& out);

/// The sequence CTest generated for outdoor_gnss_request (fixture sim_generated), or empty
/// outside CTest.
std::filesystem::path shared_outdoor_gnss_sequence();

/// Bytes of every regular file below `root`, keyed by relative path.
std::map<std::string, std::string> read_tree(const std::filesystem::path& root);

/// Names of the entries of `dir` (not recursive).
std::vector<std::string> list_dir(const std::filesystem::path& dir);

}  // namespace mrvs::sim::test
