#include "mrvs/test/run_tool.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <thread>

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

BackgroundTool::BackgroundTool(const std::filesystem::path& executable, const std::string& args,
                               const std::filesystem::path& log) {
  const std::string command = "exec " + quoted(executable) + " " + args + " >" + quoted(log) + " 2>&1";
  pid_ = fork();
  if (pid_ == 0) {
    execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  if (pid_ < 0) ADD_FAILURE() << "fork failed: " << command;
}

BackgroundTool::~BackgroundTool() { stop(); }

bool BackgroundTool::running() {
  if (pid_ <= 0) return false;
  int status = 0;
  const pid_t r = waitpid(pid_, &status, WNOHANG);
  if (r == 0) return true;
  status_ = (r == pid_ && WIFEXITED(status)) ? WEXITSTATUS(status) : -1;
  pid_ = -1;
  return false;
}

int BackgroundTool::stop(double grace_s) {
  if (!running()) return status_;
  kill(pid_, SIGTERM);
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(grace_s);
  while (running() && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (running()) kill_now();
  return status_;
}

void BackgroundTool::kill_now() {
  if (!running()) return;
  kill(pid_, SIGKILL);
  waitpid(pid_, nullptr, 0);
  pid_ = -1;
  status_ = -1;
}

std::string quoted(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

double value_of(const std::string& text, const std::string& key) {
  const std::string needle = "\n" + key + ": ";
  const std::size_t pos = ("\n" + text).find(needle);
  if (pos == std::string::npos) return std::nan("");
  return std::stod(text.substr(pos + needle.size() - 1));
}

}  // namespace mrvs::test
