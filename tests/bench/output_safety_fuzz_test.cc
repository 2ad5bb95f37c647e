// The output-safety fuzz test (issue 38): a seeded generator of command lines that each combine
// one verb (identify, run, study, study-merge, check, render, export-urdf,
// synthesize-measurements) with one bad thing, run against a sandbox of "the user's files":
// an --out, --junit or --plan-cache that is a non-empty user folder, a user file, a symlink, a
// FIFO, a socket, a device, a folder marked by another verb, a folder whose staging sibling
// (OUT.partial) is the user's, or one that equals or contains an input; an input that is a
// FIFO, /dev/zero, /dev/null, a folder, a socket or missing; absurd counts (--trials 1e9,
// --shard 1/100000); absurd data, a tracker file for identify generated per case that reads
// cleanly but contradicts itself (one row's sigma over 100 times off the median, positions in
// metres labelled mm or scaled 20-90 times as m, an --ignore-column joint that moves). Every
// such case must be refused: exit 2, an `error: <where>: <what>` line naming an option, a path
// or `command line` (for absurd data: the file, line and column, or the option, and the
// reason), and nothing created, changed or deleted anywhere in the sandbox. A few cheap
// positive cases (synthesize-measurements and export-urdf to a new file, export-urdf over its
// own earlier output, study-merge into a new, empty or its own earlier folder, identify of a
// tracker file that measures poses again, counted as distinct poses) must succeed and change
// nothing but what they name as output.
//
// Before each case the sandbox's state is known (every path, by lstat: type, mode, size, a
// hash of a regular file's bytes, a symlink's target; FIFOs, sockets and devices are never
// opened); after it the state is compared. A case that changed anything gets a rebuilt sandbox;
// a case's generated input is written over data/generated.csv before it and put back after.
//
// TWINBENCH_SAFETY_FUZZ_CASES sets the number of cases (default 320: 1.2-1.3 minutes on 2
// cores, 0.22-0.24 s a case, a process start each); TWINBENCH_SAFETY_FUZZ_SEED the generator's seed
// (default 38). Failures are listed with their argv and the first 300 characters of output.
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "bench/io/model_loader.h"
#include "calib/kinematics/forward_kinematics.h"
#include "tests/bench/cli_run.h"

namespace twin {
namespace {
namespace fs = std::filesystem;

using testing::ProcessRun;
using testing::TwinbenchArgs;

const std::string kSource = TWIN_SOURCE_DIR;

// Per case: a refusal takes well under a second (measured: see the printed mean and slowest),
// so 20 s only catches a hang (a FIFO opened for reading, a real run started by mistake).
constexpr double kCaseTimeoutS = 20.0;
// Address space of each twinbench process: a refusal needs a few hundred MiB at most; the
// limit turns an unbounded read (/dev/zero read to its end) into an allocation failure
// (exit 1 or a signal, both counted) instead of exhausting the test machine's memory.
constexpr rlim_t kChildAddressSpace = rlim_t{4} << 30;
// Largest file a twinbench process may write: far above any output of a positive case here
// (a URDF, a CSV of 30 rows, a merged study of 2 trials), so a runaway write (e.g. /dev/zero
// copied to an output) ends by SIGXFSZ (counted as a crash) instead of filling the disk.
constexpr rlim_t kChildFileSize = rlim_t{256} << 20;
// Refusals whose `error:` line does not name where (an option, a path, `command line`): a few
// library messages may slip through; 2 % of the refusals is the most the issue accepts.
constexpr double kMaxUnnamedFraction = 0.02;
// A case that hangs costs the whole time limit; after this many hangs the test stops (the
// binary plainly starts real work instead of refusing; the first hangs say enough). A bad
// thing that hung once with a verb is not run again with that verb, for the same reason (its
// cases are counted as skipped, which fails the test too).
constexpr int kMaxHangs = 15;
// The marker twinbench leaves in the folders it writes (issue 38).
const char* const kMarker = ".twinbench-output";

std::uint64_t EnvNumber(const char* name, std::uint64_t fallback) {
  const char* v = std::getenv(name);
  if (v == nullptr || *v == '\0') return fallback;
  return std::strtoull(v, nullptr, 10);
}

std::string Slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void Spit(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p, std::ios::binary | std::ios::trunc) << text;
}

std::string Replace(std::string text, const std::string& from, const std::string& to) {
  for (std::size_t p = 0; (p = text.find(from, p)) != std::string::npos; p += to.size()) {
    text.replace(p, from.size(), to);
  }
  return text;
}

// ---------------------------------------------------------------------------------------------
// The sandbox's state.

struct Entry {
  char type = '?';         // f regular, d folder, l symlink, p FIFO, s socket, c/b device
  unsigned mode = 0;       // permission bits
  std::uintmax_t size = 0;  // bytes of a regular file; st_rdev of a device
  std::size_t hash = 0;    // of a regular file's bytes
  std::string link;        // a symlink's target
  bool operator==(const Entry& o) const {
    return type == o.type && mode == o.mode && size == o.size && hash == o.hash && link == o.link;
  }
};
using Snapshot = std::map<std::string, Entry>;  // path relative to the sandbox's base

void Walk(const fs::path& dir, const std::string& prefix, Snapshot* s) {
  std::error_code ec;
  for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
    const fs::path p = it->path();
    const std::string rel = prefix + p.filename().string();
    struct stat st;
    if (lstat(p.c_str(), &st) != 0) continue;
    Entry e;
    e.mode = st.st_mode & 07777;
    if (S_ISREG(st.st_mode)) {
      e.type = 'f';
      const std::string bytes = Slurp(p);
      e.size = bytes.size();
      e.hash = std::hash<std::string>{}(bytes);
    } else if (S_ISDIR(st.st_mode)) {
      e.type = 'd';
      Walk(p, rel + "/", s);
    } else if (S_ISLNK(st.st_mode)) {
      e.type = 'l';
      std::error_code lec;
      e.link = fs::read_symlink(p, lec).string();
    } else if (S_ISFIFO(st.st_mode)) {
      e.type = 'p';
    } else if (S_ISSOCK(st.st_mode)) {
      e.type = 's';
    } else if (S_ISCHR(st.st_mode) || S_ISBLK(st.st_mode)) {
      e.type = S_ISCHR(st.st_mode) ? 'c' : 'b';
      e.size = st.st_rdev;
    }
    (*s)[rel] = e;
  }
}

Snapshot Take(const fs::path& base) {
  Snapshot s;
  Walk(base, "", &s);
  return s;
}

// `rel` is one of the allowed outputs or inside one.
bool Allowed(const std::string& rel, const std::vector<std::string>& allowed) {
  for (const std::string& a : allowed) {
    if (rel == a || rel.rfind(a + "/", 0) == 0) return true;
  }
  return false;
}

struct Diff {
  std::vector<std::string> lost;     // gone or changed
  std::vector<std::string> created;  // new
  bool empty() const { return lost.empty() && created.empty(); }
};

Diff Compare(const Snapshot& before, const Snapshot& after,
             const std::vector<std::string>& allowed) {
  Diff d;
  for (const auto& [path, e] : before) {
    const auto it = after.find(path);
    if (Allowed(path, allowed)) continue;
    if (it == after.end()) {
      d.lost.push_back("gone: " + path);
    } else if (!(it->second == e)) {
      d.lost.push_back(std::string("changed: ") + path + " (" + e.type + " -> " +
                       it->second.type + ")");
    }
  }
  for (const auto& [path, e] : after) {
    if (before.count(path) == 0 && !Allowed(path, allowed)) {
      d.created.push_back(std::string("new: ") + path + " (" + e.type + ")");
    }
  }
  return d;
}

// ---------------------------------------------------------------------------------------------
// The sandbox: base/home holds the user's files; base is what the snapshots cover, so that
// siblings of home (home.partial, home.old) are seen too.

struct Golden {  // files twinbench itself wrote at setup (its own earlier outputs)
  std::string measurements;                             // synthesize-measurements, 60 rows
  std::string urdf;                                     // export-urdf of reinovo_r1.yaml
  std::vector<std::pair<std::string, std::string>> merged;  // study-merge folder: file, bytes
  std::vector<std::string> merged_dirs;
};

struct Sandbox {
  fs::path base, home;
  bool devices = false;  // device nodes could be made (mknod: root)
  bool sockets = false;  // Unix sockets could be bound (path short enough)
  // Inputs that a case may write over (its generated file) with what Build wrote there: put
  // back after the case, so that the sandbox is pristine again without a rebuild.
  std::map<std::string, std::string> generated;
  std::string P(const std::string& rel) const { return (home / rel).string(); }
};

std::string MarkerText(const std::string& verb) {
  return "{\"written_by\": \"twinbench\", \"verb\": \"" + verb + "\"}\n";
}

std::string TrialLine(int trial) {
  return "{\"trial\": " + std::to_string(trial) +
         ", \"scenario_hash\": \"aaaa\", \"status\": \"ok\", \"figures\": {\"x\": 1.0}, "
         "\"run\": {\"wall_s\": 1.0}}\n";
}

