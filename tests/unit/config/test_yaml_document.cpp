#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "mrvs/config/yaml_document.h"
#include "mrvs/test/temp_dir.h"

namespace mrvs::config {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

TEST(YamlDocument, LoadsFileAndRemembersItsPath) {
  test::TempDir dir;
  const auto path = dir.write("a.yaml", "answer: 42\nlist: [1, 2]\n");
  auto doc = load_yaml_file(path);
  ASSERT_TRUE(doc.ok()) << doc.status();
  EXPECT_EQ(doc->root["answer"].as<int>(), 42);
  EXPECT_EQ(doc->root["list"].size(), 2u);
  EXPECT_EQ(doc->path, path);
  EXPECT_EQ(doc->name, path.string());
  EXPECT_EQ(doc->base_dir(), dir.path());
}

TEST(YamlDocument, MissingFileIsNotFoundAndNamesThePath) {
  test::TempDir dir;
  const auto path = dir / "no_such_file.yaml";
  auto doc = load_yaml_file(path);
  ASSERT_FALSE(doc.ok());
  EXPECT_EQ(doc.status().code(), absl::StatusCode::kNotFound);
  EXPECT_THAT(std::string(doc.status().message()), HasSubstr(path.string()));
}

TEST(YamlDocument, FolderIsRejected) {
  test::TempDir dir;
  auto doc = load_yaml_file(dir.path());
  ASSERT_FALSE(doc.ok());
  EXPECT_THAT(std::string(doc.status().message()), HasSubstr(dir.path().string()));
}

TEST(YamlDocument, AcceptsOpenCvHeaderAndKeepsLineNumbers) {
  test::TempDir dir;
  const auto path = dir.write("cv.yaml", "%YAML:1.0\n# comment\nvalue: [1, 2,\n        3]\n");
  auto doc = load_yaml_file(path);
  ASSERT_TRUE(doc.ok()) << doc.status();
  ASSERT_EQ(doc->root["value"].size(), 3u);
  EXPECT_EQ(doc->root["value"][2].as<int>(), 3);
  // "value" is on line 3 of the file, its list starts at column 8.
  EXPECT_EQ(location(*doc, doc->root["value"]), path.string() + ":3:8");
}

TEST(YamlDocument, SyntaxErrorNamesFileLineAndColumn) {
  test::TempDir dir;
  // Line 3 holds an unterminated flow list.
  const auto path = dir.write("bad.yaml", "a: 1\nb: 2\nc: [1, 2\nd: 4\n");
  auto doc = load_yaml_file(path);
  ASSERT_FALSE(doc.ok());
  EXPECT_EQ(doc.status().code(), absl::StatusCode::kInvalidArgument);
  const std::string message(doc.status().message());
  EXPECT_THAT(message, StartsWith(path.string() + ":"));
  EXPECT_THAT(message, HasSubstr("YAML syntax error"));
  // yaml-cpp detects the problem on line 3 or when it reaches line 4.
  EXPECT_TRUE(message.find(path.string() + ":3:") == 0 || message.find(path.string() + ":4:") == 0)
      << message;
}

TEST(YamlDocument, SyntaxErrorOnBadIndentationReportsItsLine) {
  auto doc = parse_yaml_string("a:\n  b: 1\n c: 2\n", "mem.yaml");
  ASSERT_FALSE(doc.ok());
  EXPECT_THAT(std::string(doc.status().message()), StartsWith("mem.yaml:3:"));
}

TEST(YamlDocument, LocationAndNodeText) {
  auto doc = parse_yaml_string("top:\n  key: value\n  list: [1, 2, 3]\n", "x.yaml");
  ASSERT_TRUE(doc.ok()) << doc.status();
  const YAML::Node key = find_node(*doc, "top.key");
  ASSERT_TRUE(key.IsDefined());
  EXPECT_EQ(location(*doc, key), "x.yaml:2:8");
  EXPECT_EQ(node_text(key), "value");
  EXPECT_EQ(node_text(find_node(*doc, "top.list")), "[1, 2, 3]");
  EXPECT_FALSE(find_node(*doc, "top.missing").IsDefined());
  EXPECT_FALSE(find_node(*doc, "top.key.deeper").IsDefined());
  EXPECT_EQ(expected_error(*doc, key, "top.key", "a number"),
            "x.yaml:2:8: key 'top.key': expected a number, got 'value'");
}

TEST(YamlDocument, LongNodeTextIsShortened) {
  std::string list = "v: [";
  for (int i = 0; i < 100; ++i) list += (i == 0 ? "" : ", ") + std::to_string(i);
  auto doc = parse_yaml_string(list + "]\n");
  ASSERT_TRUE(doc.ok()) << doc.status();
  const std::string text = node_text(doc->root["v"]);
  EXPECT_LE(text.size(), 80u);
  EXPECT_THAT(text, StartsWith("[0, 1, 2"));
  EXPECT_THAT(text, ::testing::EndsWith("..."));
}

TEST(YamlDocument, OverridesSetNestedKeysAndCreateSections) {
  auto doc = parse_yaml_string("tracker:\n  max_features: 100\n");
  ASSERT_TRUE(doc.ok());
  const YamlDocument before = *doc;  // shares the tree until apply_overrides clones it
  ASSERT_TRUE(apply_overrides(*doc, {"tracker.max_features=300", "new.section.value = [1, 2]"}).ok());
  EXPECT_EQ(doc->root["tracker"]["max_features"].as<int>(), 300);
  ASSERT_TRUE(doc->root["new"]["section"]["value"].IsSequence());
  EXPECT_EQ(doc->root["new"]["section"]["value"][1].as<int>(), 2);
  EXPECT_EQ(before.root["tracker"]["max_features"].as<int>(), 100);
  EXPECT_EQ(location(*doc, find_node(*doc, "tracker.max_features"), "tracker.max_features"),
            "override 'tracker.max_features=300'");
  EXPECT_EQ(location(*doc, find_node(*doc, "new.section.value"), "new.section.value"),
            "override 'new.section.value = [1, 2]'");
}

TEST(YamlDocument, OverridesOnEmptyDocument) {
  auto doc = parse_yaml_string("");
  ASSERT_TRUE(doc.ok());
  ASSERT_TRUE(apply_overrides(*doc, {"a.b=c"}).ok());
  EXPECT_EQ(doc->root["a"]["b"].as<std::string>(), "c");
}

TEST(YamlDocument, MalformedOverridesAreErrorsAndLeaveTheDocumentUnchanged) {
  auto doc = parse_yaml_string("a:\n  b: 1\n");
  ASSERT_TRUE(doc.ok());
  const Status s = apply_overrides(*doc, {"a.b=2", "no_equals_sign", "=5", "a..c=1", "a.b.c=1", "x=[1, 2"});
  ASSERT_FALSE(s.ok());
  const std::string message(s.message());
  EXPECT_THAT(message, HasSubstr("override 'no_equals_sign': expected 'dotted.key=value'"));
  EXPECT_THAT(message, HasSubstr("override '=5': empty key"));
  EXPECT_THAT(message, HasSubstr("override 'a..c=1': empty part"));
  EXPECT_THAT(message, HasSubstr("override 'a.b.c=1': 'a.b' is not a section"));
  EXPECT_THAT(message, HasSubstr("override 'x=[1, 2': the value is not valid YAML"));
  EXPECT_EQ(doc->root["a"]["b"].as<int>(), 1);  // the valid "a.b=2" was not applied either
  EXPECT_TRUE(doc->overrides.empty());
}

TEST(YamlDocument, ResolvesPathsAgainstTheFileFolder) {
  test::TempDir dir;
  const auto path = dir.write("tuning/euroc.yaml", "calibration: ../euroc/camchain.yaml\n");
  auto doc = load_yaml_file(path);
  ASSERT_TRUE(doc.ok()) << doc.status();
  EXPECT_EQ(resolve_path(*doc, doc->root["calibration"].as<std::string>()),
            (dir.path() / "euroc/camchain.yaml").lexically_normal());
  EXPECT_EQ(resolve_path(*doc, "/abs/file.yaml"), std::filesystem::path("/abs/file.yaml"));
  EXPECT_TRUE(resolve_path(*doc, "x.yaml").is_absolute());
}

}  // namespace
}  // namespace mrvs::config
