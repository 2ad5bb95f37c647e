#include "bench/runs/study_run.h"

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/personality.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <mutex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "bench/io/calibration_config.h"
#include "bench/io/content_hash.h"
#include "bench/io/model_loader.h"
#include "bench/io/output_files.h"
#include "bench/io/scenario.h"
#include "bench/report/study_file.h"
#include "bench/report/study_summary_files.h"
#include "bench/report/trial_record.h"
#include "bench/report/trial_records_file.h"
#include "bench/runs/handclasp_run.h"
#include "bench/runs/tracker_run.h"
#include "calib/common/clock.h"
#include "calib/common/cpus.h"
#include "calib/common/errors.h"

namespace twin {
namespace fs = std::filesystem;
namespace {

// The signal that interrupted the study (0: none); set by the interrupt handler of RunStudy.
std::atomic<int> g_interrupted{0};

std::string SelfExecutable() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw InputError("twinbench study", "cannot find its own executable: " + ec.message());
  return p.string();
}

std::string Duration(double s) {
  if (!(s >= 0) || s > 1e7) return "?";
  char buf[32];
  const long t = static_cast<long>(s + 0.5);
  if (t >= 3600) {
    std::snprintf(buf, sizeof(buf), "%ldh%02ldm", t / 3600, (t / 60) % 60);
  } else if (t >= 60) {
    std::snprintf(buf, sizeof(buf), "%ldm%02lds", t / 60, t % 60);
  } else {
    std::snprintf(buf, sizeof(buf), "%lds", t);
  }
  return buf;
}

// The reason a trial process gave: its last "error: ..." line (InputError), else its last
// "internal error: ..." line, else its last non-empty line.
std::string ReasonFromLog(const std::string& log_path) {
  std::ifstream in(log_path);
  std::string line, error, internal, last;
  while (std::getline(in, line)) {
    if (line.empty()) continue;
    last = line;
    if (line.rfind("error: ", 0) == 0) error = line.substr(7);
    if (line.rfind("internal error: ", 0) == 0) internal = line;
  }
  std::string r = !error.empty() ? error : !internal.empty() ? internal : last;
  if (r.size() > 400) r = r.substr(0, 400) + "...";
  return r;
}

// A trial process: `executable run SCENARIO --trial t ...` with stdout and stderr to `log`,
// killed (SIGKILL) when the study process dies.
pid_t SpawnTrial(const std::string& executable, const std::vector<std::string>& args,
                 const std::string& cwd, const std::vector<std::string>& env,
                 const std::string& log) {
  std::vector<char*> argv;
  argv.push_back(const_cast<char*>(executable.c_str()));
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  std::vector<char*> envp;
  for (const std::string& e : env) envp.push_back(const_cast<char*>(e.c_str()));
  envp.push_back(nullptr);
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error(std::string("fork failed: ") + std::strerror(errno));
  if (pid > 0) return pid;
  // Child: only async-signal-safe calls until exec.
  prctl(PR_SET_PDEATHSIG, SIGKILL);
  if (getppid() != parent) _exit(127);  // the study died before prctl
  // The same address layout in every trial process. The known layout dependence (ATLAS's BLAS
  // under cv::calibrateCamera, about 1e-6 px in the intrinsics) is gone since every program
  // links the reference BLAS (cmake/ReferenceBlas.cmake, checked by a test); this stays as a
  // second guard for any other address-dependent kernel. Where personality(2) is not allowed
  // the trial runs randomized.
  const int persona = personality(0xffffffff);
  if (persona != -1) personality(static_cast<unsigned long>(persona) | ADDR_NO_RANDOMIZE);
  signal(SIGINT, SIG_DFL);
  signal(SIGTERM, SIG_DFL);
  const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd >= 0) {
    dup2(fd, STDOUT_FILENO);
    dup2(fd, STDERR_FILENO);
    close(fd);
  }
  const int devnull = open("/dev/null", O_RDONLY);
  if (devnull >= 0) {
    dup2(devnull, STDIN_FILENO);
    close(devnull);
  }
  if (chdir(cwd.c_str()) != 0) _exit(127);
  execve(executable.c_str(), argv.data(), envp.data());
  _exit(127);
}