std::string StudyJson(int index) {
  return "{\n  \"scenario\": \"paper_reinovo\",\n  \"scenario_file\": \"/somewhere/paper_reinovo."
         "yaml\",\n  \"scenario_hash\": \"aaaa\",\n  \"shard\": \"" +
         std::to_string(index) + "/2\",\n  \"trials\": 2\n}\n";
}

// A study folder (shard `index` of 2, one trial recorded), marked as study's when `marked`.
void WriteShard(const fs::path& dir, int index, bool marked) {
  if (marked) Spit(dir / kMarker, MarkerText("study"));
  Spit(dir / "study.json", StudyJson(index));
  Spit(dir / "trials.jsonl", TrialLine(index));
}

// Joint readings of one row of a tracker file and the reflector's position [m].
struct TrackerRow {
  JointVector q;
  Vector3 p;
};

// `rows` poses of `m`: joints uniform within 80 % of their limits (and of +-3 rad), the
// reflector at the end frame in a tracker frame 1.5 m away.
std::vector<TrackerRow> TrackerPoses(const KinematicModel& m, std::mt19937& rng, int rows) {
  std::vector<TrackerRow> out;
  for (int r = 0; r < rows; ++r) {
    JointVector q(m.num_joints());
    for (int i = 0; i < m.num_joints(); ++i) {
      const double lo = std::max(-3.0, m.links[i].limits.lower);
      const double hi = std::min(3.0, m.links[i].limits.upper);
      q(i) = std::uniform_real_distribution<double>(0.8 * lo, 0.8 * hi)(rng);
    }
    out.push_back({q, EndPose(m, q).translation() + Vector3(1.5, 0.2, -0.3)});
  }
  return out;
}

// A laser-tracker file of `model` (bench/io/tracker_file.h): joints by number in radians, the
// reflector in metres in a tracker frame 1.5 m away, 0.01 mm sigma.
std::string TrackerCsv(const std::string& model_path, unsigned seed, int rows) {
  const KinematicModel m = LoadRobotModel(model_path);
  std::mt19937 rng(seed);
  std::ostringstream csv;
  csv.precision(12);
  csv << "pose";
  for (int i = 0; i < m.num_joints(); ++i) csv << ",q" << i + 1 << "_rad";
  csv << ",x_m,y_m,z_m,sigma_m\n";
  int r = 0;
  for (const TrackerRow& row : TrackerPoses(m, rng, rows)) {
    csv << ++r;
    for (int i = 0; i < m.num_joints(); ++i) csv << ',' << row.q(i);
    csv << ',' << row.p.x() << ',' << row.p.y() << ',' << row.p.z() << ",1e-05\n";
  }
  return csv.str();
}

bool MakeSocket(const fs::path& p) {
  sockaddr_un a{};
  a.sun_family = AF_UNIX;
  const std::string s = p.string();
  if (s.size() >= sizeof(a.sun_path)) return false;
  std::memcpy(a.sun_path, s.c_str(), s.size() + 1);
  const int fd = socket(AF_UNIX, SOCK_STREAM, 0);
  if (fd < 0) return false;
  const bool ok = bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof(a)) == 0;
  close(fd);
  return ok;
}

// A scenario's text with its robot models at these absolute paths (to place a copy anywhere).
std::string ScenarioWithModels(const std::string& text, const std::string& r1,
                               const std::string& r2) {
  return Replace(Replace(text, "../models/reinovo_r1.yaml", r1), "../models/reinovo_r2.yaml", r2);
}

void Build(Sandbox* sb, const Golden& g) {
  std::error_code ec;
  fs::remove_all(sb->base, ec);
  fs::create_directories(sb->home);
  const fs::path& h = sb->home;
  const std::string paper = Slurp(kSource + "/scenarios/paper_reinovo.yaml");
  const std::string r1 = sb->P("models/reinovo_r1.yaml"), r2 = sb->P("models/reinovo_r2.yaml");
  // Inputs: scenarios (model paths relative to their folder, as shipped), models, data.
  Spit(h / "scenarios/paper_reinovo.yaml", paper);
  Spit(h / "scenarios/tracker_reinovo.yaml", Slurp(kSource + "/scenarios/tracker_reinovo.yaml"));
  Spit(h / "scenarios/fifo_model.yaml",
       Replace(paper, "../models/reinovo_r2.yaml", "../models/fifo.yaml"));
  Spit(h / "scenarios/zero_model.yaml",
       Replace(paper, "../models/reinovo_r2.yaml", "../models/zero.yaml"));
  Spit(h / "scenarios/dir_model.yaml",
       Replace(paper, "../models/reinovo_r2.yaml", "../models/dir.yaml"));
  Spit(h / "scenarios/model_in_run_marked.yaml",
       ScenarioWithModels(paper, sb->P("run_marked/reinovo_r1.yaml"),
                          sb->P("run_marked/reinovo_r2.yaml")));
  for (const char* m : {"reinovo_r1.yaml", "reinovo_r2.yaml", "reinovo_r1.urdf", "reinovo_r2.urdf"}) {
    Spit(h / "models" / m, Slurp(kSource + "/models/" + m));
  }
  mkfifo((h / "models/fifo.yaml").c_str(), 0644);
  fs::create_symlink("/dev/zero", h / "models/zero.yaml");
  Spit(h / "models/dir.yaml/readme.txt", "a folder named like a model\n");
  Spit(h / "data/measurements.csv", g.measurements);
  Spit(h / "data/tracker.csv", TrackerCsv(r2, 1, 40));
  Spit(h / "data/validate.csv", TrackerCsv(r2, 2, 20));
  sb->generated["data/generated.csv"] = TrackerCsv(r2, 3, 40);
  Spit(h / "data/generated.csv", sb->generated["data/generated.csv"]);
  // The user's own things.
  Spit(h / "docs/readme.md", "# my notes\n");
  Spit(h / "docs/plan.txt", "calibrate on Monday\n");
  Spit(h / "docs/sub/deep.txt", "keep me\n");
  Spit(h / "notes.txt", "my notes, not twinbench's\n");
  Spit(h / "earlier_junit.xml",
       "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<!-- written by twinbench -->\n"
       "<testsuites name=\"twinbench\" tests=\"1\" failures=\"0\" errors=\"0\" time=\"1\">\n"
       "  <testsuite name=\"paper_reinovo\" tests=\"1\" failures=\"0\" errors=\"0\" "
       "skipped=\"0\" time=\"1\">\n    <testcase classname=\"twinbench.paper_reinovo\" "
       "name=\"run\" time=\"1\"/>\n  </testsuite>\n</testsuites>\n");
  fs::create_symlink("earlier_junit.xml", h / "link_junit.xml");
  Spit(h / "res.partial/keep.txt", "a user folder named like a staging folder\n");
  Spit(h / "resf.partial", "a user file named like a staging folder\n");
  Spit(h / "rep.old/keep.txt", "a user folder named like a replaced output\n");
  mkfifo((h / "pipe").c_str(), 0644);
  mkfifo((h / "pipe.yaml").c_str(), 0644);
  mkfifo((h / "pipe.csv").c_str(), 0644);
  fs::create_symlink("pipe.yaml", h / "link_pipe.yaml");
  sb->sockets = MakeSocket(h / "sock") && MakeSocket(h / "sock.yaml");
  sb->devices = mknod((h / "devnull").c_str(), S_IFCHR | 0666, makedev(1, 3)) == 0 &&
                mknod((h / "devzero").c_str(), S_IFCHR | 0666, makedev(1, 5)) == 0;
  fs::create_symlink("docs", h / "link_docs");
  fs::create_symlink("notes.txt", h / "link_notes.txt");
  fs::create_symlink("nowhere/missing", h / "link_dangling");
  fs::create_symlink("/dev/null", h / "link_null.yaml");
  Spit(h / "studylike/study.json", StudyJson(0));
  Spit(h / "studylike/trials.jsonl", TrialLine(0));
  Spit(h / "plans_user/0123abcd.json", "{\"poses\": []}\n");
  fs::create_directories(h / "empty_dir");
  // Folders marked by twinbench verbs, some holding inputs of a case.
  const std::string abs_paper = ScenarioWithModels(paper, r1, r2);
  Spit(h / "render_marked" / kMarker, MarkerText("render"));
  Spit(h / "render_marked/cell.png", "\x89PNG not really\n");
  Spit(h / "render_marked/scenario.yaml", abs_paper);
  Spit(h / "run_marked" / kMarker, MarkerText("run"));
  Spit(h / "run_marked/report.json", "{}\n");
  Spit(h / "run_marked/scenario.yaml", abs_paper);
  Spit(h / "run_marked/reinovo_r1.yaml", Slurp(kSource + "/models/reinovo_r1.yaml"));
  Spit(h / "run_marked/reinovo_r2.yaml", Slurp(kSource + "/models/reinovo_r2.yaml"));
  Spit(h / "ident_marked" / kMarker, MarkerText("identify"));
  Spit(h / "ident_marked/identification.json", "{}\n");
  Spit(h / "ident_marked/measurements.csv", g.measurements);
  Spit(h / "ident_marked/reinovo_r2.yaml", Slurp(kSource + "/models/reinovo_r2.yaml"));
  Spit(h / "ident_marked/tracker.csv", TrackerCsv(r2, 1, 40));
  Spit(h / "ident_marked/validate.csv", TrackerCsv(r2, 2, 20));
  Spit(h / "merge_marked" / kMarker, MarkerText("study-merge"));
  Spit(h / "merge_marked/trials.jsonl", TrialLine(0));
  WriteShard(h / "merge_marked/shard_c", 0, true);
  for (const std::string& d : g.merged_dirs) fs::create_directories(h / "merge_prev" / d);
  for (const auto& [f, bytes] : g.merged) Spit(h / "merge_prev" / f, bytes);
  WriteShard(h / "shards/a", 0, true);
  WriteShard(h / "shards/b", 1, true);
  Spit(h / "shards/a/scenario.yaml", abs_paper);
  Spit(h / "shards/fifo_shard/study.json", StudyJson(0));
  mkfifo((h / "shards/fifo_shard/trials.jsonl").c_str(), 0644);
  Spit(h / "shards/zero_shard/study.json", StudyJson(1));
  fs::create_symlink("/dev/zero", h / "shards/zero_shard/trials.jsonl");
  Spit(h / "exported/r1.urdf", g.urdf);
  Spit(h / "exported/x.urdf.partial", "a user file named like a temporary file\n");
}

