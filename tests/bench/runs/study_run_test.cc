// `twinbench study` and `twinbench study-merge` with the built binary on scenarios/
// study_small.yaml (a few seconds a trial): bad input (exit 2, nothing run), a study and its
// resumption, shards merged equal to the whole study, and a study killed with SIGKILL and run
// again: no trial lost, none recorded twice, no trial process left behind.
#include "tests/bench/cli_run.h"
#include "bench/runs/study_run.h"

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <map>
#include <set>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bench/report/trial_record.h"
#include "bench/report/trial_records_file.h"
#include "calib/common/errors.h"
#include "tests/bench/text_edit.h"

namespace twin {
namespace {
namespace fs = std::filesystem;
using json = nlohmann::json;
using twin::testing::CliRun;
using twin::testing::Twinbench;

const std::string kSmall = std::string(TWIN_SOURCE_DIR) + "/scenarios/study_small.yaml";

std::string Folder(const std::string& name) {
  const std::string d = ::testing::TempDir() + "/study_" + name;
  fs::remove_all(d);
  return d;
}

std::vector<json> Records(const std::string& dir) {
  std::vector<json> records;
  for (const TrialRecord& r : ReadTrialsFile(dir + "/trials.jsonl").records) {
    records.push_back(r.document());
  }
  return records;
}

std::map<int, json> ByTrial(const std::vector<json>& records) {
  std::map<int, json> m;
  for (const json& r : records) {
    EXPECT_TRUE(m.emplace(r["trial"].get<int>(), r).second) << "trial " << r["trial"] << " twice";
  }
  return m;
}

TEST(StudyCli, BadInputExitsTwoAndRunsNothing) {
  const std::string out = Folder("bad");
  struct Case {
    std::string args, names;
  };
  const std::vector<Case> cases = {
      {kSmall + " --trials 0 --out " + out, "--trials"},
      {kSmall + " --trials 4 --shard 2/2 --out " + out, "--shard"},
      {kSmall + " --trials 4 --shard 1-2 --out " + out, "--shard"},
      {kSmall + " --trials 4 --jobs -1 --out " + out, "--jobs"},
      {std::string(TWIN_SOURCE_DIR) + "/scenarios/twin_demo.yaml --trials 2 --out " + out,
       "calibration:, handclasp: or tracker_calibration: section"},
      {"/nonexistent.yaml --trials 2 --out " + out, "/nonexistent.yaml"},
  };
  for (const Case& c : cases) {
    const CliRun r = Twinbench("study " + c.args);
    EXPECT_EQ(r.code, 2) << c.args << "\n" << r.output;
    EXPECT_NE(r.output.find("error: "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(c.names), std::string::npos) << c.names << "\n" << r.output;
    EXPECT_FALSE(fs::exists(out + "/trials.jsonl")) << c.args;
  }
  EXPECT_EQ(Twinbench("study-merge /nonexistent_dir --out " + out).code, 2);
}

TEST(StudyCli, RefusesAFolderOfAnotherScenario) {
  const std::string out = Folder("other");
  fs::create_directories(out);
  std::ofstream(out + "/.twinbench-output") << R"({"written_by": "twinbench", "verb": "study"})";
  std::ofstream(out + "/study.json") << R"({"scenario_hash": "0000000000000000", "shard": "0/1"})";
  const CliRun r = Twinbench("study " + kSmall + " --trials 1 --out " + out);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("another scenario"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out + "/trials.jsonl"));
}

// The output-safety rule (issue 38): a study writes only into a new, empty or marked study
// folder, and removes its work/ only when the study marked it; counts are bounded.
TEST(StudyCli, NeverTouchesAFolderOrAWorkFolderItDidNotMake) {
  const std::string out = Folder("users");
  fs::create_directories(out + "/work");
  std::ofstream(out + "/work/precious.txt") << "the user's";
  CliRun r = Twinbench("study " + kSmall + " --trials 1 --out " + out);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("error: --out: '" + out + "' is a folder twinbench did not write"),
            std::string::npos) << r.output;
  // Even inside a folder marked as a study's, a work/ without the study's mark is kept.
  std::ofstream(out + "/.twinbench-output") << R"({"written_by": "twinbench", "verb": "study"})";
  r = Twinbench("study " + kSmall + " --trials 1 --out " + out);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("work folder holds something twinbench did not make"),
            std::string::npos) << r.output;
  EXPECT_EQ(testing::ReadFile(out + "/work/precious.txt"), "the user's");
  EXPECT_FALSE(fs::exists(out + "/trials.jsonl"));
  for (const char* counts : {"--trials 1e9", "--trials 100001", "--trials 4 --shard 0/10001"}) {
    r = Twinbench("study " + kSmall + " " + counts + " --out " + Folder("counts"));
    EXPECT_EQ(r.code, 2) << counts << "\n" << r.output;
    EXPECT_EQ(r.output.find("internal error"), std::string::npos) << r.output;
  }
}

