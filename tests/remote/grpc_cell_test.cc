// `twinbench run --cell grpc://...` (remote/grpc_cell.h, bench/runs/bench_cell.cc) against a
// `twinbench serve-cell` subprocess over TLS with client certificates: the report equals the
// in-process run's, key for key and bit for bit, except the wall-clock timings (timing_s), and
// the replay of the remote run's recording equals it too.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "../bench/cli_run.h"
#include "report_timings.h"
#include "serve_cell_process.h"

namespace twin::testing {
namespace {

// First differing path of two JSON values, for the failure message.
std::string FirstDifference(const nlohmann::json& a, const nlohmann::json& b) {
  const nlohmann::json patch = nlohmann::json::diff(a, b);
  return patch.empty() ? "" : patch.front().dump();
}

// The in-process run and the remote run of the scenario file `path` (TLS, client certificate,
// recorded with --record) give the same report.json but for timing_s; so does the replay of
// the recording (issue 40: the report equals the in-process run's, and the replay equals the
// live run's). The report must hold `keys` and be at least `min_bytes` long, so that the
// comparison compares something.
void ExpectRemoteReportEqualsLocalAt(const std::string& path, double timeout_s,
                                     const std::vector<std::string>& keys,
                                     std::size_t min_bytes) {
  if (!HaveOpenssl()) GTEST_SKIP() << "no openssl CLI to make certificates";
  TempDir dir;
  ASSERT_TRUE(MakeCertificates(dir.path())) << "openssl failed";
  const ProcessRun local =
      TwinbenchArgs({"run", path, "--out", dir / "local", "--quiet"}, timeout_s);
  ASSERT_TRUE(local.exited && local.code == 0) << local.output;

  ServeCellProcess server({path, "--listen", "127.0.0.1:0", "--tls-cert", dir / "server.pem",
                           "--tls-key", dir / "server.key", "--client-ca", dir / "ca.pem"});
  ASSERT_GT(server.port(), 0) << server.output();
  const ProcessRun remote = TwinbenchArgs(
      {"run", path, "--out", dir / "remote", "--quiet", "--cell",
       "grpc://127.0.0.1:" + std::to_string(server.port()), "--cell-ca", dir / "ca.pem",
       "--cell-cert", dir / "client.pem", "--cell-key", dir / "client.key", "--record",
       dir / "recording"},
      timeout_s);
  ASSERT_TRUE(remote.exited && remote.code == 0) << remote.output << server.output();
  EXPECT_EQ(server.Stop(SIGTERM), 0) << server.output();
  const ProcessRun replay = TwinbenchArgs(
      {"replay", dir / "recording", "--out", dir / "replayed", "--quiet"}, timeout_s);
  ASSERT_TRUE(replay.exited && replay.code == 0) << replay.output;

  const nlohmann::json a = ReportWithoutTimings(dir / "local/report.json");
  const nlohmann::json b = ReportWithoutTimings(dir / "remote/report.json");
  EXPECT_EQ(a, b) << "first difference: " << FirstDifference(a, b);
  const nlohmann::json c = ReportWithoutTimings(dir / "replayed/report.json");
  EXPECT_EQ(b, c) << "replay against the live remote run, first difference: "
                  << FirstDifference(b, c);
  // The comparison compares something: the report has its results.
  for (const std::string& key : keys) EXPECT_TRUE(a.contains(key)) << key;
  EXPECT_GT(a.dump().size(), min_bytes);
}

// As above for a scenario of the repository, whose report has its acceptance criteria.
void ExpectRemoteReportEqualsLocal(const std::string& scenario, double timeout_s) {
  ExpectRemoteReportEqualsLocalAt(std::string(TWIN_SOURCE_DIR) + "/" + scenario, timeout_s,
                                  {"scenario", "acceptance"}, 10000);
}

// scenarios/<name>.yaml written into `dir` with `trials: N` made `trials: 1` (a served cell is
// one twin) and the model paths made absolute; returns its path.
std::string OneTrialCopy(const std::string& name, const std::filesystem::path& dir) {
  std::string s = ReadText(std::string(TWIN_SOURCE_DIR) + "/scenarios/" + name + ".yaml");
  const std::size_t trials = s.find("trials: ");
  if (trials != std::string::npos) {
    s.replace(trials, s.find('\n', trials) - trials, "trials: 1");
  }
  for (std::size_t at = s.find("../models/"); at != std::string::npos;
       at = s.find("../models/", at)) {
    s.replace(at, 3, std::string(TWIN_SOURCE_DIR) + "/");
  }
  const std::string path = (dir / (name + ".yaml")).string();
  std::ofstream(path) << s;
  return path;
}

TEST(RemoteRun, TrackerReportEqualsInProcessOverTls) {
  ExpectRemoteReportEqualsLocal("scenarios/tracker_single_reinovo.yaml", 300);
}

// About a minute a run on 2 cores: labelled slow (TWINBENCH_SLOW_GTESTS, RemoteRun.*Paper*).
TEST(RemoteRun, PaperReportEqualsInProcessOverTls) {
  ExpectRemoteReportEqualsLocal("scenarios/paper_reinovo.yaml", 600);
}

// The handclasp (Gan et al. 2014) drives the served twin through the Cell protocol; the twin's
// simulated operator is set over the bench channel (SetOperatorError), as in process.
TEST(RemoteRun, HandclaspReportEqualsInProcessOverTls) {
  TempDir dir;
  const std::string path = OneTrialCopy("gan2014_floor_floor", dir.path());
  ExpectRemoteReportEqualsLocalAt(path, 300, {"scenario", "base_frame", "procedure"}, 3000);
}

// `text` with each `from` replaced by its `to` (each must be there); a line equal to a `from`
// whose `to` is empty drops that line and the more deeply indented ones under it (a section).
std::string Altered(std::string text,
                    const std::vector<std::pair<std::string, std::string>>& changes) {
  for (const auto& [from, to] : changes) {
    const std::size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    if (at == std::string::npos) continue;
    if (!to.empty()) {
      text.replace(at, from.size(), to);
      continue;
    }
    std::size_t end = text.find('\n', at) + 1;
    const std::size_t indent = from.find_first_not_of(' ');
    while (end < text.size() && text.compare(end, indent + 1, std::string(indent + 1, ' ')) == 0) {
      end = text.find('\n', end) + 1;
    }
    text.erase(at, end - at);
  }
  return text;
}

// On a served cell the bench reads the truth from the cell alone: a client scenario whose
// truth-only values differ (no geometry errors, other true tips, robot 2's true base 10 mm
// elsewhere) gives the in-process report of the served scenario, to the bit. The told values
// (the handclasp section, the nominal models, the initial joints) are the served scenario's.
TEST(RemoteRun, HandclaspOnAServedCellReadsOnlyWhatItIsToldFromTheScenario) {
  TempDir dir;
  const std::string path = OneTrialCopy("gan2014_floor_floor", dir.path());
  const std::string told = dir / "told.yaml";
  std::ofstream(told) << Altered(
      ReadText(path),
      {{"  effects:\n", ""},
       {"r1: {xyz_mm: [0, 0, 200], rpy_deg: [0, 0, 0], length_mm: 180",
        "r1: {xyz_mm: [0, 0, 215], rpy_deg: [0, 0, 0], length_mm: 195"},
       {"base_from_robot1: {xyz_mm: [37.9, 1476.5, 54.5]",
        "base_from_robot1: {xyz_mm: [47.9, 1476.5, 54.5]"}});
  const ProcessRun local = TwinbenchArgs({"run", path, "--out", dir / "local", "--quiet"}, 120);
  ASSERT_TRUE(local.exited && local.code == 0) << local.output;
  ServeCellProcess server({path, "--listen", "127.0.0.1:0"});
  ASSERT_GT(server.port(), 0) << server.output();
  const ProcessRun remote = TwinbenchArgs(
      {"run", told, "--out", dir / "remote", "--quiet", "--cell",
       "grpc://127.0.0.1:" + std::to_string(server.port())},
      120);
  ASSERT_TRUE(remote.exited && remote.code == 0) << remote.output;
  const nlohmann::json a = ReportWithoutTimings(dir / "local/report.json");
  const nlohmann::json b = ReportWithoutTimings(dir / "remote/report.json");
  EXPECT_EQ(a, b) << "first difference: " << FirstDifference(a, b);
  // The altered copy, run in process, is another twin: its report differs (the test can fail).
  const ProcessRun other = TwinbenchArgs({"run", told, "--out", dir / "other", "--quiet"}, 120);
  ASSERT_TRUE(other.exited && other.code == 0) << other.output;
  EXPECT_NE(a, ReportWithoutTimings(dir / "other/report.json"));
}

// A handclasp batch of several trials runs each on its own twin: on a served cell (one twin)
// it is refused before anything moves (exit 2 naming the trials key).
TEST(RemoteRun, HandclaspBatchOnAServedCellIsRefused) {
  TempDir dir;
  const std::string path = std::string(TWIN_SOURCE_DIR) + "/scenarios/gan2014_floor_floor.yaml";
  ServeCellProcess server({path, "--listen", "127.0.0.1:0"});
  ASSERT_GT(server.port(), 0) << server.output();
  const ProcessRun r = TwinbenchArgs(
      {"run", path, "--out", dir / "out", "--quiet", "--cell",
       "grpc://127.0.0.1:" + std::to_string(server.port())},
      120);
  EXPECT_TRUE(r.exited && r.code == 2) << r.output;
  EXPECT_NE(r.output.find("scenario.handclasp.trials"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
}

// `run --cell` against a TLS server without --cell-ca: refused, exit 2, naming --cell.
TEST(RemoteRun, WithoutCredentialsExitsTwoNamingCell) {
  if (!HaveOpenssl()) GTEST_SKIP() << "no openssl CLI to make certificates";
  TempDir dir;
  ASSERT_TRUE(MakeCertificates(dir.path())) << "openssl failed";
  const std::string path = std::string(TWIN_SOURCE_DIR) + "/scenarios/tracker_single_reinovo.yaml";
  ServeCellProcess server({path, "--listen", "127.0.0.1:0", "--tls-cert", dir / "server.pem",
                           "--tls-key", dir / "server.key", "--client-ca", dir / "ca.pem"});
  ASSERT_GT(server.port(), 0) << server.output();
  const std::string cell = "grpc://127.0.0.1:" + std::to_string(server.port());
  // Plaintext to a TLS server.
  ProcessRun r = TwinbenchArgs({"run", path, "--out", dir / "a", "--quiet", "--cell", cell}, 60);
  EXPECT_TRUE(r.exited && r.code == 2) << r.output;
  EXPECT_NE(r.output.find("error: --cell " + cell), std::string::npos) << r.output;
  // TLS but no client certificate.
  r = TwinbenchArgs({"run", path, "--out", dir / "b", "--quiet", "--cell", cell, "--cell-ca",
                     dir / "ca.pem"},
                    60);
  EXPECT_TRUE(r.exited && r.code == 2) << r.output;
  EXPECT_NE(r.output.find("error: --cell " + cell), std::string::npos) << r.output;
  // A malformed address and a missing credential file name their flags.
  r = TwinbenchArgs({"run", path, "--out", dir / "c", "--quiet", "--cell", "grpc://nohost"}, 60);
  EXPECT_TRUE(r.exited && r.code == 2) << r.output;
  EXPECT_NE(r.output.find("error: --cell"), std::string::npos) << r.output;
  r = TwinbenchArgs({"run", path, "--out", dir / "d", "--quiet", "--cell", cell, "--cell-ca",
                     dir / "missing.pem"},
                    60);
  EXPECT_TRUE(r.exited && r.code == 2) << r.output;
  EXPECT_NE(r.output.find("error: --cell-ca"), std::string::npos) << r.output;
  // A credential without --cell is refused rather than ignored.
  r = TwinbenchArgs({"run", path, "--out", dir / "e", "--quiet", "--cell-ca", dir / "ca.pem"}, 60);
  EXPECT_TRUE(r.exited && r.code == 2) << r.output;
  EXPECT_NE(r.output.find("error: --cell-ca"), std::string::npos) << r.output;
  // Nothing came of the refused runs.
  EXPECT_FALSE(std::filesystem::exists(dir / "a")) << r.output;
  // And the server is still there for a client with credentials.
  auto stub = RawStub(server.address(), dir / "ca.pem", dir / "client.pem", dir / "client.key");
  pb::DescribeResponse d;
  EXPECT_TRUE(stub->Describe(Context().get(), pb::DescribeRequest(), &d).ok());
  EXPECT_EQ(d.cell_name(), "tracker_single_reinovo");
}

// tracker_single_reinovo.yaml as a real cell's user writes it: only what the estimator is told
// (the nominal model, the told reflector, the procedure's settings), without the twin's truth
// (its `effects:` and `tracker:` sections), the model path made absolute.
std::string ToldOnlyTrackerScenario(const std::string& full) {
  std::string told;
  std::istringstream in(ReadText(full));
  bool skipping = false;
  for (std::string line; std::getline(in, line);) {
    if (line == "  effects:" || line == "  tracker:") {
      skipping = true;
      continue;
    }
    if (skipping && line.rfind("    ", 0) == 0) continue;  // the section's body
    skipping = false;
    const std::string rel = "../models/";
    const size_t at = line.find(rel);
    if (at != std::string::npos) {
      line.replace(at, rel.size(), std::string(TWIN_SOURCE_DIR) + "/models/");
    }
    told += line + "\n";
  }
  return told;
}

// A served cell without truth (a real cell's case): the tracker run measures, identifies and
// diagnoses, reports no figure against the truth, and leaves the criterion on the truth
// unjudged. Its estimates are those of the in-process run on the same twin (the same points).
TEST(RemoteRun, TrackerRunOnACellWithoutTruthReportsTheEstimatesOnly) {
  const std::string path = std::string(TWIN_SOURCE_DIR) + "/scenarios/tracker_single_reinovo.yaml";
  TempDir dir;
  const std::string told = dir / "told_only.yaml";
  {
    std::ofstream out(told);
    out << ToldOnlyTrackerScenario(path);
  }
  const std::string told_text = ReadText(told);
  ASSERT_EQ(told_text.find("tracker:\n"), std::string::npos) << told_text;
  ASSERT_EQ(told_text.find("geometry_errors"), std::string::npos) << told_text;
  ASSERT_NE(told_text.find("tracker_calibration:"), std::string::npos) << told_text;

  const ProcessRun local = TwinbenchArgs({"run", path, "--out", dir / "local", "--quiet"}, 300);
  ASSERT_TRUE(local.exited && local.code == 0) << local.output;
  ServeCellProcess server({path, "--listen", "127.0.0.1:0", "--no-truth"});
  ASSERT_GT(server.port(), 0) << server.output();
  const ProcessRun r = TwinbenchArgs(
      {"run", told, "--out", dir / "out", "--cell",
       "grpc://127.0.0.1:" + std::to_string(server.port())},
      300);
  ASSERT_TRUE(r.exited && r.code == 0) << r.output;
  EXPECT_NE(r.output.find("truth_position_error_mm.rigid.after.rms not judged: the cell has no "
                          "truth"),
            std::string::npos)
      << r.output;
  const nlohmann::json a = nlohmann::json::parse(ReadText(dir / "local/report.json"));
  const nlohmann::json b = nlohmann::json::parse(ReadText(dir / "out/report.json"));
  EXPECT_EQ(b["truth"]["available"], false) << b.dump().substr(0, 400);
  EXPECT_FALSE(b.contains("truth_position_error_mm"));
  EXPECT_FALSE(b.contains("truth_position_error_mm_physical"));
  EXPECT_TRUE(b["identifiable_combinations"]["within_3_sigma"].is_null());
  // No criterion left to judge: the report has no acceptance results.
  EXPECT_TRUE(!b.contains("acceptance") || b.at("acceptance").empty()) << b.dump().substr(0, 400);
  // The same measurements, so the same estimates, to the bit.
  ASSERT_EQ(a["parameters"].size(), b["parameters"].size());
  ASSERT_GT(a["parameters"].size(), 0u);
  for (size_t i = 0; i < a["parameters"].size(); ++i) {
    EXPECT_EQ(a["parameters"][i]["estimated"], b["parameters"][i]["estimated"]) << i;
    EXPECT_FALSE(a["parameters"][i]["true"].is_null());
    EXPECT_TRUE(b["parameters"][i]["true"].is_null());
  }
  EXPECT_EQ(a["heldout"], b["heldout"]);
  EXPECT_EQ(a["diagnosis"]["verdict"], b["diagnosis"]["verdict"]);
  EXPECT_EQ(ReadText(dir / "local/measurements.csv"), ReadText(dir / "out/measurements.csv"));
}

// On a cell without truth (a real cell's case, here `serve-cell --no-truth`) the optical-axis
// and the handclasp runs report their estimates alone: truth.available false, every true
// value and error against truth null, nothing scored. The estimates are those of the
// in-process run on the same twin (the same measurements), to the bit, though the client's
// optical-axis scenario has other values where only the twin reads them (no effects, another
// hand-eye pose, focal length and base of robot 2), as a real cell's user writes the drawing's.
TEST(RemoteRun, OpticalAxisAndHandclaspOnACellWithoutTruthReportTheEstimatesAlone) {
  TempDir dir;
  const std::string handclasp = OneTrialCopy("gan2014_floor_floor", dir.path());
  const std::string optical = OneTrialCopy("study_small", dir.path());
  const std::string told = dir / "study_small_told.yaml";
  std::ofstream(told) << Altered(
      ReadText(optical),
      {{"  effects:\n", ""},
       {"hand_eye: {xyz_mm: [62.1, -58.4, -24.3]", "hand_eye: {xyz_mm: [60.1, -58.4, -24.3]"},
       {"fx: 521.44375", "fx: 525.0"},
       {"base_from_robot1: {xyz_mm: [1203.2, -2.6, 0.8]",
        "base_from_robot1: {xyz_mm: [1208.2, -2.6, 0.8]"}});
  for (const std::string& path : {optical, handclasp}) {
    const std::filesystem::path local = dir / "local", out = dir / "out";
    std::filesystem::remove_all(local);
    std::filesystem::remove_all(out);
    const ProcessRun in_process =
        TwinbenchArgs({"run", path, "--out", local, "--quiet"}, 120);
    ASSERT_TRUE(in_process.exited && in_process.code == 0) << in_process.output;
    ServeCellProcess server({path, "--listen", "127.0.0.1:0", "--no-truth"});
    ASSERT_GT(server.port(), 0) << server.output();
    const ProcessRun r = TwinbenchArgs(
        {"run", path == optical ? told : path, "--out", out, "--quiet", "--cell",
         "grpc://127.0.0.1:" + std::to_string(server.port())},
        120);
    ASSERT_TRUE(r.exited && r.code == 0) << path << "\n" << r.output;
    const nlohmann::json a = nlohmann::json::parse(ReadText(local / "report.json"));
    const nlohmann::json b = nlohmann::json::parse(ReadText(out / "report.json"));
    EXPECT_FALSE(a.contains("truth")) << path;
    ASSERT_TRUE(b.contains("truth")) << path;
    EXPECT_EQ(b["truth"]["available"], false);
    if (path == optical) {
      const nlohmann::json& ra = a["robots"]["r2"];
      const nlohmann::json& rb = b["robots"]["r2"];
      ASSERT_EQ(ra["parameters"].size(), rb["parameters"].size());
      ASSERT_GT(ra["parameters"].size(), 0u);
      for (size_t i = 0; i < ra["parameters"].size(); ++i) {
        EXPECT_EQ(ra["parameters"][i]["estimated"], rb["parameters"][i]["estimated"]) << i;
        EXPECT_FALSE(ra["parameters"][i]["true"].is_null()) << i;
        EXPECT_TRUE(rb["parameters"][i]["true"].is_null()) << i;
      }
      EXPECT_EQ(ra["misaligned_error_mm"], rb["misaligned_error_mm"]);
      EXPECT_EQ(a["intrinsics"]["estimated"], b["intrinsics"]["estimated"]);
      EXPECT_TRUE(b["intrinsics"]["true"]["fx"].is_null());
      EXPECT_TRUE(b["intrinsics"]["error_px"]["fx"].is_null());
      EXPECT_TRUE(rb["scale"]["true"].is_null());
      EXPECT_TRUE(rb["identifiable_combinations"]["rms_error"].is_null());
      EXPECT_TRUE(ra.contains("truth_position_error_mm"));
      for (const auto& [key, value] : rb.items()) {
        if (key.rfind("truth_", 0) != 0) continue;
        EXPECT_EQ(key, "truth_position_error_mm_physical") << "a figure against truth";
        EXPECT_TRUE(value.contains("skipped")) << value.dump();
      }
      // The identified model and the measurements are written as in process.
      EXPECT_EQ(ReadText(local / "identified_r2.yaml"), ReadText(out / "identified_r2.yaml"));
      EXPECT_EQ(ReadText(local / "measurements.csv"), ReadText(out / "measurements.csv"));
    } else {
      const nlohmann::json& fa = a["base_frame"];
      const nlohmann::json& fb = b["base_frame"];
      for (const char* estimate : {"general", "constrained"}) {
        for (const char* key : {"xyz_mm", "zyz_deg", "rms_residual_mm"}) {
          EXPECT_EQ(fa[estimate][key], fb[estimate][key]) << estimate << " " << key;
        }
        EXPECT_FALSE(fa[estimate]["e_tran_mm"].is_null()) << estimate;
        EXPECT_TRUE(fb[estimate]["e_tran_mm"].is_null()) << estimate;
        EXPECT_TRUE(fb[estimate]["e_rot_deg"].is_null()) << estimate;
      }
      EXPECT_EQ(fa["contacts"], fb["contacts"]);
      for (const char* truth_only : {"truth", "physical_truth", "pendant_tip_error",
                                     "scoring_frame", "seed"}) {
        EXPECT_FALSE(fb.contains(truth_only)) << truth_only;
      }
      // The coupled-motion check would drive robot 2's tip onto robot 1's through an unchecked
      // estimate, and nothing would measure it: skipped.
      EXPECT_EQ(fa["coupled_motion"]["status"], "ok");
      EXPECT_EQ(fb["coupled_motion"]["status"], "skipped");
      // Its operator is a person: no simulated alignment error to report.
      EXPECT_EQ(fa["operator_error_mm"], 0.5);
      EXPECT_TRUE(fb["operator_error_mm"].is_null());
    }
  }
}

}  // namespace
}  // namespace twin::testing