// ---------------------------------------------------------------------------------------------
// Cases.

enum class Expect { kRefuse, kSucceed, kEither };

struct Case {
  std::string verb;
  std::string option;  // what is bad: --out, --junit, --plan-cache, input, --trials, ...
  std::string what;    // the bad thing in words
  std::string templ;   // the generator's template (verb#k), for the failure list
  std::vector<std::string> args;
  Expect expect = Expect::kRefuse;
  std::vector<std::string> outputs;  // home-relative paths a successful case may write
  // Inputs generated for this case (home-relative path, text): written over the sandbox's
  // copy (one of Sandbox::generated) just before the case runs.
  std::vector<std::pair<std::string, std::string>> files;
  std::vector<std::string> error_names;  // a refusal's error line must contain each of these
  int distinct_poses = -1;  // >= 0: a positive case's report.json must count these poses
};

// A path of a case: home-relative (or absolute: /dev/...), what it is, whether it is a real
// folder (then it may be spelled with a trailing slash).
struct Target {
  std::string rel;
  std::string what;
  bool dir = false;
};

struct Gen {
  std::mt19937& rng;
  const Sandbox& sb;

  std::size_t Pick(std::size_t n) {
    return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
  }
  const Target& One(const std::vector<Target>& v) { return v[Pick(v.size())]; }
  double Uniform(double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  }
  double LogUniform(double lo, double hi) { return std::exp(Uniform(std::log(lo), std::log(hi))); }

  // Spelled as a user might: absolute, relative to the current folder (home), "./"-prefixed
  // or through "docs/.."; real folders with or without a trailing slash.
  std::string Spell(const Target& t) {
    if (!t.rel.empty() && t.rel[0] == '/') return t.rel;
    if (t.rel.empty()) return Pick(2) ? sb.home.string() : "../" + sb.home.filename().string();
    std::string s;
    const std::size_t k = Pick(10);
    if (k < 5) {
      s = sb.P(t.rel);
    } else if (k < 8) {
      s = t.rel;
    } else if (k == 8) {
      s = "./" + t.rel;
    } else {
      s = "docs/../" + t.rel;
    }
    if (t.dir && Pick(5) == 0) s += "/";
    return s;
  }
  std::string Spell(const std::string& rel, bool dir = false) { return Spell(Target{rel, "", dir}); }

  std::vector<Target> BadFolderOuts(const std::string& verb) {
    std::vector<Target> v = {
        {"docs", "non-empty user folder", true},
        {"docs/sub", "non-empty user subfolder", true},
        {"notes.txt", "user file", false},
        {"link_docs", "symlink to a user folder", false},
        {"link_notes.txt", "symlink to a user file", false},
        {"link_dangling", "dangling symlink", false},
        {"pipe", "FIFO", false},
        {"studylike", "folder with a study.json but no marker", true},
        {"plans_user", "non-empty user folder", true},
        {"scenarios", "the folder of the inputs", true},
        {"", "the whole home folder", true},
        {"scenarios/paper_reinovo.yaml", "the scenario file", false},
        {"data/measurements.csv", "the measurements file", false},
        {"notes.txt/out", "below a user file", false},
    };
    if (sb.sockets) v.push_back({"sock", "socket", false});
    if (sb.devices) v.push_back({"devnull", "device", false});
    // A user's OUT.partial beside OUT: the verbs that stage into OUT.partial must refuse
    // (study writes into OUT itself and has no staging sibling to collide with).
    if (verb != "study") {
      v.push_back({"res", "user's folder res.partial beside it", false});
      v.push_back({"resf", "user's file resf.partial beside it", false});
    }
    const std::vector<std::pair<std::string, std::string>> marked = {
        {"render_marked", "render"}, {"run_marked", "run"}, {"ident_marked", "identify"},
        {"merge_marked", "study-merge"}, {"shards/a", "study"}};
    for (const auto& [dir, by] : marked) {
      if (by != verb) v.push_back({dir, "folder marked by " + by, true});
    }
    return v;
  }

  std::vector<Target> BadFileOuts() {
    std::vector<Target> v = {
        {"notes.txt", "user file", false},
        {"link_notes.txt", "symlink to a user file", false},
        {"link_dangling", "dangling symlink", false},
        {"link_junit.xml", "symlink to twinbench's JUnit file", false},
        {"pipe", "FIFO", false},
        {"docs", "user folder", true},
        {"docs/", "user folder (with a slash)", false},
        {"scenarios/paper_reinovo.yaml", "the scenario file", false},
        {"data/measurements.csv", "a measurements file", false},
        {"models/reinovo_r2.urdf", "a user's URDF", false},
        {"nodir/out.xml", "in a folder that does not exist", false},
        {"notes.txt/out.xml", "below a user file", false},
    };
    if (sb.sockets) v.push_back({"sock", "socket", false});
    if (sb.devices) {
      v.push_back({"devnull", "device (null)", false});
      v.push_back({"devzero", "device (zero)", false});
    }
    return v;
  }

  std::vector<Target> BadScenarioInputs() {
    std::vector<Target> v = {
        {"pipe.yaml", "FIFO", false},
        {"/dev/zero", "/dev/zero", false},
        {"/dev/null", "/dev/null", false},
        {"docs", "folder", true},
        {"missing.yaml", "nonexistent", false},
        {"link_pipe.yaml", "symlink to a FIFO", false},
        {"link_null.yaml", "symlink to /dev/null", false},
        {"scenarios/fifo_model.yaml", "scenario whose model is a FIFO", false},
        {"scenarios/zero_model.yaml", "scenario whose model is a symlink to /dev/zero", false},
        {"scenarios/dir_model.yaml", "scenario whose model is a folder", false},
    };
    if (sb.sockets) v.push_back({"sock.yaml", "socket", false});
    return v;
  }

  std::vector<Target> BadModelInputs() {
    std::vector<Target> v = {
        {"models/fifo.yaml", "FIFO", false},
        {"models/zero.yaml", "symlink to /dev/zero", false},
        {"/dev/zero", "/dev/zero", false},
        {"/dev/null", "/dev/null", false},
        {"models/dir.yaml", "folder", true},
        {"models/missing.yaml", "nonexistent", false},
        {"link_pipe.yaml", "symlink to a FIFO", false},
    };
    if (sb.sockets) v.push_back({"sock.yaml", "socket", false});
    return v;
  }

  std::vector<Target> BadCsvInputs() {
    std::vector<Target> v = {
        {"pipe.csv", "FIFO", false},
        {"/dev/zero", "/dev/zero", false},
        {"/dev/null", "/dev/null", false},
        {"docs", "folder", true},
        {"data/missing.csv", "nonexistent", false},
        {"link_pipe.yaml", "symlink to a FIFO", false},
    };
    if (sb.sockets) v.push_back({"sock", "socket", false});
    return v;
  }

  std::vector<Target> BadPlanCaches() {
    std::vector<Target> v = {
        {"docs", "non-empty user folder", true},
        {"plans_user", "user folder of plan-like files, no marker", true},
        {"notes.txt", "user file", false},
        {"pipe", "FIFO", false},
        {"link_docs", "symlink to a user folder", false},
        {"render_marked", "folder marked by render", true},
        {"studylike", "folder with a study.json but no marker", true},
        {"scenarios", "the folder of the inputs", true},
        {"scenarios/paper_reinovo.yaml", "the scenario file", false},
    };
    if (sb.devices) v.push_back({"devnull", "device", false});
    return v;
  }

