#include "bench/io/output_files.h"

#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <thread>
#include <vector>

#include "calib/common/errors.h"

namespace twin {
namespace fs = std::filesystem;
namespace {

// Longest name accepted in a file name: robot names prefix parameter names too, and 64
// characters keep file names far below NAME_MAX (255) with any prefix and suffix we add.
constexpr std::size_t kMaxNameLength = 64;

// The interrupt clean-up: registered paths, guarded by one recursive mutex (PublishDirectory
// unregisters while it holds the lock).
std::recursive_mutex& CleanupMutex() {
  static std::recursive_mutex m;
  return m;
}
std::vector<std::string>& CleanupPaths() {
  static std::vector<std::string> paths;
  return paths;
}

// Removes `path` (a folder tree or a file). The main thread may still be writing a file into
// a folder being removed, so a few rounds are allowed before giving up.
void RemoveQuietly(const std::string& path) {
  for (int round = 0; round < 20; ++round) {
    std::error_code ec;
    fs::remove_all(path, ec);
    if (!fs::exists(fs::symlink_status(path, ec))) return;
  }
}

void WaitForInterrupts(sigset_t set) {
  int sig = 0;
  if (sigwait(&set, &sig) != 0) return;
  {
    std::lock_guard<std::recursive_mutex> lock(CleanupMutex());
    for (const std::string& p : CleanupPaths()) RemoveQuietly(p);
    CleanupPaths().clear();
    // End the process by the signal itself (default action), so that callers see it; the
    // lock stays held, so nothing is registered or published any more.
    signal(sig, SIG_DFL);
    sigset_t one;
    sigemptyset(&one);
    sigaddset(&one, sig);
    pthread_sigmask(SIG_UNBLOCK, &one, nullptr);
    raise(sig);
    _exit(128 + sig);
  }
}

std::string Quoted(const std::string& s) { return "'" + s + "'"; }

}  // namespace

void ValidateOutputFolder(const std::string& path, const std::string& option) {
  if (path.empty()) throw InputError(option, "expected a folder path, got ''");
  std::string trimmed = path;
  while (trimmed.size() > 1 && trimmed.back() == '/') trimmed.pop_back();
  const fs::path p(trimmed);
  const std::string last = p.filename().string();
  if (trimmed == "/" || last == "." || last == ".." || last.empty()) {
    throw InputError(option, "expected a folder to create or replace, got " + Quoted(path) +
                                 " (the run replaces the whole folder; name a new one)");
  }
  std::error_code ec;
  const fs::file_status st = fs::status(p, ec);
  if (fs::exists(st) && !fs::is_directory(st)) {
    throw InputError(option, Quoted(path) + " exists and is not a folder");
  }
  const fs::path parent = p.parent_path();
  if (!parent.empty()) {
    const fs::file_status ps = fs::status(parent, ec);
    if (fs::exists(ps) && !fs::is_directory(ps)) {
      throw InputError(option, "the parent " + Quoted(parent.string()) + " of " + Quoted(path) +
                                   " is not a folder");
    }
  }
}

void ValidateOutputFile(const std::string& path, const std::string& option) {
  if (path.empty()) throw InputError(option, "expected a file path, got ''");
  if (path.back() == '/') throw InputError(option, "expected a file path, got the folder " +
                                                       Quoted(path));
  const fs::path p(path);
  std::error_code ec;
  if (fs::is_directory(p, ec)) throw InputError(option, Quoted(path) + " is a folder");
  const fs::path parent = p.parent_path();
  if (!parent.empty() && !fs::is_directory(parent, ec)) {
    throw InputError(option, "the folder " + Quoted(parent.string()) + " of " + Quoted(path) +
                                 " does not exist");
  }
}

bool IsSafeName(const std::string& name) {
  const auto alpha = [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_';
  };
  if (name.empty() || name.size() > kMaxNameLength || !alpha(name[0])) return false;
  return std::all_of(name.begin(), name.end(),
                     [&](char c) { return alpha(c) || (c >= '0' && c <= '9'); });
}

void RequireSafeName(const std::string& name, const std::string& where,
                     const std::string& what) {
  if (IsSafeName(name)) return;
  throw InputError(where, "expected a " + what + " of 1 to " + std::to_string(kMaxNameLength) +
                              " letters, digits and '_' not starting with a digit (it becomes "
                              "part of file names), got " + Quoted(name));
}

void InstallInterruptCleanup() {
  static std::once_flag once;
  std::call_once(once, [] {
    sigset_t set;
    sigemptyset(&set);
    sigaddset(&set, SIGINT);
    sigaddset(&set, SIGTERM);
    sigaddset(&set, SIGHUP);
    pthread_sigmask(SIG_BLOCK, &set, nullptr);
    std::thread(WaitForInterrupts, set).detach();
  });
}

void RegisterCleanupPath(const std::string& path) {
  std::lock_guard<std::recursive_mutex> lock(CleanupMutex());
  CleanupPaths().push_back(path);
}

void UnregisterCleanupPath(const std::string& path) {
  std::lock_guard<std::recursive_mutex> lock(CleanupMutex());
  std::vector<std::string>& v = CleanupPaths();
  v.erase(std::remove(v.begin(), v.end(), path), v.end());
}

void DiscardStaging(const std::string& path) {
  std::lock_guard<std::recursive_mutex> lock(CleanupMutex());
  RemoveQuietly(path);
  UnregisterCleanupPath(path);
}

namespace internal {
void LockCleanup() { CleanupMutex().lock(); }
void UnlockCleanup() { CleanupMutex().unlock(); }
}  // namespace internal

void WriteTextFile(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
  f.flush();
  if (!f) throw InputError(path, "writing the file failed (output folder not writable?)");
}

}  // namespace twin
