// `twinbench run --record RDIR` and `twinbench replay RDIR` (bench/runs/recording_cell.h,
// bench/runs/replay_cell.h) through the built binary: a replay writes the live run's
// report.json exactly, but for the wall-clock timings (ReportWithoutTimings); a recording with
// one number changed, or with its last lines cut off, is refused (exit 2) naming where; --record
// never writes into a folder that exists.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "../bench/cli_run.h"
#include "report_timings.h"

namespace twin {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using testing::TwinbenchArgs;

constexpr double kTimeout = 300;

fs::path TempDir(const std::string& name) {
  const fs::path base = fs::temp_directory_path() /
                        ("twinbench_replay_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(base);
  fs::create_directories(base);
  return base;
}

std::string Scenario(const std::string& name) {
  return std::string(TWIN_SOURCE_DIR) + "/scenarios/" + name + ".yaml";
}

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream os;
  os << in.rdbuf();
  return os.str();
}

// Runs `scenario` recorded into base/R (report in base/A) and replays it into base/B.
void RecordAndReplay(const fs::path& base, const std::string& scenario,
                     const std::vector<std::string>& run_options = {}) {
  std::vector<std::string> args = {"run", Scenario(scenario), "--out", (base / "A").string(),
                                   "--record", (base / "R").string(), "--quiet"};
  args.insert(args.end(), run_options.begin(), run_options.end());
  const testing::ProcessRun run = TwinbenchArgs(args, kTimeout);
  ASSERT_EQ(run.code, 0) << run.output;
  const testing::ProcessRun replay = TwinbenchArgs(
      {"replay", (base / "R").string(), "--out", (base / "B").string(), "--quiet"}, kTimeout);
  ASSERT_EQ(replay.code, 0) << replay.output;
}

// The recording's files: recording.json complete, every line of exchanges.jsonl parses with
// seq 1, 2, ..., every image file it names decodes at the size the line states. Returns the
// number of images.
int CheckRecordingFiles(const fs::path& dir, const std::string& scenario) {
  const json manifest = json::parse(ReadFile(dir / "recording.json"));
  EXPECT_EQ(manifest["format"], "twinbench-cell-recording");
  EXPECT_EQ(manifest["version"], 1);
  EXPECT_EQ(manifest["protocol"], "twinbench.cell.v1");
  EXPECT_EQ(manifest["complete"], true);
  EXPECT_FALSE(manifest["twinbench"].get<std::string>().empty());
  EXPECT_EQ(manifest["scenario"]["content"], ReadFile(Scenario(scenario)));
  std::ifstream in(dir / "exchanges.jsonl");
  std::string line;
  long seq = 0;
  int images = 0;
  while (std::getline(in, line)) {
    const json j = json::parse(line);
    EXPECT_EQ(j["seq"], ++seq);
    EXPECT_TRUE(j["request"].is_object() && j["response"].is_object()) << line;
    if (j["response"].contains("image_file")) {
      const cv::Mat image = cv::imread((dir / j["response"]["image_file"].get<std::string>()).string());
      EXPECT_FALSE(image.empty()) << line;
      EXPECT_EQ(image.cols, j["response"]["width_px"].get<int>());
      EXPECT_EQ(image.rows, j["response"]["height_px"].get<int>());
      ++images;
    }
  }
  EXPECT_EQ(manifest["exchanges"], seq);
  EXPECT_GT(seq, 10);
  return images;
}

TEST(ReplayCli, TrackerRecordingReplaysToTheSameReport) {
  const fs::path base = TempDir("tracker");
  RecordAndReplay(base, "tracker_single_reinovo");
  EXPECT_EQ(CheckRecordingFiles(base / "R", "tracker_single_reinovo"), 0);  // no camera
  const json a = ReportWithoutTimings(base / "A" / "report.json");
  const json b = ReportWithoutTimings(base / "B" / "report.json");
  EXPECT_TRUE(a == b) << "replayed report differs: " << json::diff(a, b).dump(1);
  EXPECT_EQ(ReadFile(base / "A" / "measurements.csv"), ReadFile(base / "B" / "measurements.csv"));
  // The timings were there to remove (they differ between any two runs).
  EXPECT_TRUE(json::parse(ReadFile(base / "A" / "report.json"))["timing_s"].contains("total"));
  fs::remove_all(base);
}

// About 20 s on 2 cores: in TWINBENCH_SLOW_GTESTS (ReplayCli.OpticalAxis*).
TEST(ReplayCli, OpticalAxisRecordingReplaysToTheSameReport) {
  const fs::path base = TempDir("optical");
  RecordAndReplay(base, "study_small", {"--no-images"});
  EXPECT_GT(CheckRecordingFiles(base / "R", "study_small"), 10);
  const json a = ReportWithoutTimings(base / "A" / "report.json");
  const json b = ReportWithoutTimings(base / "B" / "report.json");
  EXPECT_TRUE(a == b) << "replayed report differs: " << json::diff(a, b).dump(1);
  fs::remove_all(base);
}

// A recording of the tracker scenario in base/R.
void Record(const fs::path& base) {
  const testing::ProcessRun run = TwinbenchArgs(
      {"run", Scenario("tracker_single_reinovo"), "--out", (base / "A").string(), "--record",
       (base / "R").string(), "--quiet", "--no-images", "--no-diagnosis"},
      kTimeout);
  ASSERT_EQ(run.code, 0) << run.output;
}

std::vector<std::string> Lines(const fs::path& file) {
  std::vector<std::string> lines;
  std::ifstream in(file);
  std::string line;
  while (std::getline(in, line)) lines.push_back(line);
  return lines;
}

void WriteLines(const fs::path& file, const std::vector<std::string>& lines, size_t n) {
  std::ofstream out(file, std::ios::trunc);
  for (size_t i = 0; i < n && i < lines.size(); ++i) out << lines[i] << "\n";
}

TEST(ReplayCli, ATamperedRequestIsRefusedNamingTheLine) {
  const fs::path base = TempDir("tampered");
  Record(base);
  std::vector<std::string> lines = Lines(base / "R" / "exchanges.jsonl");
  // The first MoveTo's first joint target, one digit changed (well above the last bit).
  size_t k = 0;
  while (k < lines.size() && lines[k].find("\"method\":\"MoveTo\"") == std::string::npos) ++k;
  ASSERT_LT(k, lines.size());
  const size_t at = lines[k].find("\"q_target_rad\":[");
  ASSERT_NE(at, std::string::npos);
  const size_t digit = lines[k].find_first_of("123456789", at + 20);
  lines[k][digit] = lines[k][digit] == '9' ? '8' : static_cast<char>(lines[k][digit] + 1);
  WriteLines(base / "R" / "exchanges.jsonl", lines, lines.size());
  const testing::ProcessRun replay = TwinbenchArgs(
      {"replay", (base / "R").string(), "--out", (base / "B").string(), "--quiet"}, kTimeout);
  EXPECT_EQ(replay.code, 2) << replay.output;
  const std::string where = "exchanges.jsonl:" + std::to_string(k + 1) + " (seq " +
                            std::to_string(k + 1) + ")";
  EXPECT_NE(replay.output.find(where), std::string::npos) << replay.output;
  EXPECT_NE(replay.output.find("the estimator asked MoveTo"), std::string::npos) << replay.output;
  EXPECT_NE(replay.output.find("diverged"), std::string::npos) << replay.output;
  EXPECT_FALSE(fs::exists(base / "B"));
  fs::remove_all(base);
}

TEST(ReplayCli, ATruncatedRecordingIsRefusedWhereItEnds) {
  const fs::path base = TempDir("truncated");
  Record(base);
  const std::vector<std::string> lines = Lines(base / "R" / "exchanges.jsonl");
  ASSERT_GT(lines.size(), 100u);
  WriteLines(base / "R" / "exchanges.jsonl", lines, 100);
  const testing::ProcessRun replay = TwinbenchArgs(
      {"replay", (base / "R").string(), "--out", (base / "B").string(), "--quiet"}, kTimeout);
  EXPECT_EQ(replay.code, 2) << replay.output;
  EXPECT_NE(replay.output.find("ended at seq 100"), std::string::npos) << replay.output;
  EXPECT_FALSE(fs::exists(base / "B"));
  fs::remove_all(base);
}

TEST(ReplayCli, RecordIntoAFolderThatExistsIsRefusedAndLeavesItAlone) {
  const fs::path base = TempDir("exists");
  for (const bool empty : {true, false}) {
    const fs::path record = base / (empty ? "empty" : "full");
    fs::create_directories(record);
    if (!empty) std::ofstream(record / "notes.txt") << "mine\n";
    const testing::ProcessRun run = TwinbenchArgs(
        {"run", Scenario("tracker_single_reinovo"), "--out", (base / "A").string(), "--record",
         record.string(), "--quiet"},
        kTimeout);
    EXPECT_EQ(run.code, 2) << run.output;
    EXPECT_NE(run.output.find("--record"), std::string::npos) << run.output;
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(record)) names.push_back(e.path().filename());
    EXPECT_EQ(names, empty ? std::vector<std::string>{} : std::vector<std::string>{"notes.txt"});
    if (!empty) {
      EXPECT_EQ(ReadFile(record / "notes.txt"), "mine\n");
    }
    EXPECT_FALSE(fs::exists(base / "A"));
  }
  // Inside --out, or --out inside it: refused too.
  const testing::ProcessRun inside = TwinbenchArgs(
      {"run", Scenario("tracker_single_reinovo"), "--out", (base / "A").string(), "--record",
       (base / "A" / "rec").string(), "--quiet"},
      kTimeout);
  EXPECT_EQ(inside.code, 2) << inside.output;
  EXPECT_NE(inside.output.find("overlap"), std::string::npos) << inside.output;
  fs::remove_all(base);
}

}  // namespace
}  // namespace twin