  std::string Scenario() {
    return Spell(Pick(3) ? "scenarios/paper_reinovo.yaml" : "scenarios/tracker_reinovo.yaml");
  }
};

// ---------------------------------------------------------------------------------------------
// Absurd data: a tracker file whose every cell reads cleanly but which contradicts itself (a
// row's sigma, the position unit, an ignored joint that moves). identify must refuse it before
// it calibrates, naming the file, line and column (or the option) in its error line.

// The model of the generated tracker files (a copy of the sandbox's models/reinovo_r2.yaml).
const KinematicModel& TrackerModel() {
  static const KinematicModel m = LoadRobotModel(kSource + "/models/reinovo_r2.yaml");
  return m;
}

constexpr double kDegPerRad = 180.0 / 3.14159265358979323846;
// The generated file, rewritten for each case that uses it (Sandbox::generated).
const char* const kGenerated = "data/generated.csv";
// Plausible stated sigmas of a tracker [m]: 1 to 20 micrometres.
const std::vector<double> kSigmas = {1e-6, 2e-6, 5e-6, 1e-5, 2e-5};
// A plausible file's per-row spread of sigma about its base value: a tracker's uncertainty
// grows with distance and angle by a few times across a cell (tracker_file.cc), so rows vary
// within x0.7..x1.5 and the median stays within those bounds of the base value.
constexpr double kSigmaLow = 0.7, kSigmaHigh = 1.5;
// Least factor by which the bad row's sigma is off its base value: twinbench refuses beyond
// 100 times the median, and the median is within kSigmaLow..kSigmaHigh of the base, so 300 is
// over 200 times off the median (a margin of 2, never at the limit).
constexpr double kSigmaOffMin = 300.0;
// Largest bad sigma above the others [m]: under twinbench's 10 mm cap on any sigma by 2 times,
// so that the row is refused for its ratio to the median, not for the cap.
constexpr double kSigmaAboveMax = 5e-3;
// Largest bad sigma below the others, as a factor: 1e6 turns 1e-5 m into 1e-11 m; one case
// in kSigmaTinyOdds writes the extreme 1e-300 m instead (still a normal double).
constexpr double kSigmaBelowMax = 1e6;
constexpr std::size_t kSigmaTinyOdds = 4;
// Positions in metres written as x_m but scaled up this much about their centre ("look like
// millimetres"): twinbench refuses a spread over 10 times the model's motion, so 20 is twice
// over it; at 90 the farthest reflector (the arm reaches about 1 m from the centre of its
// poses) stays within kMaxReflectorM.
constexpr double kMmScaleLow = 20.0, kMmScaleHigh = 90.0;
// Farthest a scaled reflector may lie from the tracker [m]: twinbench refuses beyond 100 m
// (a reason of its own, not the one this case is about); the scale shrinks to keep within.
constexpr double kMaxReflectorM = 95.0;
// Range of an ignored joint column that moves [rad]: twinbench takes up to 2e-3 rad as an
// axis held still, so 4e-3 (twice that) is the least; one row jumping up to 1.5 rad or the
// whole file drifting up to 0.05 rad are the slips seen in practice (an unbraked axis).
constexpr double kIgnoredRangeLow = 4e-3, kIgnoredJumpHigh = 1.5, kIgnoredDriftHigh = 0.05;
// Encoder noise of an ignored column held still [rad]: a few counts, 2.7e-4 rad in the real
// session's torso (tracker_file.cc), well within twinbench's 2e-3.
constexpr double kIgnoredNoise = 1e-4;
// Rows of a generated file: a session measures tens of poses; 20 keeps the model's motion far
// above twinbench's 0.02 m floor for comparing spreads, 60 keeps a case cheap.
constexpr int kMinRows = 20, kMaxRows = 60;
// The repeated-pose positive case: 8 poses measured again 4 to 10 times each, among 24 to 40
// poses measured once (enough for the identification's rank), shuffled; tracker noise at the
// stated sigma. identify --no-diagnosis takes under 0.3 s on them (measured: the printed
// slowest case), as cheap as a refusal.
constexpr int kRepeatedPoses = 8, kMinRepeats = 4, kMaxRepeats = 10;
constexpr int kMinOncePoses = 24, kMaxOncePoses = 40;
constexpr double kRepeatSigma = 1e-5;  // [m]

// A tracker file as named columns of numbers.
struct TrackerTable {
  std::vector<std::pair<std::string, std::vector<double>>> columns;

  void Add(const std::string& name, std::vector<double> values) {
    columns.emplace_back(name, std::move(values));
  }
  // The 1-based number of the column `name` (0: none).
  int Column(const std::string& name) const {
    for (std::size_t i = 0; i < columns.size(); ++i) {
      if (columns[i].first == name) return static_cast<int>(i) + 1;
    }
    return 0;
  }
  // The name of the column that starts with `prefix` ("" when none).
  std::string Named(const std::string& prefix) const {
    for (const auto& [name, values] : columns) {
      if (name.rfind(prefix, 0) == 0) return name;
    }
    return "";
  }
  // The columns in a random order (twinbench finds them by name; the column an error names
  // then differs from case to case), as CSV text.
  std::string Csv(Gen& g) {
    std::shuffle(columns.begin(), columns.end(), g.rng);
    std::ostringstream csv;
    csv.precision(12);
    for (std::size_t i = 0; i < columns.size(); ++i) csv << (i ? "," : "") << columns[i].first;
    csv << '\n';
    for (std::size_t r = 0; r < columns.front().second.size(); ++r) {
      for (std::size_t i = 0; i < columns.size(); ++i) {
        csv << (i ? "," : "") << columns[i].second[r];
      }
      csv << '\n';
    }
    return csv.str();
  }
};

// The columns of a tracker file of `rows`, their naming picked at random as a user might: a
// pose column or none; joints by number (q3_rad) or by link name (q_link3_deg), in radians or
// degrees; the reflector in metres or millimetres (`unit` "m" or "mm"; "" picks one); the
// sigma per row [m] (`sigma`, none when empty) in metres or millimetres.
TrackerTable TrackerColumns(Gen& g, const std::vector<TrackerRow>& rows, std::string unit,
                            const std::vector<double>& sigma) {
  const KinematicModel& m = TrackerModel();
  const std::size_t n = rows.size();
  TrackerTable t;
  if (g.Pick(2)) {
    std::vector<double> id(n);
    for (std::size_t r = 0; r < n; ++r) id[r] = static_cast<double>(r + 1);
    t.Add("pose", id);
  }
  const bool by_name = g.Pick(2), deg = g.Pick(2);
  for (int j = 0; j < m.num_joints(); ++j) {
    std::vector<double> q(n);
    for (std::size_t r = 0; r < n; ++r) q[r] = deg ? rows[r].q(j) * kDegPerRad : rows[r].q(j);
    t.Add((by_name ? "q_" + m.links[j].name : "q" + std::to_string(j + 1)) +
              (deg ? "_deg" : "_rad"),
          q);
  }
  if (unit.empty()) unit = g.Pick(2) ? "m" : "mm";
  for (int k = 0; k < 3; ++k) {
    std::vector<double> v(n);
    for (std::size_t r = 0; r < n; ++r) v[r] = rows[r].p(k) * (unit == "mm" ? 1e3 : 1.0);
    t.Add(std::string(1, "xyz"[k]) + "_" + unit, v);
  }
  if (!sigma.empty()) {
    const bool mm = g.Pick(2);
    std::vector<double> v(n);
    for (std::size_t r = 0; r < n; ++r) v[r] = sigma[r] * (mm ? 1e3 : 1.0);
    t.Add(mm ? "sigma_mm" : "sigma_m", v);
  }
  return t;
}

std::string Num(double v) {
  std::ostringstream os;
  os.precision(3);
  os << v;
  return os.str();
}

