// The real laser-tracker data of ../shared/data/motoman_leica/ (not in the repository: the
// public ctu-vras/multirobot-calibration repository has it; docs/reference/file-formats.md,
// "Tracker files"). Skipped with a message when the files are absent.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_run.h"

namespace twin {
namespace {
namespace fs = std::filesystem;

const fs::path kData = fs::path(TWIN_SOURCE_DIR) / ".." / "shared" / "data" / "motoman_leica";
const std::string kModel = std::string(TWIN_SOURCE_DIR) + "/models/motoman_sda10_right.yaml";

nlohmann::json Identify(const std::string& file, int seed, const std::string& validate = "",
                        bool diagnosis = false, int max_effects = 0) {
  const fs::path out = fs::path(::testing::TempDir()) / ("real_tracker_" + std::to_string(seed) +
                                                         fs::path(file).stem().string());
  fs::remove_all(out);
  std::vector<std::string> args = {"identify", "--model", kModel, "--measurements",
                                   (kData / file).string(), "--ignore-column", "q_E_rad",
                                   "--seed", std::to_string(seed), "--out", out.string()};
  if (!diagnosis) args.push_back("--no-diagnosis");  // its own test below
  if (max_effects > 0) {
    args.push_back("--diagnosis-max-effects");
    args.push_back(std::to_string(max_effects));
  }
  if (!validate.empty()) {
    args.push_back("--validate");
    args.push_back((kData / validate).string());
  }
  // 900 s: with the stage-5 candidates (issue 39) a diagnosis of these files takes 1-3 min alone
  // on 2 cores, up to twice that beside the other tests of a parallel ctest; a hang is still
  // caught.
  const testing::ProcessRun r = testing::TwinbenchArgs(args, 900);
  EXPECT_EQ(r.code, 0) << r.output;
  std::ifstream in(out / "report.json");
  return nlohmann::json::parse(in, nullptr, false);
}

// Target of issue 11: the cube file's held-out random RMS <= 0.08 mm with the geometric model,
// on several random splits (seeds 1-3; 1-7 measured 0.0715-0.0761 mm), and far below the
// nominal model's (the tracker pose and reflector fitted: ~0.25 mm).
TEST(RealTrackerData, MotomanCubeHeldOutRandomRmsIsWithinTarget) {
  if (!fs::exists(kData / "right_arm_cube.csv")) {
    GTEST_SKIP() << "real tracker data absent: " << kData.string()
                 << " (get it from github.com/ctu-vras/multirobot-calibration)";
  }
  for (int seed = 1; seed <= 3; ++seed) {
    const nlohmann::json j = Identify("right_arm_cube.csv", seed);
    ASSERT_TRUE(j.is_object());
    const auto& random = j["heldout"]["random"];
    const double after = random["after"]["rms_mm"], before = random["before"]["rms_mm"];
    std::printf("[ measured ] cube, seed %d: held-out random RMS %.4f -> %.4f mm, region %.4f -> "
                "%.4f mm\n", seed, before, after,
                j["heldout"]["region"]["before"]["rms_mm"].get<double>(),
                j["heldout"]["region"]["after"]["rms_mm"].get<double>());
    EXPECT_LE(after, 0.08);
    EXPECT_GT(before, 2 * after);
    EXPECT_EQ(random["after"]["poses"], 42);
    EXPECT_FALSE(j["unidentifiable"].empty());
    EXPECT_GT(j["condition_number"].get<double>(), 1.0);
    EXPECT_EQ(j["parameters"].size(), 35u);
  }
}

// The wide file is reported the same way; its figures (docs/results/real_data_discovery.md) show
// what the geometric model misses there. The cube file trained and the wide one held out across
// sessions: a calibrated model that is worse on a held-out part must carry the flag and the
// warning.
TEST(RealTrackerData, MotomanWideIsReportedAndWorseHeldOutPartsAreFlagged) {
  if (!fs::exists(kData / "right_arm_wide.csv")) {
    GTEST_SKIP() << "real tracker data absent: " << kData.string();
  }
  const nlohmann::json j = Identify("right_arm_wide.csv", 1, "right_arm_cube.csv");
  ASSERT_TRUE(j.is_object());
  for (const char* split : {"random", "region"}) {
    const auto& s = j["heldout"][split];
    const bool worse = s["worse"];
    EXPECT_EQ(worse, s["after"]["rms_mm"].get<double>() > s["before"]["rms_mm"].get<double>());
    bool warned = false;
    for (const auto& w : j["warnings"]) {
      warned = warned || w.get<std::string>().find(std::string("held-out ") + split) == 0;
    }
    EXPECT_EQ(worse, warned) << split;
  }
}

// The second session and the black box (issue 39): the wide file trained, the cube file as
// the second session. Every new key is there and finite; a step flagged worse on the session
// is warned of by its term's name, and only such a step.
void ExpectSecondSessionAndBlackBox(const nlohmann::json& j) {
  ASSERT_TRUE(j.is_object());
  const auto finite = [](const nlohmann::json& v) {
    return v.is_number() && std::isfinite(v.get<double>()) && v.get<double>() > 0.0;
  };
  const nlohmann::json& session = j["heldout"]["session"];
  for (const char* model : {"nominal", "geometric", "discovered"}) {
    EXPECT_TRUE(finite(session[model]["rms_mm"])) << model << ": " << session[model];
    EXPECT_TRUE(finite(session[model]["rms_sd_mm"])) << model;
  }
  EXPECT_EQ(session["points"], 212);
  EXPECT_EQ(session["halvings"], 20);
  const nlohmann::json& d = j["diagnosis"];
  for (const auto& s : d["steps"]) {
    EXPECT_TRUE(finite(s["session_rms_mm"])) << s;
    bool warned = false;
    if (!s["accepted"].is_null()) {
      for (const auto& w : j["warnings"]) {
        const std::string text = w;
        warned = warned || (text.find("second session") == 0 &&
                            text.find(s["accepted"].get<std::string>()) != std::string::npos);
      }
    }
    EXPECT_EQ(s["session_worse"].get<bool>(), warned) << s;
  }
  // The calibration's geometric model and the diagnosis's starting model are the same
  // identification of the same points, scored over the same halvings (one --seed): equal but
  // for the solver's stopping point (1e-4 relative: a tenth of a micrometre here).
  EXPECT_NEAR(session["geometric"]["rms_mm"].get<double>(),
              d["session"]["start"]["rms_mm"].get<double>(),
              1e-4 * session["geometric"]["rms_mm"].get<double>());
  EXPECT_TRUE(finite(d["black_box"]["heldout_rms_mm"])) << d["black_box"];
  EXPECT_TRUE(finite(d["black_box"]["session_rms_mm"])) << d["black_box"];
  std::printf("[ measured ] wide trained, cube as the second session: nominal %.4f, geometric "
              "%.4f, discovered %.4f mm; black box region %.4f mm, session %.4f mm\n",
              session["nominal"]["rms_mm"].get<double>(),
              session["geometric"]["rms_mm"].get<double>(),
              session["discovered"]["rms_mm"].get<double>(),
              d["black_box"]["heldout_rms_mm"].get<double>(),
              d["black_box"]["session_rms_mm"].get<double>());
}


// The wide file identified with the cube file as its second session, diagnosis on.
// Up to 3 effects (the default is 10: the search ends on its tests, after six steps and about
// 590 s on this file, docs/results/real_data_discovery.md): three steps test the second
// session's per-step scores and the worse-step flag in a third of the time.
nlohmann::json WideWithCubeAsSecondSession() {
  return Identify("right_arm_wide.csv", 1, "right_arm_cube.csv", true, 3);
}

// Model discovery on both files (issue 15), the wide one with the cube one as its second
// session (issue 39: ExpectSecondSessionAndBlackBox). The wide file: a verdict, and when effects are
// added the discovered model's region-disjoint held-out RMS at most 0.8 times the geometric
// model's (the target; an independent analysis found gravity-related terms worth about
// 30 % there), or an "unexplained" with its evidence. The cube file: a verdict with its
// evidence; whatever is added must not make the held-out error worse.
TEST(RealTrackerData, MotomanDiagnosisGivesAVerdictOnBothFilesAndScoresTheSecondSession) {
  if (!fs::exists(kData / "right_arm_wide.csv") || !fs::exists(kData / "right_arm_cube.csv")) {
    GTEST_SKIP() << "real tracker data absent: " << kData.string();
  }
  for (const char* file : {"right_arm_wide.csv", "right_arm_cube.csv"}) {
    // The wide file's run is the second-session test's (one diagnosis of it, not two). The
    // cube file's stops after its first effect: each further step tests every candidate again
    // (with the defaults on both files this test took 673 s in a clean-clone CI run beside
    // other work; a verdict with its evidence needs one step; docs/results/
    // real_data_discovery.md has the full runs).
    const nlohmann::json j = std::string(file) == "right_arm_wide.csv"
                                 ? WideWithCubeAsSecondSession()
                                 : Identify(file, 1, "", true, 1);
    ASSERT_TRUE(j.is_object()) << file;
    const nlohmann::json& d = j["diagnosis"];
    const std::string verdict = d["verdict"];
    const double start = d["heldout_rms_mm"]["start"], found = d["heldout_rms_mm"]["discovered"];
    std::printf("[ measured ] %s: %s, region-disjoint held-out RMS %.4f -> %.4f mm\n", file,
                verdict.c_str(), start, found);
    ASSERT_TRUE(verdict == "consistent_with_noise" || verdict == "effects_added" ||
                verdict == "partly_explained" || verdict == "unexplained")
        << verdict;
    EXPECT_FALSE(d["reason"].get<std::string>().empty());
    EXPECT_GT(d["noise_floor_mm"].get<double>(), 0.0);
    EXPECT_FALSE(d["candidates"].empty());
    if (verdict == "effects_added" || verdict == "partly_explained") {
      EXPECT_FALSE(d["effects_added"].empty());
      EXPECT_LE(found, start);
      for (const auto& e : d["effects_added"]) EXPECT_TRUE(e["accepted"].get<bool>());
      if (std::string(file) == "right_arm_wide.csv") {
        EXPECT_LE(found, 0.8 * start);
      }
    }
    if (verdict == "unexplained" || verdict == "partly_explained") {
      EXPECT_FALSE(d["unexplained_evidence"].empty());
      EXPECT_FALSE(d["residual_maps"].empty());
    }
    if (std::string(file) == "right_arm_wide.csv") ExpectSecondSessionAndBlackBox(j);
  }
}

}  // namespace
}  // namespace twin