TEST(StudyCli, MergeRefusesDifferentScenariosAndDropsDuplicates) {
  const std::string a = Folder("merge_a"), b = Folder("merge_b"), out = Folder("merge_out");
  fs::create_directories(a);
  fs::create_directories(b);
  const json r0 = {{"trial", 0}, {"scenario_hash", "aaaa"}, {"status", "ok"},
                   {"figures", {{"x", 1.0}}}, {"run", {{"wall_s", 1.0}}}};
  json r1 = r0;
  r1["trial"] = 1;
  json r0_again = r0;
  r0_again["run"]["wall_s"] = 7.0;  // the same trial run again elsewhere
  AppendTrialRecord(a + "/trials.jsonl", TrialRecord(r0));
  AppendTrialRecord(b + "/trials.jsonl", TrialRecord(r1));
  AppendTrialRecord(b + "/trials.jsonl", TrialRecord(r0_again));
  const CliRun ok = Twinbench("study-merge " + a + " " + b + " --out " + out);
  ASSERT_EQ(ok.code, 0) << ok.output;
  EXPECT_NE(ok.output.find("2 trials (1 duplicates dropped, 0 of them different)"),
            std::string::npos)
      << ok.output;
  const std::vector<json> merged = Records(out);
  ASSERT_EQ(merged.size(), 2u);
  EXPECT_EQ(merged[0]["trial"], 0);
  EXPECT_EQ(merged[0]["run"]["wall_s"], 1.0);  // the first folder's copy
  EXPECT_EQ(merged[1]["trial"], 1);
  EXPECT_TRUE(fs::exists(out + "/summary.json"));
  EXPECT_TRUE(fs::exists(out + "/summary.html"));
  json other = r1;
  other["trial"] = 2;
  other["scenario_hash"] = "bbbb";
  AppendTrialRecord(b + "/trials.jsonl", TrialRecord(other));
  const CliRun bad = Twinbench("study-merge " + a + " " + b + " --out " + out + "_2");
  EXPECT_EQ(bad.code, 2) << bad.output;
  EXPECT_NE(bad.output.find("different scenarios"), std::string::npos) << bad.output;
  EXPECT_FALSE(fs::exists(out + "_2"));
}

// A whole study of 4 trials, resumed (nothing to do), and the same study in two shards merged:
// every trial once, and the merged records equal the whole study's except for how they ran.
TEST(StudyCli, StudyResumesAndShardsMergeToTheSameRecords) {
  const std::string whole = Folder("whole");
  const CliRun r = Twinbench("study " + kSmall + " --trials 4 --jobs 2 --quiet --out " + whole);
  ASSERT_EQ(r.code, 0) << r.output;
  const std::map<int, json> w = ByTrial(Records(whole));
  ASSERT_EQ(w.size(), 4u);
  for (const auto& [t, rec] : w) {
    EXPECT_EQ(rec["status"], "ok") << rec["reason"];
    EXPECT_EQ(rec["seeds"]["truth"], 2019 + t);
    EXPECT_EQ(rec["seeds"]["estimator"], 2019 + t);
    EXPECT_TRUE(rec["figures"].contains("robots.r2.truth_position_error_mm.rigid.after.rms"));
  }
  // The plan is pinned (planning.seed), so trials after the first read it from the cache.
  int from_store = 0;
  for (const auto& [t, rec] : w) {
    from_store += rec["run"]["timing"].value("robots.r2.planning.from_plan_store", false);
  }
  EXPECT_EQ(from_store, 3);
  const json summary = json::parse(testing::ReadFile(whole + "/summary.json"));
  EXPECT_EQ(summary["trials"]["ok"], 4);
  EXPECT_TRUE(summary["coverage"].contains("robots.r2")) << summary["coverage"].dump();

  const CliRun again = Twinbench("study " + kSmall + " --trials 4 --jobs 2 --quiet --out " + whole);
  ASSERT_EQ(again.code, 0) << again.output;
  EXPECT_NE(again.output.find("4 recorded, 0 to run"), std::string::npos) << again.output;
  EXPECT_EQ(Records(whole).size(), 4u);

  const std::string s0 = Folder("shard0"), s1 = Folder("shard1"), merged = Folder("merged");
  ASSERT_EQ(Twinbench("study " + kSmall + " --trials 4 --shard 0/2 --jobs 1 --quiet --out " + s0).code, 0);
  ASSERT_EQ(Twinbench("study " + kSmall + " --trials 4 --shard 1/2 --jobs 1 --quiet --out " + s1).code, 0);
  EXPECT_EQ(ByTrial(Records(s0)).count(2), 1u);
  EXPECT_EQ(ByTrial(Records(s1)).count(3), 1u);
  ASSERT_EQ(Twinbench("study-merge " + s0 + " " + s1 + " --out " + merged).code, 0);
  const std::map<int, json> m = ByTrial(Records(merged));
  ASSERT_EQ(m.size(), 4u);
  for (const auto& [t, rec] : m) {
    EXPECT_EQ(ComparablePart(rec), ComparablePart(w.at(t))) << "trial " << t;
  }
  EXPECT_EQ(testing::ReadFile(merged + "/summary.json"), testing::ReadFile(whole + "/summary.json"));
}

