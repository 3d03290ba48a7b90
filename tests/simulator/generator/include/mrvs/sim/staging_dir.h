#pragma once
// Writing a whole dataset folder so that it appears complete or not at all: files go to a
// hidden sibling folder that is renamed onto the destination at the end, and removed if
// anything fails before that.
#include <filesystem>

#include "mrvs/core/status.h"

namespace mrvs::sim {

class StagingDir {
 public:
  /// Checks that `destination` can be created (its parent exists or can be made and is
  /// writable; it does not exist yet unless `overwrite`), then creates the staging folder
  /// "<parent>/.<name>.partial-XXXXXX" next to it.
  static StatusOr<StagingDir> create(const std::filesystem::path& destination, bool overwrite);

  StagingDir(StagingDir&& other) noexcept;
  StagingDir& operator=(StagingDir&&) = delete;
  StagingDir(const StagingDir&) = delete;
  /// Removes the staging folder unless commit() succeeded.
  ~StagingDir();

  /// Where to write: the staging folder.
  const std::filesystem::path& path() const { return staging_; }
  const std::filesystem::path& destination() const { return destination_; }

  /// Moves the staging folder onto the destination (replacing an old one when allowed).
  Status commit();

 private:
  StagingDir(std::filesystem::path destination, std::filesystem::path staging, bool overwrite)
      : destination_(std::move(destination)), staging_(std::move(staging)), overwrite_(overwrite) {}

  std::filesystem::path destination_;
  std::filesystem::path staging_;
  bool overwrite_ = false;
  bool committed_ = false;
};

}  // namespace mrvs::sim