// The parts of a trial process in flight.
struct Running {
  int trial = 0;
  Clock::time_point start;
  std::string out, log;
};

class Progress {
 public:
  Progress(bool enabled, int total, int recorded_before)
      : enabled_(enabled), tty_(isatty(STDERR_FILENO) == 1), total_(total),
        done_(recorded_before), start_(Clock::now()) {}

  void Finished(int trial, const std::string& status, double wall_s, int running) {
    ++done_;
    ++done_now_;
    if (status != "ok") ++failed_;
    if (!enabled_) return;
    const double rate = done_now_ / std::max(1e-9, SecondsSince(start_));  // trials per second
    const double eta = (total_ - done_) / std::max(1e-9, rate);
    if (tty_) {
      Bar(running, eta);
    } else {
      std::fprintf(stderr, "study: trial %d %s in %.1f s; %d/%d done, %d failed, %d running, "
                   "ETA %s\n", trial, status.c_str(), wall_s, done_, total_, failed_, running,
                   done_ < total_ ? Duration(eta).c_str() : "0s");
    }
  }
  void Started(int running) {
    if (enabled_ && tty_) Bar(running, done_now_ > 0 ? -2 : -1);
  }
  void End() {
    if (enabled_ && tty_) std::fprintf(stderr, "\n");
  }
  int failed() const { return failed_; }

 private:
  void Bar(int running, double eta) {
    const int width = 30;
    const int filled = total_ > 0 ? width * done_ / total_ : width;
    std::string bar(filled, '#');
    bar += std::string(width - filled, '.');
    std::string eta_text = eta == -1 ? "?" : Duration(eta);
    if (eta == -2) eta_text = last_eta_;
    last_eta_ = eta_text;
    std::fprintf(stderr, "\rstudy [%s] %d/%d done, %d failed, %d running, ETA %s   ",
                 bar.c_str(), done_, total_, failed_, running, eta_text.c_str());
    std::fflush(stderr);
  }

  bool enabled_, tty_;
  int total_, done_, done_now_ = 0, failed_ = 0;
  Clock::time_point start_;
  std::string last_eta_ = "?";
};

// Refuses a folder that holds another scenario's or another shard's study; writes study.json.
void CheckStudyFile(const fs::path& path, const StudyFile& wanted) {
  if (const std::optional<StudyFileIdentity> have = ReadStudyFile(path.string())) {
    if (have->scenario_hash.value_or("") != wanted.scenario_hash) {
      throw InputError(path.string(),
                       "the folder holds a study of another scenario (hash " +
                           have->scenario_hash.value_or("?") + ", this one " +
                           wanted.scenario_hash + "); choose another --out");
    }
    if (have->shard.value_or("") != wanted.shard) {
      throw InputError(path.string(), "the folder holds shard " + have->shard.value_or("?") +
                                          ", not " + wanted.shard + "; choose another --out");
    }
  }
  WriteFileAtomically(path.string(), StudyFileText(wanted));
}

}  // namespace

void ParseShard(const std::string& text, int* index, int* count) {
  const std::size_t slash = text.find('/');
  auto number = [&](const std::string& s) {
    if (s.empty() || s.size() > 9 || s.find_first_not_of("0123456789") != std::string::npos) {
      throw InputError("--shard", "expected I/N with whole numbers 0 <= I < N, got '" + text + "'");
    }
    return std::stoi(s);
  };
  if (slash == std::string::npos) {
    throw InputError("--shard", "expected I/N with whole numbers 0 <= I < N, got '" + text + "'");
  }
  *index = number(text.substr(0, slash));
  *count = number(text.substr(slash + 1));
  if (*count < 1 || *index >= *count) {
    throw InputError("--shard", "expected I/N with whole numbers 0 <= I < N, got '" + text + "'");
  }
  if (*count > kMaxStudyShards) {
    throw InputError("--shard", "expected at most " + std::to_string(kMaxStudyShards) +
                                    " shards, got '" + text + "'");
  }
}