// An absurd-data case of identify: one of four contradictions in three classes, in a
// plausible file of random poses; `model` and `tracker` (a plausible tracker file) spelled already.
void AbsurdData(Gen& g, const std::string& model, const std::string& tracker, Case* c) {
  const KinematicModel& m = TrackerModel();
  const int n = kMinRows + static_cast<int>(g.Pick(kMaxRows - kMinRows + 1));
  std::vector<TrackerRow> rows = TrackerPoses(m, g.rng, n);
  std::vector<double> sigma;
  const double base = kSigmas[g.Pick(kSigmas.size())];
  if (g.Pick(3)) {
    for (int r = 0; r < n; ++r) sigma.push_back(base * g.Uniform(kSigmaLow, kSigmaHigh));
  }
  c->files = {{kGenerated, ""}};
  std::string extra_option;  // --ignore-column NAME
  bool as_validate = false;  // the file passed as --validate (beside a plausible one)
  TrackerTable t;
  // Sigma (0), unit (1: metres as mm, 2: millimetres as m) and ignored joint (3), the three
  // equally likely.
  const std::vector<std::size_t> kinds = {0, 0, 1, 2, 3, 3};
  const std::size_t kind = kinds[g.Pick(kinds.size())];
  c->templ += "." + std::to_string(kind);
  if (kind == 0) {
    // One row's sigma over 100 times off the median, below or above.
    if (sigma.empty()) {
      for (int r = 0; r < n; ++r) sigma.push_back(base * g.Uniform(kSigmaLow, kSigmaHigh));
    }
    const int row = static_cast<int>(g.Pick(n));
    const bool above = base * kSigmaOffMin <= kSigmaAboveMax && g.Pick(2);
    if (above) {
      sigma[row] = base * g.LogUniform(kSigmaOffMin, kSigmaAboveMax / base);
    } else if (g.Pick(kSigmaTinyOdds) == 0) {
      sigma[row] = 1e-300;
    } else {
      sigma[row] = base / g.LogUniform(kSigmaOffMin, kSigmaBelowMax);
    }
    t = TrackerColumns(g, rows, "", sigma);
    c->option = "absurd data: sigma";
    c->what = "row " + std::to_string(row + 1) + "'s sigma " + Num(sigma[row]) + " m among " +
              Num(base) + " m";
    c->files.back().second = t.Csv(g);
    const std::string col = t.Named("sigma_");
    c->error_names = {":" + std::to_string(row + 2) + " column " + std::to_string(t.Column(col)) +
                          " (" + col + ")",
                      above ? "times above" : "times below"};
    as_validate = g.Pick(4) == 0;
  } else if (kind == 1) {
    // Positions in metres labelled millimetres.
    for (TrackerRow& r : rows) r.p *= 1e-3;
    t = TrackerColumns(g, rows, "mm", sigma);
    c->option = "absurd data: unit";
    c->what = "metres in x_mm, y_mm, z_mm";
    c->files.back().second = t.Csv(g);
    c->error_names = {":1 column " + std::to_string(t.Column("x_mm")) + " (x_mm)",
                      "look like metres"};
    as_validate = g.Pick(4) == 0;
  } else if (kind == 2) {
    // Positions labelled metres, scaled up about their centre (millimetres / 20..90).
    Vector3 centre = Vector3::Zero();
    for (const TrackerRow& r : rows) centre += r.p;
    centre /= n;
    double reach = 0.0;
    for (const TrackerRow& r : rows) reach = std::max(reach, (r.p - centre).norm());
    const double f = std::min(g.Uniform(kMmScaleLow, kMmScaleHigh),
                              (kMaxReflectorM - centre.norm()) / reach);
    for (TrackerRow& r : rows) r.p = centre + f * (r.p - centre);
    t = TrackerColumns(g, rows, "m", sigma);
    c->option = "absurd data: unit";
    c->what = "x_m, y_m, z_m spread " + Num(f) + " times";
    c->files.back().second = t.Csv(g);
    c->error_names = {":1 column " + std::to_string(t.Column("x_m")) + " (x_m)",
                      "look like millimetres"};
    as_validate = g.Pick(4) == 0;
  } else {
    // An ignored joint column (a 7th axis) that moves: one row jumps, or the file drifts.
    const std::vector<std::string> names = {"q7_rad", "q_E_rad", "q7_deg", "q_torso_deg"};
    const std::string name = names[g.Pick(names.size())];
    const bool deg = name.compare(name.size() - 4, 4, "_deg") == 0;
    const double held = g.Uniform(-1.0, 1.0);
    std::vector<double> v(n);
    for (int r = 0; r < n; ++r) v[r] = held + g.Uniform(-kIgnoredNoise, kIgnoredNoise) / 2;
    std::string how;
    if (g.Pick(2)) {
      const int row = static_cast<int>(g.Pick(n));
      const double jump = (g.Pick(2) ? 1 : -1) * g.LogUniform(kIgnoredRangeLow, kIgnoredJumpHigh);
      v[row] += jump;
      how = "row " + std::to_string(row + 1) + " off by " + Num(jump) + " rad";
    } else {
      const double drift = g.LogUniform(kIgnoredRangeLow, kIgnoredDriftHigh);
      for (int r = 0; r < n; ++r) v[r] += drift * r / (n - 1);
      how = "drifting " + Num(drift) + " rad";
    }
    if (deg) {
      for (double& x : v) x *= kDegPerRad;
    }
    t = TrackerColumns(g, rows, "", sigma);
    t.Add(name, v);
    c->option = "absurd data: ignored joint";
    c->what = "--ignore-column " + name + " " + how;
    c->files.back().second = t.Csv(g);
    c->error_names = {"error: --ignore-column " + name + ": "};
    extra_option = name;
  }
  const std::string spelled = g.Spell(kGenerated);
  c->args = {"identify", "--quiet", "--model", model, "--measurements",
             as_validate ? tracker : spelled};
  if (as_validate) {
    c->args.insert(c->args.end(), {"--validate", spelled});
    c->what = "--validate " + c->what;
  }
  if (!extra_option.empty()) {
    if (g.Pick(2)) {
      c->args.insert(c->args.end(), {"--ignore-column", extra_option});
    } else {
      c->args.push_back("--ignore-column=" + extra_option);
    }
  }
  c->args.insert(c->args.end(), {"--out", g.Spell("new_out")});
  c->what = kGenerated + std::string(": ") + c->what;
}

// A positive identify case: rows that repeat kRepeatedPoses poses many times among poses
// measured once are accepted, and counted as that many distinct poses.
void RepeatedPoses(Gen& g, const std::string& model, Case* c) {
  const int once = kMinOncePoses + static_cast<int>(g.Pick(kMaxOncePoses - kMinOncePoses + 1));
  const std::vector<TrackerRow> poses = TrackerPoses(TrackerModel(), g.rng, kRepeatedPoses + once);
  std::vector<TrackerRow> rows = poses;
  for (int k = 0; k < kRepeatedPoses; ++k) {
    const int again = kMinRepeats + static_cast<int>(g.Pick(kMaxRepeats - kMinRepeats + 1));
    for (int a = 0; a < again; ++a) rows.push_back(poses[k]);
  }
  std::shuffle(rows.begin(), rows.end(), g.rng);
  std::normal_distribution<double> noise(0.0, kRepeatSigma);
  for (TrackerRow& r : rows) r.p += Vector3(noise(g.rng), noise(g.rng), noise(g.rng));
  TrackerTable t =
      TrackerColumns(g, rows, "", std::vector<double>(rows.size(), kRepeatSigma));
  c->option = "positive";
  c->expect = Expect::kSucceed;
  c->what = std::string(kGenerated) + ": " + std::to_string(rows.size()) + " rows, " +
            std::to_string(kRepeatedPoses + once) + " distinct poses";
  c->files = {{kGenerated, t.Csv(g)}};
  c->outputs = {"new_ident"};
  c->distinct_poses = kRepeatedPoses + once;
  c->args = {"identify", "--quiet", "--no-diagnosis", "--model", model, "--measurements",
             g.Spell(kGenerated), "--out", g.Spell("new_ident")};
}

