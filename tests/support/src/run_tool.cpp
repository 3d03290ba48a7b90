#include "mrvs/test/run_tool.h"

#include <sys/wait.h>

#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

namespace mrvs::test {

RunResult run_tool(const std::filesystem::path& executable, const std::string& args) {
  const std::string command = quoted(executable) + " " + args + " 2>&1";
  RunResult result;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) {
    ADD_FAILURE() << "popen failed: " << command;
    return result;
  }
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof(buffer), pipe)) > 0) result.output.append(buffer, n);
  const int status = pclose(pipe);
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return result;
}

std::string quoted(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

double value_of(const std::string& text, const std::string& key) {
  const std::string needle = "\n" + key + ": ";
  const std::size_t pos = ("\n" + text).find(needle);
  if (pos == std::string::npos) return std::nan("");
  return std::stod(text.substr(pos + needle.size() - 1));
}

}  // namespace mrvs::test