void ValidateStudyOptions(const StudyOptions& o) {
  if (o.trials < 1 || o.trials > kMaxStudyTrials) {
    throw InputError("--trials", std::to_string(o.trials) + ": expected 1 to " +
                                     std::to_string(kMaxStudyTrials) + " trials");
  }
  if (o.shard_count > kMaxStudyShards) {
    throw InputError("--shard", std::to_string(o.shard_count) + " shards: expected at most " +
                                    std::to_string(kMaxStudyShards));
  }
  if (o.jobs < 0) throw InputError("--jobs", std::to_string(o.jobs) + ": expected >= 1");
  if (o.shard_count < 1 || o.shard_index < 0 || o.shard_index >= o.shard_count) {
    throw InputError("--shard", std::to_string(o.shard_index) + "/" +
                                    std::to_string(o.shard_count) + ": expected 0 <= I < N");
  }
  if (o.out_dir.empty()) throw InputError("--out", "expected a folder");
}

namespace {

// What a study runs: its scenario (validated as a trial would), its hash and the trial command.
struct StudyInputs {
  Scenario sc;
  std::string hash;           // ScenarioHash(sc)
  std::string executable;     // the twinbench binary the trials run
  int jobs = 0;               // trial processes at a time
  std::string scenario_path;  // the scenario file, absolute
};

// The study folder, claimed and locked by this process.
struct StudyFolder {
  fs::path out;
  int lock_fd = -1;   // the lock on .study.lock, held until the study ends
  std::string shard;  // "I/N"
};

// The trials of this shard and which of them are still to run.
struct ShardTrials {
  std::string trials_path;  // OUT/trials.jsonl
  std::vector<int> todo;    // the trials not recorded yet, in order
  int in_shard = 0, recorded_in_shard = 0;
};

// The folders the trial processes work in.
struct WorkFolders {
  fs::path work;      // OUT/work, the trials' working directory
  std::string plans;  // the plan cache, linked into work/ as plans
};

// The processes of the trials in flight, as the interrupt handler sees them.
struct TrialChildren {
  std::mutex mutex;
  std::set<pid_t> pids;
};

// The fixed parts of a study that its trial loop reads.
struct StudyParts {
  const StudyInputs& in;
  const StudyFolder& folder;
  const ShardTrials& trials;
  const WorkFolders& folders;
  const std::vector<std::string>& env;  // the trial processes' whole environment
};

// The state of the trial loop, and what it leaves.
struct TrialLoop {
  std::map<pid_t, Running> running;  // the trial processes in flight
  std::size_t next = 0;              // the next entry of todo to start
  double wall_sum = 0;               // wall time of the finished trials [s]
  int finished = 0, stopped = 0;     // trials recorded / stopped by an interrupt
  Clock::time_point start;           // when the loop began
};

// Refuses a scenario without a section that `twinbench run` runs, or one a trial would refuse.
void CheckStudyScenario(const Scenario& sc) {
  if (IsPresent(sc.calibration)) ParseCalibrationConfig(sc);
  if (IsPresent(sc.handclasp)) ParseHandclaspConfig(sc);
  if (IsPresent(sc.tracker_calibration)) ValidateTrackerScenario(sc);
  if (!IsPresent(sc.calibration) && !IsPresent(sc.handclasp) &&
      !IsPresent(sc.tracker_calibration)) {
    throw InputError(sc.path + " scenario",
                     "a study needs a calibration:, handclasp: or tracker_calibration: section "
                     "(what `twinbench run` runs)");
  }
}

// Loads and checks the scenario and settles the trial command and the jobs at a time.
StudyInputs LoadStudyInputs(const StudyOptions& o) {
  StudyInputs in;
  in.sc = LoadScenario(o.scenario);
  CheckStudyScenario(in.sc);
  in.hash = ScenarioHash(in.sc);
  in.executable = o.executable.empty() ? SelfExecutable() : o.executable;
  // Trials are not confined to CPUs of their own: two trials each held to one of 2 CPUs ran
  // no faster than two free ones (README.md of e5af83d, "Speed of trials").
  in.jobs = o.jobs > 0 ? o.jobs : UsableCpuCount();
  in.scenario_path = fs::absolute(o.scenario).lexically_normal().string();
  return in;
}

// Claims OUT, locks it against a second study process and writes (or checks) study.json.
StudyFolder ClaimStudyFolder(const StudyOptions& o, const StudyInputs& in) {
  StudyFolder folder;
  folder.out = fs::path(o.out_dir);
  const fs::path& out = folder.out;
  // A new, empty or earlier study folder of ours (its mark), never a folder of the user's.
  ClaimOutputFolder(o.out_dir, "--out", "study");
  // One study process per folder at a time.
  const std::string lock_path = (out / ".study.lock").string();
  const int lock_fd = open(lock_path.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock_fd < 0 || flock(lock_fd, LOCK_EX | LOCK_NB) != 0) {
    throw InputError(o.out_dir, "another study runs in this folder (" + lock_path + " is locked)");
  }
  folder.lock_fd = lock_fd;
  folder.shard = std::to_string(o.shard_index) + "/" + std::to_string(o.shard_count);
  CheckStudyFile(out / "study.json", {in.scenario_path, in.sc.name, in.hash, o.trials,
                                      folder.shard});
  return folder;
}

// The trials recorded in trials.jsonl (its torn last line dropped); refuses another scenario's.
std::set<int> ReadRecordedTrials(const std::string& trials_path, const std::string& hash) {
  TrialsFileContent content = ReadTrialsFile(trials_path);
  if (content.torn_tail) {
    std::fprintf(stderr, "study: dropping the torn last line of %s (a killed study)\n",
                 trials_path.c_str());
    TruncateTrialsFile(trials_path, content.valid_bytes);
  }
  std::set<int> recorded;
  for (const TrialRecord& r : content.records) {
    if (r.scenario_hash().value_or("") != hash) {
      throw InputError(trials_path, "trial " + std::to_string(r.trial()) +
                                        " was recorded for another scenario (hash " +
                                        r.scenario_hash().value_or("?") + ", this one " + hash +
                                        "); choose another --out");
    }
    recorded.insert(r.trial());
  }
  return recorded;
}

// The trials of this shard, split into recorded ones and those still to run.
ShardTrials FindTrialsToRun(const StudyOptions& o, const std::string& hash, const fs::path& out) {
  ShardTrials trials;
  trials.trials_path = (out / "trials.jsonl").string();
  const std::set<int> recorded = ReadRecordedTrials(trials.trials_path, hash);
  for (int t = o.shard_index; t < o.trials; t += o.shard_count) {
    ++trials.in_shard;
    if (recorded.count(t)) {
      ++trials.recorded_in_shard;
    } else {
      trials.todo.push_back(t);
    }
  }
  return trials;
}

// A fresh work folder (an earlier one, of a killed study, removed) and the plan cache, claimed.
WorkFolders ClaimWorkFolders(const StudyOptions& o, const fs::path& out) {
  std::error_code ec;
  WorkFolders folders;
  folders.work = out / "work";
  const fs::path& work = folders.work;
  // Trials in flight when a study was killed: run again. The folder is removed only when it
  // carries the mark the study gave it.
  if (fs::exists(fs::symlink_status(work, ec))) {
    if (!IsMarkedFolder(work.string(), "study-work")) {
      throw InputError(work.string(), "the study's work folder holds something twinbench did "
                                      "not make (no " + std::string(kOutputMarker) +
                                      " mark); move it away and rerun");
    }
    fs::remove_all(work, ec);
  }
  ClaimOutputFolder(work.string(), work.string(), "study-work");
  folders.plans = o.plan_cache.empty() ? (out / "plans").string() : o.plan_cache;
  ClaimOutputFolder(folders.plans, o.plan_cache.empty() ? folders.plans : "--plan-cache",
                    "plan-cache");
  return folders;
}

// The line that opens a study: the scenario, the shard's trials and the jobs at a time.
void PrintStudyStart(const StudyInputs& in, const StudyFolder& folder, const ShardTrials& trials) {
  std::printf("twinbench study: %s (hash %s), trials %d of shard %s: %d recorded, %d to run, "
              "%d at a time\n",
              in.sc.name.c_str(), in.hash.c_str(), trials.in_shard, folder.shard.c_str(),
              trials.recorded_in_shard, static_cast<int>(trials.todo.size()), in.jobs);
  std::fflush(stdout);
}

// SIGINT, SIGTERM and SIGHUP wait on their own thread (InstallInterruptCleanup): here they
// stop the trial processes, whose ends wake the trial loop; the study then cleans up and
// ends by the signal.
// Restores the default reaction to interrupts when it goes out of scope, an exception
// included: the study's handler refers to the children of a frame that is then gone.
struct DefaultInterruptsOnExit {
  DefaultInterruptsOnExit() = default;
  DefaultInterruptsOnExit(const DefaultInterruptsOnExit&) = delete;
  DefaultInterruptsOnExit& operator=(const DefaultInterruptsOnExit&) = delete;
  ~DefaultInterruptsOnExit() { SetInterruptHandler({}); }
};

void StopTrialsOnInterrupt(TrialChildren* children) {
  SetInterruptHandler([children](int sig) {
    std::lock_guard<std::mutex> lock(children->mutex);
    g_interrupted = sig;
    for (const pid_t pid : children->pids) kill(pid, SIGTERM);
  });
}

}  // namespace

