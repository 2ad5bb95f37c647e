// Runs the built twinbench binary (TWINBENCH_BIN) for CLI tests: exit code and the combined
// stdout and stderr.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <memory>
#include <string>

namespace twin::testing {

struct CliRun {
  int code;            ///< exit code, -1 if the process did not exit normally
  std::string output;  ///< stdout and stderr
};

inline CliRun Twinbench(const std::string& args) {
  const std::string cmd = std::string(TWINBENCH_BIN) + " " + args + " 2>&1";
  std::unique_ptr<FILE, int (*)(FILE*)> pipe(popen(cmd.c_str(), "r"), pclose);
  CliRun r{-1, ""};
  if (!pipe) return r;
  std::array<char, 512> buf;
  while (fgets(buf.data(), buf.size(), pipe.get())) r.output += buf.data();
  const int status = pclose(pipe.release());
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace twin::testing