// Sets or (nullptr) unsets environment variables for its lifetime, then restores them.
class ScopedEnvironment {
 public:
  ScopedEnvironment(std::initializer_list<std::pair<const char*, const char*>> values) {
    for (const auto& [name, value] : values) {
      const char* old = std::getenv(name);
      saved_.push_back({name, old != nullptr, old ? old : ""});
      if (value) {
        setenv(name, value, 1);
      } else {
        unsetenv(name);
      }
    }
  }
  ~ScopedEnvironment() {
    for (const Saved& s : saved_) {
      if (s.was_set) {
        setenv(s.name.c_str(), s.value.c_str(), 1);
      } else {
        unsetenv(s.name.c_str());
      }
    }
  }

 private:
  struct Saved {
    std::string name;
    bool was_set;
    std::string value;
  };
  std::vector<Saved> saved_;
};

TEST(StudyEnvironment, KeepsOnlyTheGlChoiceEglPathsAndLibraryPathOfTheStudysOwn) {
  std::vector<std::string> plain, gl;
  {
    const ScopedEnvironment none({{"TWINBENCH_GL", nullptr},
                                  {"__EGL_VENDOR_LIBRARY_DIRS", nullptr},
                                  {"__EGL_VENDOR_LIBRARY_FILENAMES", nullptr},
                                  {"LD_LIBRARY_PATH", nullptr},
                                  {"TWINBENCH_STUDY_TEST_OTHER", "1"}});
    plain = TrialEnvironment();
  }
  {
    const ScopedEnvironment set({{"TWINBENCH_GL", "egl:1"},
                                 {"__EGL_VENDOR_LIBRARY_DIRS", nullptr},
                                 {"__EGL_VENDOR_LIBRARY_FILENAMES", "/x/10_nvidia.json"},
                                 {"LD_LIBRARY_PATH", "/opt/nvidia/lib"},
                                 {"TWINBENCH_STUDY_TEST_OTHER", "1"}});
    gl = TrialEnvironment();
  }
  EXPECT_EQ(plain.size(), 6u);  // the fixed list (study_run.cc: its size is part of the layout)
  ASSERT_EQ(gl.size(), 9u);
  EXPECT_TRUE(std::equal(plain.begin(), plain.end(), gl.begin()));
  EXPECT_EQ(gl[6], "TWINBENCH_GL=egl:1");
  EXPECT_EQ(gl[7], "__EGL_VENDOR_LIBRARY_FILENAMES=/x/10_nvidia.json");
  EXPECT_EQ(gl[8], "LD_LIBRARY_PATH=/opt/nvidia/lib");
  for (const std::string& e : gl) EXPECT_NE(e.rfind("TWINBENCH_STUDY_TEST_OTHER", 0), 0u) << e;
}

// A trial renders with the back end the study was told to use: with TWINBENCH_GL=osmesa its
// report names OSMesa without auto's reason for it (a trial that lost the variable would run
// auto: OSMesa "; EGL: ..." here, EGL on a GPU).
TEST(StudyCli, TrialsRenderWithTheStudysGlBackEnd) {
  const std::string out = Folder("gl");
  CliRun r;
  {
    const ScopedEnvironment osmesa({{"TWINBENCH_GL", "osmesa"}});
    r = Twinbench("study " + kSmall + " --trials 1 --jobs 1 --quiet --out " + out);
  }
  ASSERT_EQ(r.code, 0) << r.output;
  const std::map<int, json> w = ByTrial(Records(out));
  ASSERT_EQ(w.size(), 1u);
  const json& timing = w.at(0)["run"]["timing"];
  ASSERT_TRUE(timing.contains("timing_s.cell.renderer")) << timing.dump();
  const std::string renderer = timing["timing_s.cell.renderer"];
  EXPECT_EQ(renderer.rfind("osmesa (", 0), 0u) << renderer;
  EXPECT_EQ(renderer.find("EGL"), std::string::npos) << renderer;
}

