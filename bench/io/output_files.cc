#include "bench/io/output_files.h"

#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <thread>
#include <vector>

#include "bench/report/output_mark.h"
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

std::function<void(int)>& InterruptHandler() {
  static std::function<void(int)> handler;
  return handler;
}

void WaitForInterrupts(sigset_t set) {
  for (;;) {
    int sig = 0;
    if (sigwait(&set, &sig) != 0) return;
    // The handler runs under the lock, so SetInterruptHandler({}) waits for one in progress:
    // what it refers to may end right after.
    std::unique_lock<std::recursive_mutex> lock(CleanupMutex());
    const std::function<void(int)> handler = InterruptHandler();
    if (!handler) {
      lock.unlock();
      EndBySignal(sig);
    }
    handler(sig);
  }
}

std::string Quoted(const std::string& s) { return "'" + s + "'"; }

}  // namespace

namespace {

// The process's verb and inputs (SetOutputVerb, NoteInput), guarded by one mutex: the planner's
// threads may read models while the main thread checks an output.
std::mutex& StateMutex() {
  static std::mutex m;
  return m;
}
std::string& VerbState() {
  static std::string verb = "twinbench";
  return verb;
}
struct NotedInput {
  fs::path path;  // resolved (absolute, symbolic links followed where they exist)
  std::string as_given;
  bool is_folder;
};
std::vector<NotedInput>& Inputs() {
  static std::vector<NotedInput> inputs;
  return inputs;
}

// Absolute, normalised, symbolic links resolved as far as the path exists; no empty last
// component (a trailing '/').
fs::path Resolved(const std::string& path) {
  std::error_code ec;
  fs::path p = fs::weakly_canonical(fs::absolute(path, ec), ec);
  if (ec) p = fs::absolute(path, ec).lexically_normal();
  if (!p.has_filename() && p.has_parent_path() && p != p.root_path()) p = p.parent_path();
  return p;
}

// True when `inner` is `outer` or lies below it (both Resolved).
bool IsWithin(const fs::path& inner, const fs::path& outer) {
  auto i = inner.begin();
  for (auto o = outer.begin(); o != outer.end(); ++o, ++i) {
    if (i == inner.end() || *i != *o) return false;
  }
  return true;
}

// The verb named by the mark in `dir`, or "" when there is no readable mark.
std::string MarkedVerb(const fs::path& dir) {
  const fs::path marker = dir / kOutputMarker;
  std::error_code ec;
  if (!fs::is_regular_file(fs::symlink_status(marker, ec))) return "";
  std::ifstream in(marker, std::ios::binary);
  std::string text(4096, '\0');
  in.read(&text[0], static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  return OutputMarkVerb(text);
}

// "a FIFO", "a device", ... for an existing path that is neither a folder nor a regular file.
std::string KindOf(const fs::file_status& st) {
  switch (st.type()) {
    case fs::file_type::symlink: return "a symbolic link";
    case fs::file_type::fifo: return "a FIFO";
    case fs::file_type::socket: return "a socket";
    case fs::file_type::block: return "a block device";
    case fs::file_type::character: return "a character device";
    case fs::file_type::directory: return "a folder";
    case fs::file_type::regular: return "a file";
    default: return "not a regular file";
  }
}

// Refuses `path` (an output folder, or a file when `is_file`) that equals or contains an input,
// or lies inside an input folder.
void CheckAgainstInputs(const std::string& path, const std::string& option, bool is_file) {
  const fs::path out = Resolved(path);
  std::lock_guard<std::mutex> lock(StateMutex());
  for (const NotedInput& in : Inputs()) {
    if (IsWithin(in.path, out)) {
      throw InputError(option, Quoted(path) + (in.path == out ? " is" : " contains") +
                                   " the input " + Quoted(in.as_given) +
                                   (is_file ? "; twinbench never writes over its inputs"
                                            : "; the run would replace it (name another folder)"));
    }
    if (in.is_folder && IsWithin(out, in.path)) {
      throw InputError(option, Quoted(path) + " lies inside the input folder " +
                                   Quoted(in.as_given) + "; name a folder outside it");
    }
  }
}

// The checks of ValidateOutputFolder; `staged`: the output is published by renaming a staging
// folder PATH.partial onto PATH (the old PATH kept aside as PATH.old until then).
void CheckOutputFolder(const std::string& path, const std::string& option,
                       const std::string& verb_in, bool staged) {
  const std::string verb = verb_in.empty() ? OutputVerb() : verb_in;
  if (path.empty()) throw InputError(option, "expected a folder path, got ''");
  std::string trimmed = path;
  while (trimmed.size() > 1 && trimmed.back() == '/') trimmed.pop_back();
  const fs::path p(trimmed);
  const std::string last = p.filename().string();
  if (trimmed == "/" || last == "." || last == ".." || last.empty()) {
    throw InputError(option, "expected a new folder or one twinbench wrote, got " +
                                 Quoted(path) + " (name a new folder)");
  }
  const auto refuse_existing = [&](const fs::path& q, const std::string& what) {
    std::error_code ec;
    // A staged output replaces PATH by a rename, which would replace a link itself; a folder
    // written in place may be reached through a link (a study's work/plans).
    const fs::file_status st = staged ? fs::symlink_status(q, ec) : fs::status(q, ec);
    if (!fs::exists(st)) return;
    if (fs::is_symlink(st)) {
      throw InputError(option, Quoted(q.string()) + " is a symbolic link; twinbench writes only "
                               "folders it made (name the folder itself, or a new one)");
    }
    if (!fs::is_directory(st)) {
      throw InputError(option, Quoted(q.string()) + " exists and is " + KindOf(st) +
                                   ", not a folder" + what);
    }
    if (fs::is_empty(q, ec)) return;
    const std::string marked = MarkedVerb(q);
    if (marked == verb) return;
    if (!marked.empty()) {
      throw InputError(option, Quoted(q.string()) + " holds the output of `twinbench " + marked +
                                   "`, not of `twinbench " + verb + "`" + what +
                                   "; name another folder");
    }
    throw InputError(option, Quoted(q.string()) + " is a folder twinbench did not write (no " +
                                 kOutputMarker + " mark in it and not empty)" + what +
                                 "; twinbench writes only new, empty or its own folders: name "
                                 "a new folder");
  };
  refuse_existing(p, "");
  if (staged) {
    for (const char* suffix : {".partial", ".old"}) {
      refuse_existing(fs::path(trimmed + suffix),
                      std::string(" (twinbench stages its output under that name)"));
    }
  }
  std::error_code ec;
  const fs::path parent = p.parent_path();
  if (!parent.empty()) {
    const fs::file_status ps = fs::status(parent, ec);
    if (fs::exists(ps) && !fs::is_directory(ps)) {
      throw InputError(option, "the parent " + Quoted(parent.string()) + " of " + Quoted(path) +
                                   " is not a folder");
    }
  }
  CheckAgainstInputs(trimmed, option, false);
}

void WriteMarkFile(const fs::path& dir, const std::string& verb) {
  const fs::path tmp = dir / (std::string(kOutputMarker) + ".partial");
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    f << OutputMarkText(verb);
    f.flush();
    if (!f) throw InputError(dir.string(), "cannot write the output mark " + tmp.string());
  }
  std::error_code ec;
  fs::rename(tmp, dir / kOutputMarker, ec);
  if (ec) throw InputError(dir.string(), "cannot write the output mark: " + ec.message());
}

}  // namespace