// One llvmpipe and one OpenCV thread per trial: the processes are the parallelism.
// A fixed mmap threshold: glibc raises it whenever a thread frees a large block, so whether
// a later large buffer comes from mmap or from the heap (and how it is aligned) would depend
// on the timing of the threads (with the address layout, SpawnTrial). twinbench's main() now
// fixes it itself (mallopt, 64 MiB, which overrides this variable); the variable stays in the
// list because the list's size is part of every trial's stack layout (below).
// The trial's whole environment is this fixed list, and its arguments are the same strings
// wherever the study's folder lies (relative to the work folder, its working directory, with
// the plan cache linked there): the environment and the arguments sit on the stack of the
// new process, so their sizes move every stack buffer's alignment, and with it (measured:
// a trial under Slurm differed from the same trial run locally by 1e-6 px in the intrinsics)
// the result.
// The GL back end's choice (sim/render/gl_context.h) and where EGL finds its vendor libraries
// and the driver's (LD_LIBRARY_PATH, in some clusters and containers) pass through, where set:
// a trial renders as the study was told to. They add to the environment's size, so trials are
// the same bit for bit across nodes (above) where these variables are the same too.
std::vector<std::string> TrialEnvironment() {
  std::vector<std::string> env = {"PATH=/usr/local/bin:/usr/bin:/bin", "LANG=C",
                                  "LC_ALL=C", "LP_NUM_THREADS=1",
                                  "OPENCV_FOR_THREADS_NUM=1",
                                  "MALLOC_MMAP_THRESHOLD_=131072"};
  for (const char* name :
       {"TWINBENCH_GL", "__EGL_VENDOR_LIBRARY_DIRS", "__EGL_VENDOR_LIBRARY_FILENAMES",
        "LD_LIBRARY_PATH"}) {
    if (const char* value = std::getenv(name)) env.push_back(std::string(name) + "=" + value);
  }
  return env;
}

