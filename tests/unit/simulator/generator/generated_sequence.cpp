#include "generated_sequence.h"

#include <cstdlib>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "mrvs/config/options.h"
#include "mrvs/test/shared_data.h"

namespace mrvs::sim::test {

GeneratorRequest indoor_request(const std::filesystem::path& out, double duration_s, double start_s) {
  GeneratorRequest r;
  r.profile = SceneProfile::kIndoor;
  r.trajectory = mrvs::test::euroc_groundtruth_file("V1_01_easy.txt");
  r.out = out;
  r.preset = "easy";
  r.options = default_options(SceneProfile::kIndoor);
  EXPECT_TRUE(apply_preset("easy", r.profile, r.options).ok());
  auto doc = config::load_yaml_file(MRVS_INDOOR_FIXTURE_YAML);
  EXPECT_TRUE(doc.ok()) << doc.status();
  if (doc.ok()) {
    EXPECT_TRUE(config::update_options(*doc, "", r.options).ok());
  }
  if (start_s >= 0) r.options.trajectory.window_start_s = start_s;
  if (duration_s >= 0) r.options.trajectory.window_duration_s = duration_s;
  return r;
}

namespace {

/// <MRVS_GENERATED_DATA>/<name> under CTest, else empty.
std::filesystem::path shared_sequence(const char* name) {
  const char* dir = std::getenv("MRVS_GENERATED_DATA");
  return dir != nullptr ? std::filesystem::path(dir) / name : std::filesystem::path();
}

}  // namespace

std::filesystem::path shared_indoor_sequence() { return shared_sequence("generated_indoor"); }

GeneratorRequest outdoor_gnss_request(const std::filesystem::path& out) {
  GeneratorRequest r;
  r.profile = SceneProfile::kOutdoor;
  r.out = out;
  r.preset = "easy";
  r.options = default_options(SceneProfile::kOutdoor);
  EXPECT_TRUE(apply_preset("easy", r.profile, r.options).ok());
  auto doc = config::load_yaml_file(MRVS_OUTDOOR_GNSS_FIXTURE_YAML);
  EXPECT_TRUE(doc.ok()) << doc.status();
  if (doc.ok()) {
    EXPECT_TRUE(config::update_options(*doc, "", r.options).ok());
  }
  return r;
}

std::filesystem::path shared_outdoor_gnss_sequence() { return shared_sequence("generated_outdoor_gnss"); }

std::map<std::string, std::string> read_tree(const std::filesystem::path& root) {
  std::map<std::string, std::string> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(root)) {
    if (!entry.is_regular_file()) continue;
    std::ifstream in(entry.path(), std::ios::binary);
    std::stringstream bytes;
    bytes << in.rdbuf();
    files[std::filesystem::relative(entry.path(), root).string()] = bytes.str();
  }
  return files;
}

std::vector<std::string> list_dir(const std::filesystem::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) names.push_back(entry.path().filename());
  return names;
}

}  // namespace mrvs::sim::test
