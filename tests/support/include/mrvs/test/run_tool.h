#pragma once
// Runs a project executable from a test and captures what it prints.
#include <filesystem>
#include <string>

namespace mrvs::test {

struct RunResult {
  int exit_code = -1;  ///< -1 when the process did not exit normally
  std::string output;  ///< stdout and stderr, interleaved
};

/// Runs `executable` with `args` (already shell-quoted where needed, see quoted()).
RunResult run_tool(const std::filesystem::path& executable, const std::string& args);

/// 'path' for a shell command line.
std::string quoted(const std::filesystem::path& p);

/// Value of the machine-readable line "KEY: value" in `text`; NaN when the key is missing.
double value_of(const std::string& text, const std::string& key);

}  // namespace mrvs::test
