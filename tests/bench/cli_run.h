// Runs the built twinbench binary (TWINBENCH_BIN) for CLI tests: exit code and the combined
// stdout and stderr; RunProcess also bounds the time and reports signals.
#pragma once

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <functional>
#include <memory>
#include <string>
#include <vector>

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

/// The outcome of RunProcess.
struct ProcessRun {
  bool exited = false;     ///< ended by exit (code valid)
  int code = -1;           ///< exit code
  int signal = 0;          ///< the signal that ended it (0: none)
  bool timed_out = false;  ///< killed after the time limit (SIGTERM, then SIGKILL)
  std::string output;      ///< stdout and stderr (the first max_output bytes)
  double seconds = 0.0;    ///< wall time
};

/// Runs argv[0] with argv (no shell) in `cwd` (empty: this one), stdin from /dev/null, for at
/// most timeout_s seconds; `on_start(pid)` runs once the child exists (may be empty).
inline ProcessRun RunProcess(const std::vector<std::string>& argv, double timeout_s,
                             const std::string& cwd = "",
                             const std::function<void(pid_t)>& on_start = {},
                             std::size_t max_output = 1 << 20) {
  ProcessRun r;
  int fds[2];
  if (pipe(fds) != 0) return r;
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    dup2(fds[1], 1);
    dup2(fds[1], 2);
    close(fds[0]);
    close(fds[1]);
    const int null = open("/dev/null", O_RDONLY);
    if (null >= 0) dup2(null, 0);
    if (!cwd.empty() && chdir(cwd.c_str()) != 0) _exit(126);
    std::vector<char*> args;
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    execv(args[0], args.data());
    _exit(127);
  }
  close(fds[1]);
  if (on_start) on_start(pid);
  fcntl(fds[0], F_SETFL, O_NONBLOCK);
  int status = 0;
  bool done = false, killed = false;
  std::chrono::steady_clock::time_point term_at{};
  char buf[4096];
  while (!done) {
    pollfd p{fds[0], POLLIN, 0};
    poll(&p, 1, 20);
    for (;;) {
      const ssize_t n = read(fds[0], buf, sizeof(buf));
      if (n <= 0) break;
      if (r.output.size() < max_output) r.output.append(buf, static_cast<std::size_t>(n));
    }
    const pid_t w = waitpid(pid, &status, WNOHANG);
    if (w == pid) {
      done = true;
      break;
    }
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (!killed && elapsed > timeout_s) {
      r.timed_out = true;
      kill(pid, SIGTERM);
      killed = true;
      term_at = std::chrono::steady_clock::now();
    } else if (killed && std::chrono::steady_clock::now() - term_at > std::chrono::seconds(5)) {
      kill(pid, SIGKILL);
    }
  }
  for (;;) {
    const ssize_t n = read(fds[0], buf, sizeof(buf));
    if (n <= 0) break;
    if (r.output.size() < max_output) r.output.append(buf, static_cast<std::size_t>(n));
  }
  close(fds[0]);
  r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (WIFEXITED(status)) {
    r.exited = true;
    r.code = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    r.signal = WTERMSIG(status);
  }
  return r;
}

/// RunProcess of the twinbench binary with `args`.
inline ProcessRun TwinbenchArgs(const std::vector<std::string>& args, double timeout_s,
                                const std::string& cwd = "",
                                const std::function<void(pid_t)>& on_start = {}) {
  std::vector<std::string> argv = {TWINBENCH_BIN};
  argv.insert(argv.end(), args.begin(), args.end());
  return RunProcess(argv, timeout_s, cwd, on_start);
}

}  // namespace twin::testing
