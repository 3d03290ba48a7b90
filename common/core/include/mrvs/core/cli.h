#pragma once
// Command-line conventions shared by every executable (CLI11):
// - `--log-level` on every tool, logs on stderr;
// - exit codes: 0 success (and --help), 1 data error, 2 usage error.
//
//   int main(int argc, char** argv) {
//     CLI::App app{"What the tool does.", "tool_name"};
//     Args args;  // add_option(...) calls
//     std::string log_level = "info";
//     mrvs::add_log_level_option(app, log_level);
//     if (auto exit_code = mrvs::parse_command_line(app, argc, argv, log_level)) return *exit_code;
//     return run(args);
//   }
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

namespace mrvs {

inline constexpr int kExitOk = 0;
inline constexpr int kExitDataError = 1;
inline constexpr int kExitUsageError = 2;

/// Adds `--log-level` (trace|debug|info|warn|error|off) bound to `level`.
void add_log_level_option(CLI::App& app, std::string& level);

/// Parses the command line and configures logging. Returns the code main() should return
/// now (0 after --help, kExitUsageError on a usage error, with the message printed), or
/// nullopt when the program should go on.
std::optional<int> parse_command_line(CLI::App& app, int argc, char** argv, const std::string& level);

}  // namespace mrvs
