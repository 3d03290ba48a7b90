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

/// A project executable running in the background (a server for a client under test), its
/// stdout and stderr in `log`. Stopped (TERM, then KILL) at the latest by the destructor.
class BackgroundTool {
 public:
  BackgroundTool(const std::filesystem::path& executable, const std::string& args,
                 const std::filesystem::path& log);
  ~BackgroundTool();
  BackgroundTool(const BackgroundTool&) = delete;
  BackgroundTool& operator=(const BackgroundTool&) = delete;
  bool running();
  /// SIGTERM, then SIGKILL after `grace_s`; the exit code (-1: killed or not started).
  int stop(double grace_s = 5.0);
  /// SIGKILL at once (a crash of the server).
  void kill_now();

 private:
  int pid_ = -1;
  int status_ = -1;
};

/// 'path' for a shell command line.
std::string quoted(const std::filesystem::path& p);

/// Value of the machine-readable line "KEY: value" in `text`; NaN when the key is missing.
double value_of(const std::string& text, const std::string& key);

}  // namespace mrvs::test
