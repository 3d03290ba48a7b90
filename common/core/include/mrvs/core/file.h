#pragma once
// Writing files so that a reader never sees a half-written one.
#include <filesystem>
#include <string_view>

#include "mrvs/core/status.h"

namespace mrvs {

/// Writes `content` to `path` (creating missing parent folders) through a temporary file
/// in the same folder that is renamed into place: either the old file or the complete new
/// one exists at any time. The error names the path and the likely fix.
Status write_file_atomically(const std::filesystem::path& path, std::string_view content);

}  // namespace mrvs
