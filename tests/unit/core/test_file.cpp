#include <sys/stat.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "mrvs/core/file.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs {
namespace {

std::string read(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(File, WritesCreatesFoldersAndReplaces) {
  const test::TempDir dir;
  const auto path = dir / "a/b/c.txt";
  ASSERT_TRUE(write_file_atomically(path, "first").ok());
  EXPECT_EQ(read(path), "first");
  ASSERT_TRUE(write_file_atomically(path, std::string("sec\0ond", 7)).ok());
  EXPECT_EQ(read(path), std::string("sec\0ond", 7));
  // No temporary left behind.
  int entries = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator(path.parent_path())) ++entries;
  EXPECT_EQ(entries, 1);
}

TEST(File, UnwritableFolderIsAnErrorNamingThePathAndKeepsTheOldFile) {
  if (::geteuid() == 0) GTEST_SKIP() << "root ignores folder permissions";
  const test::TempDir dir;
  const auto path = dir / "locked/file.txt";
  ASSERT_TRUE(write_file_atomically(path, "old").ok());
  ::chmod(path.parent_path().c_str(), 0500);
  const Status s = write_file_atomically(path, "new");
  ::chmod(path.parent_path().c_str(), 0700);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find(path.string()), std::string::npos) << s;
  EXPECT_EQ(read(path), "old");
}

TEST(File, PathThroughAFileIsAnError) {
  const test::TempDir dir;
  ASSERT_TRUE(write_file_atomically(dir / "plain", "x").ok());
  const Status s = write_file_atomically(dir / "plain/child.txt", "y");
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("plain"), std::string::npos) << s;
}

}  // namespace
}  // namespace mrvs
