// `twinbench run --cell grpc://...` (remote/grpc_cell.h, bench/runs/bench_cell.cc) against a
// `twinbench serve-cell` subprocess over TLS with client certificates: the report equals the
// in-process run's, key for key and bit for bit, except the wall-clock timings (timing_s), and
// the replay of the remote run's recording equals it too.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "../bench/cli_run.h"
#include "serve_cell_process.h"

namespace twin::testing {
namespace {

// Wall-clock keys, as bench/report/trial_record.cc tells them from figures: timing_s, time_s
// (a stage's compute time) and *_time_s (planning's wait).
bool IsWallClockKey(const std::string& key) {
  return key == "timing_s" || key == "time_s" ||
         (key.size() > 7 && key.compare(key.size() - 7, 7, "_time_s") == 0);
}

// report.json without its wall-clock keys, wherever they are: everything else is compared
// exactly.
nlohmann::json ReportWithoutTimes(const std::string& path) {
  nlohmann::json j = nlohmann::json::parse(ReadText(path));
  std::function<void(nlohmann::json&)> strip = [&](nlohmann::json& node) {
    if (node.is_object()) {
      std::vector<std::string> times;
      for (auto& [key, value] : node.items()) {
        if (IsWallClockKey(key)) times.push_back(key);
      }
      for (const std::string& key : times) node.erase(key);
      for (auto& [key, value] : node.items()) strip(value);
    } else if (node.is_array()) {
      for (auto& value : node) strip(value);
    }
  };
  strip(j);
  return j;
}

// First differing path of two JSON values, for the failure message.
std::string FirstDifference(const nlohmann::json& a, const nlohmann::json& b) {
  const nlohmann::json patch = nlohmann::json::diff(a, b);
  return patch.empty() ? "" : patch.front().dump();
}

// The in-process run and the remote run of `scenario` (TLS, client certificate, recorded with
// --record) give the same report.json but for timing_s; so does the replay of the recording
// (issue 40: the report equals the in-process run's, and the replay equals the live run's).
void ExpectRemoteReportEqualsLocal(const std::string& scenario, double timeout_s) {
  if (!HaveOpenssl()) GTEST_SKIP() << "no openssl CLI to make certificates";
  TempDir dir;
  ASSERT_TRUE(MakeCertificates(dir.path())) << "openssl failed";
  const std::string path = std::string(TWIN_SOURCE_DIR) + "/" + scenario;
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

  const nlohmann::json a = ReportWithoutTimes(dir / "local/report.json");
  const nlohmann::json b = ReportWithoutTimes(dir / "remote/report.json");
  EXPECT_EQ(a, b) << "first difference: " << FirstDifference(a, b);
  const nlohmann::json c = ReportWithoutTimes(dir / "replayed/report.json");
  EXPECT_EQ(b, c) << "replay against the live remote run, first difference: "
                  << FirstDifference(b, c);
  // The comparison compares something: the report has its results.
  EXPECT_TRUE(a.contains("scenario") && a.contains("acceptance")) << a.dump().substr(0, 500);
  EXPECT_GT(a.dump().size(), 10000u);
}

TEST(RemoteRun, TrackerReportEqualsInProcessOverTls) {
  ExpectRemoteReportEqualsLocal("scenarios/tracker_single_reinovo.yaml", 300);
}

// About a minute a run on 2 cores: labelled slow (TWINBENCH_SLOW_GTESTS, RemoteRun.*Paper*).
TEST(RemoteRun, PaperReportEqualsInProcessOverTls) {
  ExpectRemoteReportEqualsLocal("scenarios/paper_reinovo.yaml", 600);
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

// The optical-axis run scores against the twin's truth and has no report without it yet: on a
// cell without truth it refuses at the start (exit 2 naming --cell), before anything moves.
TEST(RemoteRun, OpticalAxisRunOnACellWithoutTruthIsRefusedAtTheStart) {
  const std::string path = std::string(TWIN_SOURCE_DIR) + "/scenarios/study_small.yaml";
  TempDir dir;
  ServeCellProcess server({path, "--listen", "127.0.0.1:0", "--no-truth"});
  ASSERT_GT(server.port(), 0) << server.output();
  const ProcessRun r = TwinbenchArgs(
      {"run", path, "--out", dir / "out", "--quiet", "--cell",
       "grpc://127.0.0.1:" + std::to_string(server.port())},
      120);
  EXPECT_TRUE(r.exited && r.code == 2) << r.output;
  EXPECT_NE(r.output.find("error: --cell"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("no truth"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir / "out"));
}

}  // namespace
}  // namespace twin::testing