Case Make(const std::string& verb, Gen& g) {
  Case c;
  c.verb = verb;
  // Template k of n, equally likely unless `choices` lists them with repeats (weights).
  const auto tpl = [&](std::size_t n, const std::vector<std::size_t>& choices = {}) {
    const std::size_t k = choices.empty() ? g.Pick(n) : choices[g.Pick(choices.size())];
    c.templ = verb + "#" + std::to_string(k);
    return k;
  };
  const auto bad = [&](const std::string& option, const Target& t) {
    c.option = option;
    c.what = option + " " + (t.rel.empty() ? "home" : t.rel) + ": " + t.what;
    return g.Spell(t);
  };
  if (verb == "identify") {
    const std::string model = g.Spell("models/reinovo_r2.yaml");
    const std::string csv = g.Spell("data/measurements.csv");
    const std::string tracker = g.Spell("data/tracker.csv");
    // Absurd data (template 7) is identify's alone and comes in four kinds: weighted up so
    // that a round of 320 cases has about a dozen of them; the repeated-pose positive case (8)
    // costs a calibration, so it stays at the weight of one template.
    switch (tpl(9, {0, 1, 2, 3, 4, 5, 6, 7, 7, 7, 7, 8})) {
      case 0:
        c.args = {"identify", "--model", model, "--measurements", csv, "--out",
                  bad("--out", g.One(g.BadFolderOuts(verb)))};
        break;
      case 1:
        c.args = {"identify", "--model", model, "--measurements",
                  bad("input", g.One(g.BadCsvInputs())), "--out", g.Spell("new_out")};
        break;
      case 2:
        c.args = {"identify", "--model", bad("input", g.One(g.BadModelInputs())),
                  "--measurements", csv, "--out", g.Spell("new_out")};
        break;
      case 3:
        c.option = "--out contains input";
        if (g.Pick(2)) {
          c.what = "--out ident_marked holds --measurements";
          c.args = {"identify", "--model", model, "--measurements",
                    g.Spell("ident_marked/measurements.csv"), "--out", g.Spell("ident_marked", true)};
        } else {
          c.what = "--out ident_marked holds --model";
          c.args = {"identify", "--model", g.Spell("ident_marked/reinovo_r2.yaml"),
                    "--measurements", csv, "--out", g.Spell("ident_marked", true)};
        }
        break;
      case 4:
        c.args = {"identify", "--quiet", "--model", model, "--measurements", tracker, "--validate",
                  bad("input", g.One(g.BadCsvInputs())), "--out", g.Spell("new_out")};
        c.what = "--validate " + c.what;
        break;
      case 5:
        c.option = "--out contains input";
        if (g.Pick(2)) {
          c.what = "--out ident_marked holds the tracker file";
          c.args = {"identify", "--quiet", "--model", model, "--measurements",
                    g.Spell("ident_marked/tracker.csv"), "--out", g.Spell("ident_marked", true)};
        } else {
          c.what = "--out ident_marked holds --validate";
          c.args = {"identify", "--quiet", "--model", model, "--measurements", tracker,
                    "--validate", g.Spell("ident_marked/validate.csv"), "--out",
                    g.Spell("ident_marked", true)};
        }
        break;
      case 6:
        c.args = {"identify", "--quiet", "--model", model, "--measurements", tracker, "--out",
                  bad("--out", g.One(g.BadFolderOuts(verb)))};
        break;
      case 7:
        AbsurdData(g, model, tracker, &c);
        break;
      default:
        RepeatedPoses(g, model, &c);
        break;
    }
  } else if (verb == "run") {
    // --junit (templates 2, 3) is run's alone: weighted up so that it gets as many cases as
    // the other options.
    switch (tpl(6, {0, 0, 1, 2, 2, 2, 3, 4, 4, 5})) {
      case 0:
        c.args = {"run", g.Scenario(), "--quiet", "--out",
                  bad("--out", g.One(g.BadFolderOuts(verb)))};
        // An acceptable --junit (twinbench's own earlier file) and --plan-cache (new) beside
        // the bad --out: neither may be touched or created.
        if (g.Pick(2)) c.args.insert(c.args.end(), {"--junit", g.Spell("earlier_junit.xml")});
        if (g.Pick(3) == 0) c.args.insert(c.args.end(), {"--plan-cache", g.Spell("new_plans")});
        break;
      case 1:
        c.args = {"run", bad("input", g.One(g.BadScenarioInputs())), "--out", g.Spell("new_out")};
        if (g.Pick(2)) c.args.insert(c.args.end(), {"--junit", g.Spell("new_junit.xml")});
        break;
      case 2:
        c.args = {"run", g.Scenario(), "--quiet", "--out", g.Spell("new_out"), "--junit",
                  bad("--junit", g.One(g.BadFileOuts()))};
        break;
      case 3:
        c.option = "--junit";
        if (g.Pick(2)) {
          c.what = "--junit inside --out (run_marked)";
          c.args = {"run", g.Scenario(), "--quiet", "--out", g.Spell("run_marked", true),
                    "--junit", g.Spell("run_marked/junit.xml")};
        } else {
          c.what = "--junit inside --out (new)";
          c.args = {"run", g.Scenario(), "--quiet", "--out", g.Spell("new_out"), "--junit",
                    g.Spell("new_out/junit.xml")};
        }
        break;
      case 4:
        c.args = {"run", g.Scenario(), "--quiet", "--out", g.Spell("new_out"), "--plan-cache",
                  bad("--plan-cache", g.One(g.BadPlanCaches()))};
        break;
      default:
        c.option = "--out contains input";
        if (g.Pick(2)) {
          c.what = "--out run_marked holds the scenario";
          c.args = {"run", g.Spell("run_marked/scenario.yaml"), "--quiet", "--out",
                    g.Spell("run_marked", true)};
        } else {
          c.what = "--out run_marked holds the scenario's models";
          c.args = {"run", g.Spell("scenarios/model_in_run_marked.yaml"), "--quiet", "--out",
                    g.Spell("run_marked", true)};
        }
        break;
    }
  } else if (verb == "study") {
    const std::vector<std::string> head = {"study", "--quiet", "--jobs", "1"};
    c.args = head;
    switch (tpl(6)) {
      case 0:
        c.args.insert(c.args.end(), {g.Scenario(), "--trials", "4", "--out",
                                     bad("--out", g.One(g.BadFolderOuts(verb)))});
        break;
      case 1: {
        const std::vector<std::string> trials = {"1e9",    "0",   "-1",  "100001", "1000000",
                                                 "abc",    "2.5", "",    "1e5x",   "99999999999",
                                                 "0x186a1"};
        const std::string t = trials[g.Pick(trials.size())];
        c.option = "--trials";
        c.what = "--trials '" + t + "'";
        c.args.insert(c.args.end(), {g.Scenario(), "--trials=" + t, "--out", g.Spell("new_out")});
        break;
      }
      case 2: {
        const std::vector<std::string> shards = {"1/100000", "0/10001", "0/0",    "5/3",
                                                 "-1/4",     "1/",      "/3",     "3/3",
                                                 "0/1/2",    "a/b",     "9999999999/99999999999"};
        const std::string s = shards[g.Pick(shards.size())];
        c.option = "--shard";
        c.what = "--shard '" + s + "'";
        c.args.insert(c.args.end(),
                      {g.Scenario(), "--trials", "4", "--shard=" + s, "--out", g.Spell("new_out")});
        break;
      }
      case 3:
        c.args.insert(c.args.end(), {bad("input", g.One(g.BadScenarioInputs())), "--trials", "4",
                                     "--out", g.Spell("new_out")});
        break;
      case 4:
        c.args.insert(c.args.end(), {g.Scenario(), "--trials", "4", "--out", g.Spell("new_out"),
                                     "--plan-cache",
                                     bad("--plan-cache", g.One(g.BadPlanCaches()))});
        break;
      default:
        c.option = "--out contains input";
        c.what = "--out shards/a (marked by study) holds the scenario";
        c.args.insert(c.args.end(), {g.Spell("shards/a/scenario.yaml"), "--trials", "4", "--out",
                                     g.Spell("shards/a", true)});
        break;
    }
  } else if (verb == "study-merge") {
    const std::string a = g.Spell("shards/a", true), b = g.Spell("shards/b", true);
    switch (tpl(5)) {
      case 0: {
        std::vector<Target> outs = g.BadFolderOuts(verb);
        outs.push_back({"shards/a", "an input folder", true});
        outs.push_back({"shards/a/merged", "inside an input folder", false});
        outs.push_back({"shards", "the folder holding the inputs", true});
        c.args = {"study-merge", a, b, "--out", bad("--out", g.One(outs))};
        break;
      }
      case 1: {
        std::vector<Target> inputs = {
            {"pipe", "FIFO", false},
            {"notes.txt", "user file", false},
            {"missing_dir", "nonexistent", false},
            {"/dev/null", "/dev/null", false},
            {"/dev/zero", "/dev/zero", false},
            {"shards/fifo_shard", "study folder whose trials.jsonl is a FIFO", true},
            {"shards/zero_shard", "study folder whose trials.jsonl is a symlink to /dev/zero",
             true},
            {"docs", "folder that is no study", true},
        };
        if (g.sb.sockets) inputs.push_back({"sock", "socket", false});
        c.args = {"study-merge", a, bad("input", g.One(inputs)), "--out", g.Spell("new_out")};
        break;
      }
      case 2: {
        c.option = "positive";
        c.expect = Expect::kSucceed;
        const std::vector<Target> outs = {{"new_merge", "a new folder", false},
                                          {"empty_dir", "an empty folder", true},
                                          {"merge_prev", "its own earlier output", true}};
        const Target& t = g.One(outs);
        c.what = "--out " + t.rel + ": " + t.what;
        c.outputs = {t.rel};
        c.args = {"study-merge", a, b, "--out", g.Spell(t)};
        break;
      }
      case 3:
        c.option = "--out contains input";
        c.what = "--out merge_marked holds an input folder";
        c.args = {"study-merge", g.Spell("merge_marked/shard_c", true), b, "--out",
                  g.Spell("merge_marked", true)};
        break;
      default:
        // A user folder rep.old beside --out rep: the merge may refuse or write rep, but
        // rep.old is the user's and stays.
        c.option = "either";
        c.expect = Expect::kEither;
        c.what = "--out rep beside a user folder rep.old";
        c.outputs = {"rep"};
        c.args = {"study-merge", a, b, "--out", g.Spell("rep")};
        break;
    }
  } else if (verb == "check") {
    tpl(1);
    c.args = {"check", bad("input", g.One(g.BadScenarioInputs()))};
  } else if (verb == "render") {
    switch (tpl(3)) {
      case 0:
        c.args = {"render", g.Scenario(), "--out", bad("--out", g.One(g.BadFolderOuts(verb)))};
        break;
      case 1:
        c.args = {"render", bad("input", g.One(g.BadScenarioInputs())), "--out",
                  g.Spell("new_out")};
        break;
      default:
        c.option = "--out contains input";
        c.what = "--out render_marked holds the scenario";
        c.args = {"render", g.Spell("render_marked/scenario.yaml"), "--out",
                  g.Spell("render_marked", true)};
        break;
    }
  } else if (verb == "export-urdf") {
    const std::vector<std::string> models = {"models/reinovo_r1.yaml", "models/reinovo_r2.yaml",
                                             "models/reinovo_r1.urdf"};
    const std::string model = g.Spell(models[g.Pick(models.size())]);
    switch (tpl(5)) {
      case 0:
        c.args = {"export-urdf", model, "--out", bad("--out", g.One(g.BadFileOuts()))};
        break;
      case 1:
        c.args = {"export-urdf", bad("input", g.One(g.BadModelInputs())), "--out",
                  g.Spell("exported/new.urdf")};
        break;
      case 2: {
        c.option = "positive";
        c.expect = Expect::kSucceed;
        const std::string out = g.Pick(2) ? "exported/new.urdf" : "exported/r1.urdf";
        c.what = "--out " + out + (out == "exported/new.urdf" ? ": a new file"
                                                              : ": its own earlier output");
        c.outputs = {out};
        c.args = {"export-urdf", model, "--out", g.Spell(out)};
        break;
      }
      case 3:
        c.option = "--out contains input";
        if (g.Pick(2)) {
          c.what = "--out is the input URDF";
          c.args = {"export-urdf", g.Spell("models/reinovo_r1.urdf"), "--out",
                    g.Spell("models/reinovo_r1.urdf")};
        } else {
          c.what = "--out is the input, twinbench's own earlier URDF";
          c.args = {"export-urdf", g.Spell("exported/r1.urdf"), "--out",
                    g.Spell("exported/r1.urdf")};
        }
        break;
      default:
        // The user's exported/x.urdf.partial: export-urdf may refuse or write x.urdf, but the
        // user's file stays.
        c.option = "either";
        c.expect = Expect::kEither;
        c.what = "--out exported/x.urdf beside a user file x.urdf.partial";
        c.outputs = {"exported/x.urdf"};
        c.args = {"export-urdf", model, "--out", g.Spell("exported/x.urdf")};
        break;
    }
  } else {  // synthesize-measurements
    const std::string model = g.Spell("models/reinovo_r2.yaml");
    switch (tpl(5)) {
      case 0: {
        std::vector<Target> outs = g.BadFileOuts();
        outs.push_back({"exported/r1.urdf", "a file twinbench wrote (not to be replaced)", false});
        c.args = {"synthesize-measurements", "--model", model, "--rows", "30", "--out",
                  bad("--out", g.One(outs))};
        break;
      }
      case 1:
        c.args = {"synthesize-measurements", "--model", bad("input", g.One(g.BadModelInputs())),
                  "--rows", "30", "--out", g.Spell("data/new.csv")};
        break;
      case 2: {
        const std::vector<std::string> rows = {"0", "-5", "1e12", "99999999999", "abc", "14",
                                               "1000001"};
        const std::string r = rows[g.Pick(rows.size())];
        c.option = "--rows";
        c.what = "--rows '" + r + "'";
        c.args = {"synthesize-measurements", "--model", model, "--rows=" + r, "--out",
                  g.Spell("data/new.csv")};
        break;
      }
      case 3:
        c.option = "positive";
        c.expect = Expect::kSucceed;
        c.what = "--out data/new.csv: a new file";
        c.outputs = {"data/new.csv"};
        c.args = {"synthesize-measurements", "--model", model, "--rows", "30", "--out",
                  g.Spell("data/new.csv")};
        break;
      default:
        c.option = "--out contains input";
        c.what = "--out is the model";
        c.args = {"synthesize-measurements", "--model", model, "--rows", "30", "--out",
                  g.Spell("models/reinovo_r2.yaml")};
        break;
    }
  }
  return c;
}

