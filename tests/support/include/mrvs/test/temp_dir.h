#pragma once
// A temporary directory removed (recursively) when the object goes out of scope.
#include <filesystem>
#include <string>

namespace mrvs::test {

class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  const std::filesystem::path& path() const { return path_; }
  /// path() / relative
  std::filesystem::path operator/(const std::string& relative) const { return path_ / relative; }

  /// Writes `content` to path()/relative (creating parent folders) and returns the path.
  std::filesystem::path write(const std::string& relative, const std::string& content) const;

 private:
  std::filesystem::path path_;
};

}  // namespace mrvs::test
