// `twinbench study`: a Monte Carlo accuracy study of a scenario. Trial t is `twinbench run
// SCENARIO --trial t` (the truth drawn from seeds.truth + t, the estimator's own randomness
// from seeds.estimator + t; bench/io/scenario.h) in its own process (OSMesa contexts and
// MuJoCo's global handlers make the process the safe unit), `jobs` at a time. Each finished
// trial is appended to OUT/trials.jsonl as one complete line and flushed (bench/report/
// trial_record.h, trial_records_file.h). Killed at any moment, the study loses only the trials in
// flight (their processes die with it: PR_SET_PDEATHSIG); run again with the same command it
// skips the recorded trials and never records one twice. A failed trial is recorded with its
// reason and the study goes on. A shard (--shard I/N) runs trials I, I+N, I+2N, ... < trials.
//
// OUT holds: trials.jsonl; study.json (scenario file, name and hash, trials, shard: a rerun
// with another scenario or shard is refused); summary.json and summary.html of the recorded
// trials (bench/report/study_summary.h), rewritten at the end; plans/ (the plan cache,
// bench/runs/plan_cache.h, unless --plan-cache names another folder); logs/trial_<t>.log of
// failed trials; work/ while trials run. Trial processes render with one llvmpipe thread
// (LP_NUM_THREADS=1) and one OpenCV thread: parallelism comes from the processes.
#pragma once

#include <string>
#include <vector>

namespace twin {

/// Options of RunStudy; validated by ValidateStudyOptions.
struct StudyOptions {
  std::string scenario;     ///< scenario file (any that `twinbench run` takes)
  int trials = 0;           ///< trials of the whole study (all shards), >= 1
  int jobs = 0;             ///< trial processes at a time; 0: the CPUs this process may use
  int shard_index = 0;      ///< this shard, 0 .. shard_count - 1
  int shard_count = 1;      ///< shards of the study (Slurm array tasks), >= 1
  std::string out_dir;      ///< the study folder (created; reused to resume)
  std::string plan_cache;   ///< plan cache folder; empty: out_dir/plans
  bool progress = true;     ///< a progress bar (terminal) or a line per trial on stderr
  std::string executable;   ///< the twinbench binary trials run; empty: this process' own
};

/// Largest study: 100000 trials are weeks of compute at a trial a minute on 2 cores, and each
/// trial holds a line of trials.jsonl; more is a typo (--trials 1e9), refused before anything
/// runs.
constexpr int kMaxStudyTrials = 100000;
/// Most shards of one study (--shard I/N): a Slurm array of 10000 tasks is already beyond
/// most clusters' MaxArraySize.
constexpr int kMaxStudyShards = 10000;

/// Parses "I/N" (0 <= I < N) into `index` and `count`; InputError ("--shard") otherwise.
void ParseShard(const std::string& text, int* index, int* count);

/// Throws InputError naming the option (--trials, --jobs, --shard, --out).
void ValidateStudyOptions(const StudyOptions& options);

/// A trial process' whole environment (`NAME=value` strings): a fixed list, plus TWINBENCH_GL,
/// EGL's vendor-library paths (__EGL_VENDOR_LIBRARY_DIRS, __EGL_VENDOR_LIBRARY_FILENAMES) and
/// LD_LIBRARY_PATH, in that order, where this process has them.
std::vector<std::string> TrialEnvironment();

/// Runs the study (see above). Returns 0 when every trial of the shard is recorded (failed
/// trials included), 130 when interrupted. Throws InputError for bad input, a scenario the
/// trials cannot run, or an OUT of another scenario or shard.
int RunStudy(const StudyOptions& options);

}  // namespace twin