// ---------------------------------------------------------------------------------------------
// Verdicts.

// The first line of the output that starts with "error: " ("" when none).
std::string ErrorLine(const std::string& out) {
  std::istringstream in(out);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("error: ", 0) == 0) return line;
  }
  return "";
}

// The error line names where: the text after "error: " up to the next ": " is an option
// (--...), `command line`, a path (has a '/'), a file name with an extension (or a key
// location such as scenario.fx; both have a '.' and no space), or a path exactly as the case
// passed it ("docs", "pipe": a user's relative path need have neither).
bool NamesWhere(const std::string& line, const std::vector<std::string>& args) {
  if (line.empty()) return false;
  std::string where = line.substr(7);
  const std::size_t colon = where.find(": ");
  if (colon == std::string::npos) return false;
  where = where.substr(0, colon);
  if (where.empty()) return false;
  if (where.rfind("--", 0) == 0 || where == "command line") return true;
  if (where.find('/') != std::string::npos) return true;
  for (const std::string& a : args) {
    if (!a.empty() && a[0] != '-' && (where == a || where == "'" + a + "'")) return true;
  }
  return where.find('.') != std::string::npos && where.find(' ') == std::string::npos;
}

// The integer after `"key":` in a JSON file (-1 when there is none).
long JsonInteger(const fs::path& p, const std::string& key) {
  const std::string text = Slurp(p);
  const std::size_t at = text.find("\"" + key + "\"");
  if (at == std::string::npos) return -1;
  const std::size_t colon = text.find(':', at);
  if (colon == std::string::npos) return -1;
  char* end = nullptr;
  const long v = std::strtol(text.c_str() + colon + 1, &end, 10);
  return end == text.c_str() + colon + 1 ? -1 : v;
}

void LimitChild(pid_t pid) {
  const rlimit as{kChildAddressSpace, kChildAddressSpace};
  const rlimit fsize{kChildFileSize, kChildFileSize};
  prlimit(pid, RLIMIT_AS, &as, nullptr);
  prlimit(pid, RLIMIT_FSIZE, &fsize, nullptr);
}

std::string Joined(const std::vector<std::string>& args) {
  std::string s = "twinbench";
  for (const std::string& a : args) {
    s += " ";
    s += a.empty() || a.find(' ') != std::string::npos ? "'" + a + "'" : a;
  }
  return s;
}

std::string Oneline(std::string s, std::size_t n) {
  if (s.size() > n) s = s.substr(0, n) + "...";
  std::replace(s.begin(), s.end(), '\n', '|');
  return s;
}

bool MakeGolden(const fs::path& dir, Golden* g) {
  std::error_code ec;
  fs::remove_all(dir, ec);
  fs::create_directories(dir);
  const auto ok = [&](const std::vector<std::string>& args) {
    const ProcessRun r = TwinbenchArgs(args, 120, dir.string());
    if (r.exited && r.code == 0) return true;
    ADD_FAILURE() << "setup: " << Joined(args) << " failed (exit " << r.code << "):\n"
                  << r.output;
    return false;
  };
  if (!ok({"synthesize-measurements", "--model", kSource + "/models/reinovo_r2.yaml", "--rows",
           "60", "--seed", "7", "--out", (dir / "measurements.csv").string()}) ||
      !ok({"export-urdf", kSource + "/models/reinovo_r1.yaml", "--out",
           (dir / "r1.urdf").string()})) {
    return false;
  }
  WriteShard(dir / "a", 0, true);
  WriteShard(dir / "b", 1, true);
  if (!ok({"study-merge", (dir / "a").string(), (dir / "b").string(), "--out",
           (dir / "merged").string()})) {
    return false;
  }
  g->measurements = Slurp(dir / "measurements.csv");
  g->urdf = Slurp(dir / "r1.urdf");
  for (const auto& e : fs::recursive_directory_iterator(dir / "merged")) {
    const std::string rel = fs::relative(e.path(), dir / "merged").string();
    if (e.is_directory()) {
      g->merged_dirs.push_back(rel);
    } else {
      g->merged.emplace_back(rel, Slurp(e.path()));
    }
  }
  return true;
}

struct Tally {
  int cases = 0, exit0 = 0, exit2 = 0, failed = 0;
};

