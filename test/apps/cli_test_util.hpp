// Running the real fgcal executable from a test, as a user's shell would:
// its exit code, and what it printed on stdout and stderr.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "apps_test_util.hpp"

namespace fgcal::apps::test {

/// `s` in single quotes for /bin/sh, its own single quotes escaped.
inline std::string quoted(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += (c == '\'') ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

struct CliRun {
  int exit_code = -1;  ///< -1 when the command did not exit normally
  std::string out, err;
  std::string command;  ///< as run, without the redirections
};

/// Runs `executable args` through the shell; stdout and stderr go to files
/// under `scratch` (named per process and call, so that suites running at
/// once never share them), read back and removed.
inline CliRun runCommand(const std::string& executable, const std::string& args, const std::filesystem::path& scratch) {
  static std::atomic<int> counter{0};
  const std::string tag = std::to_string(::getpid()) + "_" + std::to_string(counter++);
  const std::string out = (scratch / ("cli_stdout_" + tag + ".txt")).string();
  const std::string err = (scratch / ("cli_stderr_" + tag + ".txt")).string();
  CliRun r;
  r.command = quoted(executable) + " " + args;
  const int status = std::system((r.command + " >" + quoted(out) + " 2>" + quoted(err)).c_str());
  r.exit_code = (status != -1 && WIFEXITED(status)) ? WEXITSTATUS(status) : -1;
  r.out = readFile(out);
  r.err = readFile(err);
  std::error_code ec;
  std::filesystem::remove(out, ec);
  std::filesystem::remove(err, ec);
  return r;
}

}  // namespace fgcal::apps::test