void SetOutputVerb(const std::string& verb) {
  std::lock_guard<std::mutex> lock(StateMutex());
  VerbState() = verb;
}

const std::string& OutputVerb() {
  std::lock_guard<std::mutex> lock(StateMutex());
  return VerbState();
}

void NoteInput(const std::string& path, bool is_folder) {
  if (path.empty()) return;
  NotedInput in{Resolved(path), path, is_folder};
  std::lock_guard<std::mutex> lock(StateMutex());
  for (const NotedInput& have : Inputs()) {
    if (have.path == in.path) return;
  }
  Inputs().push_back(std::move(in));
}

bool IsMarkedFolder(const std::string& dir, const std::string& verb) {
  std::error_code ec;
  return fs::is_directory(fs::symlink_status(dir, ec)) && MarkedVerb(dir) == verb;
}

void MarkFolder(const std::string& dir, const std::string& verb) {
  WriteMarkFile(dir, verb.empty() ? OutputVerb() : verb);
}

bool PathIsWithin(const std::string& inner, const std::string& outer) {
  return IsWithin(Resolved(inner), Resolved(outer));
}

void ValidateOutputFolder(const std::string& path, const std::string& option,
                          const std::string& verb, bool staged) {
  CheckOutputFolder(path, option, verb, staged);
}