TEST(OutputSafetyFuzz, GeneratedBadInputsLoseNothingHangNeverAndNameWhere) {
  const std::uint64_t cases = EnvNumber("TWINBENCH_SAFETY_FUZZ_CASES", 320);
  const std::uint64_t seed = EnvNumber("TWINBENCH_SAFETY_FUZZ_SEED", 38);
  const fs::path root = fs::path(::testing::TempDir()) / "twinbench_output_safety";
  Golden golden;
  ASSERT_TRUE(MakeGolden(root / "golden", &golden));
  Sandbox sb;
  sb.base = root / "sandbox";
  sb.home = sb.base / "home";
  Build(&sb, golden);
  const bool devices = sb.devices, sockets = sb.sockets;
  const Snapshot pristine = Take(sb.base);
  ASSERT_GT(pristine.size(), 50u);
  {  // The bookkeeping: a rebuilt sandbox is the same sandbox.
    Build(&sb, golden);
    ASSERT_TRUE(Compare(pristine, Take(sb.base), {}).empty()) << "sandbox rebuild differs";
  }

  const std::vector<std::string> verbs = {"identify", "run",         "study",
                                          "study-merge", "check",    "render",
                                          "export-urdf", "synthesize-measurements"};
  std::mt19937 rng(static_cast<std::mt19937::result_type>(seed));
  Gen gen{rng, sb};
  std::map<std::string, Tally> by_verb, by_option;
  int refused = 0, succeeded = 0, lost = 0, created = 0, process = 0, hangs = 0, crashes = 0,
      wrong_exit = 0, wrong_report = 0, internal = 0, unnamed = 0, misnamed = 0, skipped = 0,
      rebuilds = 0, run_cases = 0;
  double total_s = 0.0, slowest_s = 0.0;
  std::set<std::string> hung;
  std::vector<std::string> failures;
  bool stopped = false;
  for (std::uint64_t k = 0; k < cases; ++k) {
    const Case c = Make(verbs[k % verbs.size()], gen);
    const std::string key = c.verb + " | " + c.what;  // hangs are remembered per bad thing
    if (hung.count(key) > 0) {
      ++skipped;
      continue;
    }
    if (hangs >= kMaxHangs) {
      stopped = true;
      break;
    }
    // The case's generated inputs go over their sandbox copies: the state to compare with is
    // the pristine one with those files' new bytes.
    Snapshot with_files;
    const Snapshot* expected = &pristine;
    if (!c.files.empty()) {
      with_files = pristine;
      for (const auto& [rel, text] : c.files) {
        Spit(sb.home / rel, text);
        Entry& e = with_files.at("home/" + rel);
        e.size = text.size();
        e.hash = std::hash<std::string>{}(text);
      }
      expected = &with_files;
    }
    const ProcessRun r = TwinbenchArgs(c.args, kCaseTimeoutS, sb.home.string(), LimitChild);
    ++run_cases;
    total_s += r.seconds;
    slowest_s = std::max(slowest_s, r.seconds);
    const Snapshot after = Take(sb.base);
    std::vector<std::string> classes;
    // (c) the process: ended by exit within the limit, with the expected code.
    if (r.timed_out) {
      ++hangs;
      hung.insert(key);
      classes.push_back("(c) hang (killed after " + std::to_string(int(kCaseTimeoutS)) + " s)");
    } else if (!r.exited) {
      ++crashes;
      classes.push_back("(c) signal " + std::to_string(r.signal));
    } else if ((c.expect == Expect::kRefuse && r.code != 2) ||
               (c.expect == Expect::kSucceed && r.code != 0) ||
               (c.expect == Expect::kEither && r.code != 0 && r.code != 2)) {
      ++wrong_exit;
      classes.push_back("(c) exit " + std::to_string(r.code) +
                        (c.expect == Expect::kRefuse    ? " (must refuse: 2)"
                         : c.expect == Expect::kSucceed ? " (must succeed: 0)"
                                                        : " (0 or 2)"));
    }
    if (r.output.find("internal error") != std::string::npos) {
      ++internal;
      classes.push_back("(c) internal error");
    }
    if (r.exited && r.code == 0 && c.expect == Expect::kSucceed &&
        !fs::exists(fs::symlink_status(sb.home / c.outputs.front()))) {
      ++wrong_exit;
      classes.push_back("(c) exit 0 but no " + c.outputs.front());
    } else if (r.exited && r.code == 0 && c.distinct_poses >= 0) {
      const long got = JsonInteger(sb.home / c.outputs.front() / "report.json", "distinct_poses");
      if (got != c.distinct_poses) {
        ++wrong_report;
        classes.push_back("(c) report.json's distinct_poses " + std::to_string(got) +
                          ", expected " + std::to_string(c.distinct_poses));
      }
    }
    const bool c_failed = !classes.empty();
    if (c_failed) ++process;
    // (a), (b): nothing changed or appeared but a successful case's named outputs.
    std::vector<std::string> allowed;
    if (r.exited && r.code == 0 && c.expect != Expect::kRefuse) {
      for (const std::string& o : c.outputs) allowed.push_back("home/" + o);
    }
    const Diff d = Compare(*expected, after, allowed);
    if (!d.lost.empty()) {
      ++lost;
      classes.push_back("(a) " + std::to_string(d.lost.size()) + " lost/changed, e.g. " +
                        d.lost.front());
    }
    if (!d.created.empty()) {
      ++created;
      classes.push_back("(b) " + std::to_string(d.created.size()) + " created, e.g. " +
                        d.created.front());
    }
    // (d) a refusal names where.
    if (r.exited && r.code == 2) {
      ++refused;
      if (!NamesWhere(ErrorLine(r.output), c.args)) {
        ++unnamed;
        classes.push_back("(d) error line names no option/path: '" +
                          Oneline(ErrorLine(r.output), 160) + "'");
      }
      // ... and, for a case that knows it (absurd data), exactly where and why.
      for (const std::string& want : c.error_names) {
        if (ErrorLine(r.output).find(want) == std::string::npos) {
          ++misnamed;
          classes.push_back("(d) error line lacks '" + want + "': '" +
                            Oneline(ErrorLine(r.output), 200) + "'");
          break;
        }
      }
    }
    if (r.exited && r.code == 0) ++succeeded;
    for (Tally* t : {&by_verb[c.verb], &by_option[c.option]}) {
      ++t->cases;
      t->exit0 += r.exited && r.code == 0;
      t->exit2 += r.exited && r.code == 2;
      t->failed += !classes.empty();
    }
    if (!classes.empty()) {
      std::string f = "case " + std::to_string(k) + " [" + c.templ + ", " + c.what + "]";
      for (const std::string& s : classes) f += "\n    " + s;
      f += "\n    argv: " + Joined(c.args) + "\n    output: " + Oneline(r.output, 300);
      failures.push_back(f);
    }
    // A case that changed the sandbox (a positive one, or a failure) gets a fresh one; one
    // that only had its generated inputs written gets them back as Build wrote them.
    if (Compare(*expected, after, {}).empty()) {
      for (const auto& f : c.files) Spit(sb.home / f.first, sb.generated.at(f.first));
    } else {
      ++rebuilds;
      Build(&sb, golden);
      ASSERT_EQ(sb.devices, devices);
      ASSERT_EQ(sb.sockets, sockets);
      ASSERT_TRUE(Compare(pristine, Take(sb.base), {}).empty()) << "sandbox rebuild differs";
    }
  }

  std::printf("[ measured ] output safety fuzz: %llu cases (seed %llu), %d run, %d skipped "
              "(the same bad thing hung before)%s; devices %s, sockets %s\n",
              static_cast<unsigned long long>(cases), static_cast<unsigned long long>(seed),
              run_cases, skipped, stopped ? ", stopped after too many hangs" : "",
              devices ? "yes" : "no (not root: mknod)", sockets ? "yes" : "no");
  std::printf("[ measured ] %-26s %6s %6s %6s %7s\n", "verb / bad thing", "cases", "exit0",
              "exit2", "failed");
  for (const auto* m : {&by_verb, &by_option}) {
    for (const auto& [name, t] : *m) {
      std::printf("[ measured ] %-26s %6d %6d %6d %7d\n", name.c_str(), t.cases, t.exit0,
                  t.exit2, t.failed);
    }
  }
  std::printf("[ measured ] refused %d, succeeded %d; failures: (a) lost/changed files %d, "
              "(b) created paths %d, (c) process %d (hangs %d, signals %d, wrong exit %d, "
              "wrong report %d, internal error %d), (d) unnamed %d, misnamed %d; sandbox "
              "rebuilt %d times; per case mean %.3f s, slowest %.2f s\n",
              refused, succeeded, lost, created, process, hangs, crashes, wrong_exit,
              wrong_report, internal, unnamed, misnamed, rebuilds,
              run_cases ? total_s / run_cases : 0.0, slowest_s);
  for (const std::string& f : failures) std::printf("%s\n", f.c_str());
  EXPECT_EQ(lost, 0) << "cases that lost or changed a file (listed above)";
  EXPECT_EQ(created, 0) << "cases that created a path they may not (listed above)";
  EXPECT_EQ(process, 0) << "cases that hung, crashed or exited wrongly (listed above)";
  EXPECT_EQ(skipped, 0) << "cases skipped because the same bad thing hung";
  EXPECT_FALSE(stopped) << "stopped after " << kMaxHangs << " hangs";
  EXPECT_EQ(misnamed, 0) << "absurd-data refusals whose error line names another place or "
                            "reason (listed above)";
  EXPECT_LE(unnamed, static_cast<int>(kMaxUnnamedFraction * refused))
      << "refusals whose error line names no option or path (listed above)";
  EXPECT_GT(refused, 0);
}

}  // namespace
}  // namespace twin
