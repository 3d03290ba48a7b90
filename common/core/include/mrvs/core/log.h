#pragma once
// Logging goes through spdlog (Debian's libspdlog-dev). Executables call
// configure_logging() once from main(); library code just uses spdlog::info/warn/error.
#include <string>

#include <spdlog/spdlog.h>

#include "mrvs/core/status.h"

namespace mrvs {

/// Names accepted by configure_logging: trace, debug, info, warn, error, off.
inline constexpr const char* kLogLevelNames = "trace|debug|info|warn|error|off";

/// Routes spdlog's default logger to stderr (stdout stays for machine-readable output),
/// sets the global level and a compact pattern. Returns an error naming the
/// accepted levels when `level` is not one of them.
Status configure_logging(const std::string& level);

}  // namespace mrvs
