#include "mrvs/core/cli.h"

#include <fmt/format.h>

#include "mrvs/core/log.h"

namespace mrvs {

void add_log_level_option(CLI::App& app, std::string& level) {
  app.add_option("--log-level", level, fmt::format("Log level ({}); logs go to stderr", kLogLevelNames))
      ->capture_default_str();
}

std::optional<int> parse_command_line(CLI::App& app, int argc, char** argv, const std::string& level) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? kExitOk : kExitUsageError;
  }
  const Status logging = configure_logging(level);
  if (!logging.ok()) {
    fmt::print(stderr, "{}: error: {}\n", app.get_name(), std::string(logging.message()));
    return kExitUsageError;
  }
  return std::nullopt;
}

}  // namespace mrvs
