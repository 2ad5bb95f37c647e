// The fuzz test (issue 14, item 4): a seeded mutator over the shipped robot models (YAML and
// URDF), scenarios and a measurements file (deleted lines, wrong types, NaN, infinities, huge
// and negative values, truncation, junk bytes, duplicated lines and rows), each mutated file
// run through the CLI with a time limit. Every case must end by exit 0 or 2 (never a signal,
// never 1, never the time limit), with an `error:` line naming the mutated file on 2, and
// leave nothing in --out on failure. Models and URDFs go through `info`, scenarios through
// `check` and, where `check` refuses, `run --out` too (which must refuse as well, writing
// nothing), measurement files through `identify --out`.
//
// TWINBENCH_FUZZ_CASES sets the number of cases (default 300, a minute or two on 2 cores);
// TWINBENCH_FUZZ_SEED the mutator's seed (default 14). A failing case is kept under the test's
// temporary folder (fuzz/failed_<case>.<ext>) and printed with its seed and mutation.
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <iterator>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "../calib/optical_axis_synthetic.h"
#include "bench/io/model_yaml.h"
#include "bench/runs/calibration_run.h"
#include "tests/bench/cli_run.h"
#include "tests/bench/text_edit.h"

namespace twin {
namespace {
namespace fs = std::filesystem;

using testing::ProcessRun;
using testing::ReadFile;
using testing::TwinbenchArgs;

const std::string kSource = TWIN_SOURCE_DIR;
// Per CLI run: far above any refusal (they take well under a second) and above a valid
// `identify` (seconds), far below a real run.
constexpr double kCaseTimeoutS = 60.0;

enum class Kind { kModel, kUrdf, kScenario, kMeasurements };

struct SeedFile {
  std::string name;  // file name of the mutated copy (extension chosen by kind)
  Kind kind;
  std::string text;
};

std::uint64_t EnvNumber(const char* name, std::uint64_t fallback) {
  const char* v = std::getenv(name);
  if (v == nullptr || *v == '\0') return fallback;
  return std::strtoull(v, nullptr, 10);
}

using testing::AbsoluteModels;

// A measurements.csv as `twinbench run` writes it, from the synthetic recording (exact joint
// angles and depths; 5 axes x 10 positions).
std::string SyntheticMeasurements() {
  const testing::OpticalAxisScenario s = testing::MakeOpticalAxisScenario(42);
  std::ostringstream csv;
  csv.precision(12);
  csv << "robot,camera_robot,axis,index,set,q1_deg,q2_deg,q3_deg,q4_deg,q5_deg,q6_deg,du_px,"
         "dv_px,depth_mm,offset_x_mm,offset_y_mm,offset_z_mm,frames,moves\n";
  int index = 0, last_axis = -1;
  for (const AxisSample& smp : s.samples) {
    index = smp.axis == last_axis ? index + 1 : 0;
    last_axis = smp.axis;
    const Line3& axis = s.axes[smp.axis];
    const double depth = (EndPose(s.truth, smp.q).translation() - axis.point).dot(axis.direction);
    csv << "r2,r1," << smp.axis << ',' << index << ','
        << (smp.axis < 3 ? "calibration" : "validation");
    for (int i = 0; i < 6; ++i) csv << ',' << RadToDeg(smp.q(i));
    csv << ",0,0," << 1000 * depth << ",0,0,0,3,2\n";
  }
  return csv.str();
}

std::vector<SeedFile> SeedFiles() {
  std::vector<SeedFile> seeds;
  for (const char* m : {"reinovo_r1.yaml", "reinovo_r2.yaml"}) {
    seeds.push_back({m, Kind::kModel, ReadFile(kSource + "/models/" + m)});
  }
  for (const char* m : {"reinovo_r1.urdf", "reinovo_r2.urdf"}) {
    seeds.push_back({m, Kind::kUrdf, ReadFile(kSource + "/models/" + m)});
  }
  for (const char* s : {"twin_demo.yaml", "paper_reinovo.yaml", "gan2014_floor_floor.yaml",
                        "gan2014_floor_wall.yaml", "workflow_dual.yaml"}) {
    seeds.push_back({s, Kind::kScenario, AbsoluteModels(ReadFile(kSource + "/scenarios/" + s))});
  }
  seeds.push_back({"measurements.csv", Kind::kMeasurements, SyntheticMeasurements()});
  return seeds;
}

// Values that replace a scalar: wrong types, non-finite, huge, negative, empty, unbalanced.
const char* const kYamlValues[] = {
    "nan",  ".nan",  ".inf", "-.inf", "1e308", "-1e308", "1e9",  "-1",   "0",   "-0.0",
    "abc",  "''",    "[]",   "{}",    "[1, 2", "'x",     "\"x",  "null", "~",   "1e-300",
    "99999999999999999999",  "0x10",  "true",  "[1e308, 1e308, 1e308]", "-1e9", "1e6", ""};
const char* const kXmlValues[] = {"nan", "inf", "-inf", "1e308", "-1e308", "-1", "0", "abc",
                                  "",    "1e9", "1 2",  "1e-300", "-5", "&amp;", "x y z w"};
const char* const kCsvValues[] = {"nan", "inf", "-inf", "1e308", "-1", "0", "abc", "",
                                  "1e9", "999999", "../evil", "calibration", "unused", "x,y"};

struct Mutation {
  std::string text;
  std::string what;  // for the failure message
};

std::size_t Pick(std::mt19937_64& rng, std::size_t n) {
  return std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
}

std::vector<std::size_t> LineStarts(const std::string& t) {
  std::vector<std::size_t> starts = {0};
  for (std::size_t i = 0; i + 1 < t.size(); ++i) {
    if (t[i] == '\n') starts.push_back(i + 1);
  }
  return starts;
}

// Positions of the values of a text: YAML scalars after ": " or inside [...] lists, XML
// attribute values, CSV fields (start, length).
std::vector<std::pair<std::size_t, std::size_t>> ValueSpans(const std::string& t, Kind kind) {
  std::vector<std::pair<std::size_t, std::size_t>> spans;
  if (kind == Kind::kUrdf) {
    for (std::size_t p = t.find("=\""); p != std::string::npos; p = t.find("=\"", p + 2)) {
      const std::size_t end = t.find('"', p + 2);
      if (end == std::string::npos) break;
      spans.emplace_back(p + 2, end - p - 2);
    }
  } else if (kind == Kind::kMeasurements) {
    std::size_t start = 0;
    for (std::size_t i = 0; i <= t.size(); ++i) {
      if (i == t.size() || t[i] == ',' || t[i] == '\n') {
        if (i > start) spans.emplace_back(start, i - start);
        start = i + 1;
      }
    }
  } else {
    for (std::size_t i = 0; i < t.size(); ++i) {
      const bool after_colon = t[i] == ':' && i + 1 < t.size() && t[i + 1] == ' ';
      const bool in_list = t[i] == '[' || (t[i] == ',' && i + 1 < t.size() && t[i + 1] == ' ');
      if (!after_colon && !in_list) continue;
      std::size_t b = i + 1;
      while (b < t.size() && t[b] == ' ') ++b;
      std::size_t e = b;
      while (e < t.size() && t[e] != ',' && t[e] != ']' && t[e] != '}' && t[e] != '\n' &&
             t[e] != '#') {
        ++e;
      }
      while (e > b && t[e - 1] == ' ') --e;
      if (e > b && t[b] != '{' && t[b] != '[') spans.emplace_back(b, e - b);
    }
  }
  return spans;
}

Mutation Mutate(const SeedFile& seed, std::mt19937_64& rng) {
  std::string t = seed.text;
  const std::vector<std::size_t> lines = LineStarts(t);
  const auto line_end = [&](std::size_t start) {
    const std::size_t e = t.find('\n', start);
    return e == std::string::npos ? t.size() : e + 1;
  };
  // Mostly value replacements: they are the mutations the validation must catch at a key.
  const int op = static_cast<int>(Pick(rng, 10));
  if (op <= 4) {
    const auto spans = ValueSpans(t, seed.kind);
    if (!spans.empty()) {
      const auto [b, n] = spans[Pick(rng, spans.size())];
      std::string v;
      if (seed.kind == Kind::kUrdf) {
        v = kXmlValues[Pick(rng, std::size(kXmlValues))];
      } else if (seed.kind == Kind::kMeasurements) {
        v = kCsvValues[Pick(rng, std::size(kCsvValues))];
      } else {
        v = kYamlValues[Pick(rng, std::size(kYamlValues))];
      }
      if (Pick(rng, 4) == 0) {  // or the value scaled: huge, tiny or negative
        const std::string old = t.substr(b, n);
        const char* scale[] = {"e6", "e-9", "e300"};
        v = (Pick(rng, 2) ? "-" : "") + old + scale[Pick(rng, 3)];
      }
      const std::string what = "value at byte " + std::to_string(b) + " '" + t.substr(b, n) +
                               "' -> '" + v + "'";
      t.replace(b, n, v);
      return {t, what};
    }
  }
  if (op == 5) {
    const std::size_t s = lines[Pick(rng, lines.size())];
    const std::string what = "deleted line '" + t.substr(s, line_end(s) - s) + "'";
    t.erase(s, line_end(s) - s);
    return {t, what};
  }
  if (op == 6) {
    const std::size_t at = Pick(rng, t.size() + 1);
    t.resize(at);
    return {t, "truncated at byte " + std::to_string(at)};
  }
  if (op == 7) {
    const std::size_t at = Pick(rng, t.size() + 1);
    std::string junk;
    const std::size_t n = 1 + Pick(rng, 16);
    for (std::size_t k = 0; k < n; ++k) junk += static_cast<char>(Pick(rng, 256));
    t.insert(at, junk);
    return {t, "junk bytes inserted at byte " + std::to_string(at)};
  }
  if (op == 8 && seed.kind == Kind::kMeasurements) {
    // Many rows: a copy of the data rows until the row limit (kMaxMeasurementRows) is passed,
    // which must be refused quickly. (Below the limit a large file is identified, which takes
    // minutes for 20,000 rows of nonsense: legitimate work, not what the fuzz bounds.)
    const std::string rows = t.substr(line_end(0));
    const long per_copy = std::max<long>(1, std::count(rows.begin(), rows.end(), '\n'));
    std::string big = t;
    for (long n = 0; n <= kMaxMeasurementRows; n += per_copy) big += rows;
    return {big, "data rows repeated to " + std::to_string(big.size()) + " bytes"};
  }
  const std::size_t s = lines[Pick(rng, lines.size())];
  const std::string line = t.substr(s, line_end(s) - s);
  t.insert(s, line);
  return {t, "duplicated line '" + line + "'"};
}

std::string Extension(Kind kind) {
  switch (kind) {
    case Kind::kUrdf: return ".urdf";
    case Kind::kMeasurements: return ".csv";
    default: return ".yaml";
  }
}

// The case's verdict: "" when it kept the contract, else what broke it.
std::string Violation(const ProcessRun& r, const std::string& file, const fs::path& out) {
  if (r.timed_out) return "ran past the time limit";
  if (!r.exited) return "ended by signal " + std::to_string(r.signal);
  if (r.code != 0 && r.code != 2) return "exit code " + std::to_string(r.code);
  if (r.code == 2) {
    const std::size_t at = r.output.find("error: ");
    if (at == std::string::npos) return "exit 2 without an 'error:' line";
    const std::string line = r.output.substr(at, r.output.find('\n', at) - at);
    if (line.find(file) == std::string::npos) return "the error line does not name " + file;
    if (!out.empty() && (fs::exists(out) || fs::exists(out.string() + ".partial") ||
                         fs::exists(out.string() + ".old"))) {
      return "exit 2 left output in " + out.string();
    }
  }
  return "";
}

TEST(FuzzCli, MutatedInputsExitZeroOrTwoAndLeaveNothingBehind) {
  const std::uint64_t cases = EnvNumber("TWINBENCH_FUZZ_CASES", 300);
  const std::uint64_t seed = EnvNumber("TWINBENCH_FUZZ_SEED", 14);
  const std::vector<SeedFile> seeds = SeedFiles();
  const fs::path dir = fs::path(::testing::TempDir()) / "fuzz";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "nominal_r2.yaml") << ReadFile(kSource + "/models/reinovo_r2.yaml");
  std::mt19937_64 rng(seed);
  int exit0 = 0, exit2 = 0, runs = 0, failures = 0;
  double slowest = 0.0;
  for (std::uint64_t c = 0; c < cases; ++c) {
    const SeedFile& s = seeds[Pick(rng, seeds.size())];
    const Mutation m = Mutate(s, rng);
    const std::string file = (dir / ("case" + Extension(s.kind))).string();
    {
      std::ofstream f(file, std::ios::binary | std::ios::trunc);
      f << m.text;
    }
    const fs::path out = dir / "out";
    fs::remove_all(out);
    std::vector<std::pair<std::vector<std::string>, fs::path>> commands;
    switch (s.kind) {
      case Kind::kModel:
      case Kind::kUrdf:
        commands.push_back({{"info", file}, {}});
        break;
      case Kind::kScenario:
        commands.push_back({{"check", file}, {}});
        break;
      case Kind::kMeasurements:
        commands.push_back({{"identify", "--model", (dir / "nominal_r2.yaml").string(),
                             "--measurements", file, "--out", out.string()},
                            out});
        break;
    }
    for (std::size_t k = 0; k < commands.size(); ++k) {
      const ProcessRun r = TwinbenchArgs(commands[k].first, kCaseTimeoutS, dir.string());
      ++runs;
      slowest = std::max(slowest, r.seconds);
      const std::string v = Violation(r, file, commands[k].second);
      if (!v.empty()) {
        ++failures;
        const fs::path kept = dir / ("failed_" + std::to_string(c) + Extension(s.kind));
        fs::copy_file(file, kept, fs::copy_options::overwrite_existing);
        ADD_FAILURE() << "case " << c << " (seed " << seed << ", " << s.name << ", " << m.what
                      << "): " << commands[k].first[0] << " " << v << "; kept as " << kept
                      << "\noutput:\n" << r.output.substr(0, 2000);
        break;
      }
      (r.code == 0 ? exit0 : exit2)++;
      // A scenario `check` refused: `run` must refuse it the same way and write nothing.
      if (s.kind == Kind::kScenario && k == 0 && r.code == 2 && c % 3 == 0) {
        commands.push_back({{"run", file, "--out", out.string()}, out});
      }
      fs::remove_all(out);
    }
    if (failures >= 10) break;  // enough to go on
  }
  std::printf("[ measured ] fuzz: %llu cases (seed %llu), %d CLI runs: %d exit 0, %d exit 2, "
              "%d violations; slowest run %.2f s\n",
              static_cast<unsigned long long>(cases), static_cast<unsigned long long>(seed), runs,
              exit0, exit2, failures, slowest);
  EXPECT_GT(exit2, 0);  // the mutator does produce bad input
}

}  // namespace
}  // namespace twin
