#include "mrvs/core/log.h"

#include <fmt/format.h>
#include <spdlog/sinks/stdout_color_sinks.h>

namespace mrvs {

Status configure_logging(const std::string& level) {
  const spdlog::level::level_enum parsed = spdlog::level::from_str(level);
  // spdlog maps unknown names to "off"; only accept "off" when asked for.
  if (parsed == spdlog::level::off && level != "off") {
    return absl::InvalidArgumentError(
        fmt::format("unknown log level '{}' (expected one of {})", level, kLogLevelNames));
  }
  // Logs go to stderr: stdout stays clean for the tools' machine-readable lines.
  if (spdlog::default_logger()->name() != "mrvs") {
    spdlog::set_default_logger(spdlog::stderr_color_mt("mrvs"));
  }
  spdlog::set_level(parsed);
  spdlog::set_pattern("[%H:%M:%S.%e] [%^%l%$] %v");
  return absl::OkStatus();
}

}  // namespace mrvs