namespace {

// Creates the plan cache and links it into the work folder as plans.
void LinkPlanCache(const WorkFolders& folders) {
  std::error_code ec;
  fs::create_directories(folders.plans, ec);
  if (!ec) fs::create_directory_symlink(fs::absolute(folders.plans), folders.work / "plans", ec);
  if (ec) {
    throw InputError((folders.work / "plans").string(),
                     "cannot link the plan cache: " + ec.message());
  }
}

// Starts trial processes until `jobs` run or none is left to start.
void StartTrials(const StudyParts& s, TrialChildren* children, Progress* progress,
                 TrialLoop* loop) {
  const fs::path& work = s.folders.work;
  while (loop->next < s.trials.todo.size() && static_cast<int>(loop->running.size()) < s.in.jobs) {
    const int t = s.trials.todo[loop->next++];
    Running r;
    r.trial = t;
    r.start = Clock::now();
    r.out = (work / ("trial_" + std::to_string(t))).string();
    r.log = r.out + ".log";
    const pid_t pid = SpawnTrial(s.in.executable,
                                 {"run", s.in.scenario_path, "--trial", std::to_string(t), "--out",
                                  "trial_" + std::to_string(t), "--quiet", "--no-images",
                                  "--plan-cache", "plans"},
                                 work.string(), s.env, r.log);
    {
      std::lock_guard<std::mutex> lock(children->mutex);
      children->pids.insert(pid);
      if (g_interrupted) kill(pid, SIGTERM);
    }
    loop->running[pid] = r;
    progress->Started(static_cast<int>(loop->running.size()));
  }
}

// The outcome of a finished trial process: its exit status, its report.json (read into
// *report, which the outcome points to) and, when it failed, the reason.
TrialOutcome JudgeTrial(const Running& r, int status, std::optional<TrialReport>* report) {
  TrialOutcome outcome;
  outcome.wall_s = SecondsSince(r.start);
  outcome.exit_code = WIFEXITED(status) ? WEXITSTATUS(status)
                                        : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  *report = ReadTrialReport(r.out + "/report.json");
  if (*report) outcome.report = &**report;
  if (outcome.exit_code == 0 && outcome.report) {
    outcome.status = outcome.report->failed ? "failed" : "ok";
  } else {
    outcome.status = "failed";
  }
  if (outcome.status == "failed") {
    outcome.reason = outcome.report && outcome.report->reason ? *outcome.report->reason
                                                              : ReasonFromLog(r.log);
    if (WIFSIGNALED(status)) {
      outcome.reason = "killed by signal " + std::to_string(WTERMSIG(status)) +
                       (outcome.reason.empty() ? "" : ": " + outcome.reason);
    }
    if (outcome.reason.empty()) {
      outcome.reason = "exit code " + std::to_string(outcome.exit_code) + ", no report";
    }
  }
  return outcome;
}

// Appends the trial's record to trials.jsonl, keeps the log of a failed trial in logs/ and
// removes the trial's files from the work folder.
void RecordTrial(const StudyParts& s, const Running& r, const TrialOutcome& outcome) {
  std::error_code ec;
  Scenario trial_scenario = s.in.sc;
  ApplyTrial(r.trial, &trial_scenario);
  AppendTrialRecord(s.trials.trials_path, MakeTrialRecord(s.in.hash, trial_scenario, outcome));
  if (outcome.status == "failed") {
    fs::create_directories(s.folder.out / "logs", ec);
    fs::rename(r.log, s.folder.out / "logs" / ("trial_" + std::to_string(r.trial) + ".log"), ec);
  }
  fs::remove_all(r.out, ec);
  fs::remove(r.log, ec);
  fs::remove_all(r.out + ".partial", ec);
}

// Runs the trials still to run, `jobs` at a time, recording each as it ends, until all are
// recorded or an interrupt stops them.
TrialLoop RunTrials(const StudyParts& s, TrialChildren* children, Progress* progress) {
  TrialLoop loop;
  loop.start = Clock::now();
  while ((loop.next < s.trials.todo.size() || !loop.running.empty()) && !g_interrupted) {
    StartTrials(s, children, progress, &loop);
    int status = 0;
    const pid_t pid = waitpid(-1, &status, 0);
    if (pid < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error(std::string("waitpid failed: ") + std::strerror(errno));
    }
    {
      std::lock_guard<std::mutex> lock(children->mutex);
      children->pids.erase(pid);
    }
    const auto it = loop.running.find(pid);
    if (it == loop.running.end()) continue;
    if (g_interrupted) {  // stopped by the interrupt: not a failed trial
      loop.running.erase(it);
      ++loop.stopped;
      continue;
    }
    const Running r = it->second;
    loop.running.erase(it);
    std::optional<TrialReport> report;
    const TrialOutcome outcome = JudgeTrial(r, status, &report);
    RecordTrial(s, r, outcome);
    progress->Finished(r.trial, outcome.status, outcome.wall_s,
                       static_cast<int>(loop.running.size()));
    loop.wall_sum += outcome.wall_s;
    ++loop.finished;
  }
  return loop;
}

// After an interrupt: stops the trials still in flight, removes work/ and ends by the signal.
[[noreturn]] void EndInterruptedStudy(const TrialLoop& loop, const StudyFolder& folder,
                                      const WorkFolders& folders) {
  std::error_code ec;
  const int sig = g_interrupted;
  for (const auto& [pid, r] : loop.running) kill(pid, SIGTERM);
  for (const auto& [pid, r] : loop.running) waitpid(pid, nullptr, 0);
  fs::remove_all(folders.work, ec);
  std::fprintf(stderr, "study: interrupted; %d trial(s) in flight were not recorded; run the "
               "same command again to resume\n",
               loop.stopped + static_cast<int>(loop.running.size()));
  close(folder.lock_fd);
  EndBySignal(sig);
}

// Writes summary.json and summary.html of all recorded trials and prints the closing line.
void WriteStudySummary(const StudyFolder& folder, const ShardTrials& trials,
                       const TrialLoop& loop) {
  const fs::path& out = folder.out;
  const StudySummaryCounts counts =
      WriteStudySummaryFiles(out.string(), ReadTrialsFile(trials.trials_path).records);
  if (!counts.mixed_renderers_warning.empty()) {
    std::fprintf(stderr, "%s\n", counts.mixed_renderers_warning.c_str());
  }
  std::printf("study: %d trials of shard %s recorded (%d failed); this run: %d trials in %.1f "
              "s, mean trial wall time %.2f s; wrote %s/{trials.jsonl, summary.json, "
              "summary.html}\n",
              trials.in_shard, folder.shard.c_str(), counts.failed,
              loop.finished, SecondsSince(loop.start),
              loop.finished > 0 ? loop.wall_sum / loop.finished : 0.0, out.string().c_str());
}

}  // namespace

