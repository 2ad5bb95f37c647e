// `twinbench identify` on a tracker file with model discovery (issue 15): the report's
// diagnosis section, --no-diagnosis, --declare and their refusals. The file is written here
// from a known arm: the nominal Reinovo r2 with 0.5 mm / 0.05 deg on each DH parameter, a
// compliant joint 2 (3e-5 rad/(N m)) when asked, and 10 um of noise (stated in sigma_m).
#include "bench/runs/tracker_identify_run.h"

#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <random>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "bench/io/model_loader.h"
#include "calib/common/errors.h"
#include "calib/model/robot_model.h"

namespace twin {
namespace {
namespace fs = std::filesystem;

const std::string kModel = std::string(TWIN_SOURCE_DIR) + "/models/reinovo_r2.yaml";

// `held_joint` (0-based, -1 none) is held at mid-range in every row.
fs::path WriteTrackerFile(const std::string& name, bool compliant, int points = 150,
                          int held_joint = -1) {
  const KinematicModel nominal = LoadRobotModel(kModel);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1e-5);
  KinematicModel chain = nominal;
  for (Link& l : chain.links) {
    l.dh.d += 5e-4 * u(rng);
    l.dh.a += 5e-4 * u(rng);
    l.dh.alpha += DegToRad(0.05) * u(rng);
    l.dh.theta_offset += DegToRad(0.05) * u(rng);
  }
  RobotModel truth = MakeRobotModel(chain);
  if (compliant) {
    truth = WithTerm(truth, MakeErrorTerm({"joint_compliance", 1, {}}, chain, chain.name));
    truth.term_values(0) = 3e-5;
  }
  const fs::path path = fs::path(::testing::TempDir()) / name;
  std::ofstream out(path);
  out.precision(12);
  out << "pose";
  for (int i = 0; i < chain.num_joints(); ++i) out << ",q" << i + 1 << "_rad";
  out << ",x_m,y_m,z_m,sigma_m\n";
  for (int k = 0; k < points; ++k) {
    MeasurementContext c;
    c.q = JointVector(chain.num_joints());
    for (int i = 0; i < chain.num_joints(); ++i) {
      const JointLimits& l = chain.links[i].limits;
      c.q(i) = 0.5 * (l.lower + l.upper) + 0.4 * (l.upper - l.lower) * u(rng);
      if (i == held_joint) c.q(i) = 0.5 * (l.lower + l.upper);
    }
    const Vector3 p = EndPose(truth, c).translation();
    out << k + 1;
    for (int i = 0; i < c.q.size(); ++i) out << "," << c.q(i);
    out << "," << p.x() + noise(rng) << "," << p.y() + noise(rng) << "," << p.z() + noise(rng)
        << ",1e-5\n";
  }
  return path;
}

nlohmann::json Report(const fs::path& out) {
  std::ifstream in(out / "report.json");
  return nlohmann::json::parse(in, nullptr, false);
}

TrackerIdentifyOptions Options(const fs::path& csv, const std::string& out_name) {
  TrackerIdentifyOptions o;
  o.model = kModel;
  o.measurements = csv.string();
  o.out_dir = (fs::path(::testing::TempDir()) / out_name).string();
  fs::remove_all(o.out_dir);
  o.quiet = true;
  return o;
}

TEST(TrackerIdentifyRun, TheReportCarriesTheDiagnosisAndNamesTheUndeclaredCompliance) {
  const fs::path csv = WriteTrackerFile("discovery_compliant.csv", true);
  TrackerIdentifyOptions o = Options(csv, "discovery_compliant_out");
  ASSERT_EQ(RunTrackerIdentify(o), 0);
  const nlohmann::json d = Report(o.out_dir)["diagnosis"];
  ASSERT_EQ(d["verdict"], "effects_added") << d.dump(1);
  ASSERT_GE(d["effects_added"].size(), 1u);
  EXPECT_EQ(d["effects_added"][0]["term"], "joint_compliance");
  EXPECT_EQ(d["effects_added"][0]["joint"], 2);  // 1-based in reports
  for (const char* key : {"noise_floor_mm", "residual_test", "steps", "candidates",
                          "unexplained_evidence", "residual_maps", "heldout_rms_mm"}) {
    EXPECT_TRUE(d.contains(key)) << key;
  }
  for (const auto& c : d["candidates"]) {
    for (const char* key : {"term", "joint", "parameters", "sigma", "heldout_gain_percent",
                            "p_value", "accepted"}) {
      EXPECT_TRUE(c.contains(key)) << key;
    }
  }
  // report.html shows the decision chain with the accepted term.
  std::ifstream html(fs::path(o.out_dir) / "report.html");
  const std::string page((std::istreambuf_iterator<char>(html)), std::istreambuf_iterator<char>());
  EXPECT_NE(page.find("Decision chain"), std::string::npos);
  EXPECT_NE(page.find("joint_compliance (joint 2)"), std::string::npos);
  // Geometric-only held-out error is the compliance's (~0.1-0.5 mm); discovered, the noise's.
  EXPECT_LT(d["heldout_rms_mm"]["discovered"].get<double>(),
            0.2 * d["heldout_rms_mm"]["start"].get<double>());
}

TEST(TrackerIdentifyRun, ADeclaredEffectIsInTheModelFromTheStartAndDiscoveryAddsNothing) {
  const fs::path csv = WriteTrackerFile("discovery_declared.csv", true);
  TrackerIdentifyOptions o = Options(csv, "discovery_declared_out");
  o.declared_terms = {"joint_compliance:2"};
  ASSERT_EQ(RunTrackerIdentify(o), 0);
  const nlohmann::json j = Report(o.out_dir);
  EXPECT_EQ(j["declared_terms"], nlohmann::json::array({"joint_compliance (joint 2)"}));
  EXPECT_EQ(j["diagnosis"]["verdict"], "consistent_with_noise") << j["diagnosis"]["reason"];
  EXPECT_TRUE(j["diagnosis"]["effects_added"].empty());
}

TEST(TrackerIdentifyRun, NoDiagnosisSkipsItAndBadDeclarationsAreRefusedBeforeAnythingIsWritten) {
  const fs::path csv = WriteTrackerFile("discovery_plain.csv", false, 60);
  TrackerIdentifyOptions o = Options(csv, "discovery_plain_out");
  o.diagnosis = false;
  ASSERT_EQ(RunTrackerIdentify(o), 0);
  EXPECT_TRUE(Report(o.out_dir)["diagnosis"]["verdict"].is_null());
  EXPECT_EQ(Report(o.out_dir)["diagnosis"]["skipped"], "--no-diagnosis");
  for (const char* bad : {"joint_compliance:x", "no_such_term", "joint_compliance:9",
                                 "transmission_error:2:0", "thermal_drift"}) {
    TrackerIdentifyOptions b = Options(csv, "discovery_bad_out");
    b.declared_terms = {std::string(bad)};
    try {
      RunTrackerIdentify(b);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const InputError& e) {
      // thermal_drift is a valid term, but this file has no time stamps.
      const std::string where = e.where();
      EXPECT_TRUE(where.find("--declare") != std::string::npos ||
                  where.find("discovery_plain.csv") != std::string::npos) << where;
    }
    EXPECT_FALSE(fs::exists(b.out_dir)) << bad;
  }
  TrackerIdentifyOptions f = Options(csv, "discovery_bad_out");
  f.diagnosis_folds = 1;
  EXPECT_THROW(RunTrackerIdentify(f), InputError);
  EXPECT_FALSE(fs::exists(f.out_dir));
}

// A rank drop is explained by naming its cause (issue 38): a joint the file does not move, and
// rows that measure one pose again.
TEST(TrackerIdentifyRun, ARankDropNamesTheJointThatDidNotMoveAndTheRepeats) {
  const fs::path held = WriteTrackerFile("held_joint6.csv", false, 80, 5);
  std::ifstream in(held);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::istringstream lines(text);
  std::string header, line, copies;
  std::getline(lines, header);
  for (int k = 0; k < 10 && std::getline(lines, line); ++k) copies += line + "\n";
  std::ofstream(held, std::ios::app) << copies;  // rows 2-11 measured again
  TrackerIdentifyOptions o = Options(held, "held_joint6_out");
  o.diagnosis = false;
  ASSERT_EQ(RunTrackerIdentify(o), 0);
  const nlohmann::json r = Report(o.out_dir);
  EXPECT_EQ(r["points"], 90);
  EXPECT_EQ(r["distinct_poses"], 80);
  ASSERT_EQ(r["rank_causes"].size(), 2u) << r["rank_causes"].dump();
  EXPECT_NE(r["rank_causes"][0].get<std::string>().find("joint 6 (column q6_rad) spans only 0 "
                                                        "deg"),
            std::string::npos) << r["rank_causes"][0];
  EXPECT_NE(r["rank_causes"][1].get<std::string>().find("90 rows measure 80 different poses"),
            std::string::npos) << r["rank_causes"][1];
  // The file where every joint moves and no pose repeats names no cause.
  TrackerIdentifyOptions plain = Options(WriteTrackerFile("moving.csv", false, 80), "moving_out");
  plain.diagnosis = false;
  ASSERT_EQ(RunTrackerIdentify(plain), 0);
  EXPECT_TRUE(Report(plain.out_dir)["rank_causes"].empty());
}

}  // namespace
}  // namespace twin
