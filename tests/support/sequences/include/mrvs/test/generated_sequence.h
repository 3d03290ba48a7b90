#pragma once
// Generated EuRoC-format sequences for end-to-end tests, written once per build tree and
// reused by every test process (CTest runs each test in its own process).
#include <filesystem>
#include <string>

#include "mrvs/core/status.h"
#include "mrvs/sim/generator.h"

namespace mrvs::test {

/// A short indoor request along a real EuRoC trajectory (tests/data/euroc_groundtruth):
/// `duration_s` from `start_s`, the given preset, a coarse map (issue-7 tests do not use it).
sim::GeneratorRequest indoor_sequence_request(const std::string& trajectory_file, double start_s,
                                              double duration_s, const std::string& preset);

/// The folder of the sequence `name` under the build tree's test-data folder, generated
/// from `request` (its `out` is ignored) when it is not there yet. Concurrent callers are
/// safe: the generator publishes a complete folder atomically, and losing the race means the
/// folder exists.
StatusOr<std::filesystem::path> generated_sequence(const std::string& name, sim::GeneratorRequest request);

}  // namespace mrvs::test