int RunStudy(const StudyOptions& o) {
  ValidateStudyOptions(o);
  // Everything a trial would refuse is refused here, before anything runs.
  const StudyInputs in = LoadStudyInputs(o);
  // OUT claimed, locked and holding this study's study.json.
  const StudyFolder folder = ClaimStudyFolder(o, in);
  // The trials of the shard not yet in trials.jsonl.
  const ShardTrials trials = FindTrialsToRun(o, in.hash, folder.out);
  // A fresh work/ and the plan cache.
  const WorkFolders folders = ClaimWorkFolders(o, folder.out);
  // The opening line.
  PrintStudyStart(in, folder, trials);
  // From here an interrupt stops the trial processes.
  TrialChildren children;
  StopTrialsOnInterrupt(&children);
  const DefaultInterruptsOnExit default_interrupts_on_exit;
  // The trial processes' fixed environment.
  const std::vector<std::string> env = TrialEnvironment();
  // The plan cache, linked into work/.
  LinkPlanCache(folders);
  // The trials, `jobs` at a time.
  Progress progress(o.progress, trials.in_shard, trials.recorded_in_shard);
  const TrialLoop loop = RunTrials({in, folder, trials, folders, env}, &children, &progress);
  progress.End();
  // Interrupted: clean up and end by the signal.
  if (g_interrupted) EndInterruptedStudy(loop, folder, folders);
  SetInterruptHandler({});
  std::error_code ec;
  fs::remove_all(folders.work, ec);
  // summary.json, summary.html and the closing line.
  WriteStudySummary(folder, trials, loop);
  close(folder.lock_fd);
  return 0;
}

}  // namespace twin