// Every process whose command line names `dir` (the trials of a study in `dir`).
// Processes whose working directory is `dir` (trial processes run in the study's work folder).
std::vector<int> ProcessesNaming(const std::string& dir) {
  std::vector<int> pids;
  const std::string want = fs::weakly_canonical(dir).string();
  for (const auto& e : fs::directory_iterator("/proc")) {
    const std::string name = e.path().filename();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::error_code ec;
    const std::string cwd = fs::read_symlink(e.path() / "cwd", ec).string();
    if (!ec && cwd.rfind(want, 0) == 0 && std::stoi(name) != getpid()) {
      pids.push_back(std::stoi(name));
    }
  }
  return pids;
}

TEST(StudyCli, KilledWithSigkillLosesOnlyTheTrialsInFlight) {
  const std::string out = Folder("killed");
  const int trials = 6;
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const std::string log = ::testing::TempDir() + "/study_killed.log";
    freopen(log.c_str(), "w", stdout);
    freopen(log.c_str(), "a", stderr);
    execl(TWINBENCH_BIN, TWINBENCH_BIN, "study", kSmall.c_str(), "--trials",
          std::to_string(trials).c_str(), "--jobs", "2", "--quiet", "--out", out.c_str(),
          static_cast<char*>(nullptr));
    _exit(127);
  }
  // Kill as soon as the first trials are recorded, while others run.
  const auto t0 = std::chrono::steady_clock::now();
  std::size_t before = 0;
  while (std::chrono::steady_clock::now() - t0 < std::chrono::seconds(240)) {
    before = fs::exists(out + "/trials.jsonl") ? Records(out).size() : 0;
    if (before >= 2) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  ASSERT_GE(before, 2u) << "the study recorded nothing in 240 s";
  ASSERT_LT(before, static_cast<std::size_t>(trials)) << "too late to kill in flight";
  ASSERT_FALSE(ProcessesNaming(out + "/work").empty()) << "no trial in flight to lose";
  kill(pid, SIGKILL);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFSIGNALED(status));
  const std::string kept = testing::ReadFile(out + "/trials.jsonl");
  // The trials in flight die with the study (PR_SET_PDEATHSIG); allow them a moment.
  for (int i = 0; i < 50 && !ProcessesNaming(out + "/work").empty(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  EXPECT_TRUE(ProcessesNaming(out + "/work").empty()) << "trial processes outlived the study";
  const std::size_t recorded = Records(out).size();
  std::printf("[ measured ] killed with %zu of %d trials recorded\n", recorded, trials);

  const CliRun r = Twinbench("study " + kSmall + " --trials " + std::to_string(trials) +
                             " --jobs 2 --quiet --out " + out);
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find(std::to_string(recorded) + " recorded, " +
                          std::to_string(trials - recorded) + " to run"),
            std::string::npos)
      << r.output;
  const std::map<int, json> m = ByTrial(Records(out));  // fails on a trial recorded twice
  EXPECT_EQ(m.size(), static_cast<std::size_t>(trials));
  for (int t = 0; t < trials; ++t) EXPECT_EQ(m.count(t), 1u) << "trial " << t << " lost";
  // What was recorded before the kill is untouched, at the start of the file.
  EXPECT_EQ(testing::ReadFile(out + "/trials.jsonl").compare(0, kept.size(), kept), 0);
}

// SIGTERM, SIGINT and SIGHUP stop the trial processes; the study removes its work folder and
// ends by the signal, as `run` does.
TEST(StudyCli, InterruptedStudiesStopTheirTrialsAndLeaveNoWorkFolder) {
  for (const int sig : {SIGTERM, SIGHUP}) {
    const std::string out = Folder("interrupted" + std::to_string(sig));
    const testing::ProcessRun r = testing::RunProcess(
        {TWINBENCH_BIN, "study", kSmall, "--trials", "6", "--jobs", "2", "--quiet", "--out", out},
        240, "", [&](pid_t pid) {
          const auto t0 = std::chrono::steady_clock::now();
          while (ProcessesNaming(out + "/work").empty() &&
                 std::chrono::steady_clock::now() - t0 < std::chrono::seconds(120)) {
            std::this_thread::sleep_for(std::chrono::milliseconds(50));
          }
          kill(pid, sig);
        });
    EXPECT_FALSE(r.timed_out) << r.output;
    EXPECT_EQ(r.signal, sig) << "exited " << r.exited << " code " << r.code << ": " << r.output;
    EXPECT_NE(r.output.find("study: interrupted;"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out + "/work")) << "signal " << sig;
    EXPECT_TRUE(fs::exists(out + "/.twinbench-output"));  // a rerun resumes it
    for (int i = 0; i < 50 && !ProcessesNaming(out + "/work").empty(); ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    EXPECT_TRUE(ProcessesNaming(out).empty()) << "trial processes outlived the study";
  }
}

}  // namespace
}  // namespace twin
