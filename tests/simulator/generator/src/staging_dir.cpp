#include "mrvs/sim/staging_dir.h"

#include <stdlib.h>  // mkdtemp
#include <unistd.h>  // access

#include <vector>

#include <fmt/format.h>

namespace mrvs::sim {
namespace fs = std::filesystem;

StatusOr<StagingDir> StagingDir::create(const fs::path& destination, bool overwrite) {
  if (destination.empty()) return absl::InvalidArgumentError("the output folder is empty; give --out DIR");
  const fs::path dest = fs::absolute(destination).lexically_normal();
  std::error_code ec;
  if (fs::exists(dest, ec) && !overwrite) {
    return absl::AlreadyExistsError(
        fmt::format("output folder {} already exists; choose another --out, delete it, or pass --overwrite",
                    dest.string()));
  }
  if (fs::exists(dest, ec) && !fs::is_directory(dest, ec)) {
    return absl::AlreadyExistsError(fmt::format("output path {} exists and is not a folder", dest.string()));
  }
  const fs::path parent = dest.parent_path();
  fs::create_directories(parent, ec);
  if (ec || ::access(parent.c_str(), W_OK) != 0) {
    return absl::PermissionDeniedError(
        fmt::format("cannot write into {} (for output folder {}){}{}; choose a writable --out",
                    parent.string(), dest.string(), ec ? ": " : "", ec ? ec.message() : ""));
  }
  std::string pattern = (parent / fmt::format(".{}.partial-XXXXXX", dest.filename().string())).string();
  std::vector<char> buffer(pattern.begin(), pattern.end());
  buffer.push_back('\0');
  if (::mkdtemp(buffer.data()) == nullptr) {
    return absl::PermissionDeniedError(fmt::format("cannot create a staging folder in {}", parent.string()));
  }
  return StagingDir(dest, fs::path(buffer.data()), overwrite);
}

StagingDir::StagingDir(StagingDir&& other) noexcept
    : destination_(std::move(other.destination_)),
      staging_(std::move(other.staging_)),
      overwrite_(other.overwrite_),
      committed_(other.committed_) {
  other.committed_ = true;  // the moved-from object owns nothing
}

StagingDir::~StagingDir() {
  if (committed_) return;
  std::error_code ec;
  fs::remove_all(staging_, ec);
}

Status StagingDir::commit() {
  std::error_code ec;
  fs::path old;
  if (fs::exists(destination_, ec)) {
    if (!overwrite_) {
      return absl::AlreadyExistsError(
          fmt::format("output folder {} appeared while writing; nothing replaced", destination_.string()));
    }
    old = staging_;
    old += ".old";
    fs::rename(destination_, old, ec);
    if (ec) {
      return absl::PermissionDeniedError(
          fmt::format("cannot move the old {} aside: {}", destination_.string(), ec.message()));
    }
  }
  fs::rename(staging_, destination_, ec);
  if (ec) {
    if (!old.empty()) fs::rename(old, destination_, ec);
    return absl::PermissionDeniedError(
        fmt::format("cannot rename {} to {}: {}", staging_.string(), destination_.string(), ec.message()));
  }
  committed_ = true;
  if (!old.empty()) fs::remove_all(old, ec);
  return absl::OkStatus();
}

}  // namespace mrvs::sim
