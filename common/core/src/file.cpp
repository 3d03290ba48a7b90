#include "mrvs/core/file.h"

#include <unistd.h>

#include <fstream>

#include <fmt/format.h>

namespace mrvs {

Status write_file_atomically(const std::filesystem::path& path, std::string_view content) {
  std::error_code ec;
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path(), ec);
  if (ec) {
    return absl::PermissionDeniedError(fmt::format("cannot create folder {} for {}: {}",
                                                   path.parent_path().string(), path.string(), ec.message()));
  }
  // The pid keeps two processes writing the same file from sharing a temporary.
  std::filesystem::path tmp = path;
  tmp += fmt::format(".tmp{}", static_cast<long>(::getpid()));
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    out.close();
    if (!out) {
      std::filesystem::remove(tmp, ec);
      return absl::PermissionDeniedError(fmt::format(
          "cannot write {}: check that the folder is writable and the disk is not full", path.string()));
    }
  }
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    return absl::PermissionDeniedError(fmt::format("cannot rename {} to {}: {}; check the permissions",
                                                   tmp.string(), path.string(), ec.message()));
  }
  return absl::OkStatus();
}

}  // namespace mrvs