void ClaimOutputFolder(const std::string& dir, const std::string& option,
                       const std::string& verb_in) {
  const std::string verb = verb_in.empty() ? OutputVerb() : verb_in;
  ValidateOutputFolder(dir, option, verb, false);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw InputError(option, "cannot create " + Quoted(dir) + ": " + ec.message());
  if (MarkedVerb(dir) != verb) WriteMarkFile(dir, verb);
}

void ValidateOutputFile(const std::string& path, const std::string& option,
                        const std::vector<std::string>& signatures) {
  if (path.empty()) throw InputError(option, "expected a file path, got ''");
  if (path.back() == '/') {
    throw InputError(option, "expected a file path, got the folder " + Quoted(path));
  }
  const fs::path p(path);
  std::error_code ec;
  const fs::file_status st = fs::symlink_status(p, ec);
  if (fs::is_directory(st)) throw InputError(option, Quoted(path) + " is a folder");
  const fs::path parent = p.parent_path().empty() ? fs::path(".") : p.parent_path();
  if (!fs::is_directory(parent, ec)) {
    throw InputError(option, "the folder " + Quoted(parent.string()) + " of " + Quoted(path) +
                                 " does not exist");
  }
  if (access(parent.c_str(), W_OK | X_OK) != 0) {
    throw InputError(option, "the folder " + Quoted(parent.string()) + " of " + Quoted(path) +
                                 " cannot be written");
  }
  if (fs::exists(st)) {
    if (!fs::is_regular_file(st)) {
      throw InputError(option, Quoted(path) + " exists and is " + KindOf(st) +
                                   "; twinbench writes only regular files it made");
    }
    if (signatures.empty()) {
      throw InputError(option, Quoted(path) + " exists; twinbench writes only a new file here "
                                              "(name a new file)");
    }
    std::ifstream in(path, std::ios::binary);
    std::string head(4096, '\0');
    in.read(&head[0], static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<std::size_t>(in.gcount()));
    const bool ours = std::any_of(signatures.begin(), signatures.end(), [&](const std::string& s) {
      return head.find(s) != std::string::npos;
    });
    if (!ours) {
      throw InputError(option, Quoted(path) + " exists and was not written by twinbench (no '" +
                                   signatures.front() + "' in it); twinbench replaces only files "
                                   "it wrote (name a new file)");
    }
  }
  CheckAgainstInputs(path, option, true);
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

void SetInterruptHandler(std::function<void(int)> handler) {
  std::lock_guard<std::recursive_mutex> lock(CleanupMutex());
  InterruptHandler() = std::move(handler);
}

void EndBySignal(int sig) {
  // The lock stays held, so nothing is registered or published any more.
  CleanupMutex().lock();
  for (const std::string& p : CleanupPaths()) RemoveQuietly(p);
  CleanupPaths().clear();
  // End the process by the signal itself (default action), so that callers see it.
  signal(sig, SIG_DFL);
  sigset_t one;
  sigemptyset(&one);
  sigaddset(&one, sig);
  pthread_sigmask(SIG_UNBLOCK, &one, nullptr);
  raise(sig);
  _exit(128 + sig);
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

bool WriteAll(int fd, const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      if (n == 0) errno = EIO;
      return false;
    }
    done += static_cast<std::size_t>(n);
  }
  return true;
}

void WriteTextFile(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
  f.flush();
  if (!f) throw InputError(path, "writing the file failed (output folder not writable?)");
}

}  // namespace twin
