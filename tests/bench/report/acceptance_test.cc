#include "bench/report/acceptance.h"

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "tests/bench/text_edit.h"

namespace twin {
namespace {

using testing::ReadFile;

const std::string kScenarioDir = std::string(TWIN_SOURCE_DIR) + "/scenarios";

// paper_reinovo.yaml with `section` as its acceptance section.
Scenario WithAcceptance(const std::string& section) {
  std::string text = ReadFile(kScenarioDir + "/paper_reinovo.yaml");
  text = text.substr(0, text.find("  # The CI verdict"));
  text += "  acceptance:\n" + section;
  return ParseScenario(text, "acc.yaml", kScenarioDir);
}

std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

const nlohmann::json kReport = nlohmann::json::parse(R"({
  "robots": {"r2": {"truth_position_error_mm": {"rigid": {"after": {"rms": 0.25, "max": 0.9}}},
                    "servo": {"failures": [{"frames": 7}], "mean_frames_per_pose": null}}},
  "status": "ok"})");

TEST(Acceptance, ParsesCriteriaWithNamesAndBounds) {
  const Acceptance a = ParseAcceptance(WithAcceptance(
      "    - {figure: robots.r2.truth_position_error_mm.rigid.after.rms, max: 0.3}\n"
      "    - figure: robots.r2.servo.failures[0].frames\n"
      "      min: 1\n      max: 10\n      name: frames\n"));
  ASSERT_EQ(a.criteria.size(), 2u);
  EXPECT_EQ(*a.criteria[0].max, 0.3);
  EXPECT_FALSE(a.criteria[0].min);
  EXPECT_EQ(a.criteria[0].name, "robots.r2.truth_position_error_mm.rigid.after.rms <= 0.3");
  EXPECT_EQ(a.criteria[1].name, "frames");
  EXPECT_NE(a.criteria[1].where.find("acc.yaml:"), std::string::npos);
  EXPECT_TRUE(ParseAcceptance(ParseScenario(ReadFile(kScenarioDir + "/twin_demo.yaml"),
                                            "d.yaml", kScenarioDir))
                  .criteria.empty());
  // The shipped scenarios' criteria parse (their targets: the scenarios' comments).
  EXPECT_EQ(ParseAcceptance(ParseScenario(ReadFile(kScenarioDir + "/paper_reinovo.yaml"),
                                          "p.yaml", kScenarioDir))
                .criteria.size(),
            8u);
}

TEST(Acceptance, BadSectionsAreRefusedBeforeTheRun) {
  struct Case {
    std::string section, expected;
  };
  const Case cases[] = {
      {"    figure: x\n", "expected a list of 1 to 100 criteria"},
      {"    - {figure: robots.r2.x}\n", "expected a bound"},
      {"    - {figure: robots.r2.x, max: abc}\n", "expected a number"},
      {"    - {figure: robots.r2.x, max: .nan}\n", "finite"},
      {"    - {figure: robots.r2.x, min: 2, max: 1}\n", "min 2 is above max 1"},
      {"    - {figure: 'robots..x', max: 1}\n", "expected a report.json key path"},
      {"    - {figure: robts.r2.x, max: 1}\n", "'robts' is not a top-level key"},
      {"    - {figure: robots.r9.x, max: 1}\n", "'r9' is not a robot of the scenario"},
      {"    - {max: 1}\n", "missing required key 'figure'"},
      {"    - {figure: robots.r2.x, maximum: 1}\n", "unknown key 'maximum'"},
  };
  for (const Case& c : cases) {
    const std::string msg = ErrorOf([&] { ParseAcceptance(WithAcceptance(c.section)); });
    EXPECT_NE(msg.find("acc.yaml:"), std::string::npos) << msg;
    EXPECT_NE(msg.find(c.expected), std::string::npos) << c.section << ": " << msg;
  }
}

TEST(Acceptance, EvaluatesAndSaysByHowMuch) {
  const Acceptance a = ParseAcceptance(WithAcceptance(
      "    - {figure: robots.r2.truth_position_error_mm.rigid.after.rms, max: 0.3}\n"
      "    - {figure: robots.r2.truth_position_error_mm.rigid.after.max, max: 0.5}\n"
      "    - {figure: robots.r2.servo.failures.0.frames, min: 10}\n"
      "    - {figure: robots.r2.servo.mean_frames_per_pose, max: 4}\n"));
  nlohmann::json report = kReport;
  const AcceptanceVerdict v = EvaluateAcceptance(a, &report);
  ASSERT_EQ(v.results.size(), 4u);
  EXPECT_TRUE(v.results[0].passed) << v.results[0].message;
  EXPECT_NE(v.results[0].message.find("margin 0.05"), std::string::npos) << v.results[0].message;
  EXPECT_FALSE(v.results[1].passed);
  EXPECT_NE(v.results[1].message.find("0.9 > max 0.5 (over by 0.4)"), std::string::npos)
      << v.results[1].message;
  EXPECT_FALSE(v.results[2].passed);
  EXPECT_NE(v.results[2].message.find("under by 3"), std::string::npos) << v.results[2].message;
  EXPECT_FALSE(v.results[3].passed);  // null: not computed
  EXPECT_NE(v.results[3].message.find("null"), std::string::npos);
  EXPECT_FALSE(v.passed());
  EXPECT_EQ(VerdictExitCode(v), 3);
  EXPECT_EQ(report["acceptance"].size(), 4u);
  EXPECT_EQ(report["acceptance"][1]["passed"], false);
}

TEST(Acceptance, UnknownOrNonNumericFiguresAreBadInput) {
  for (const auto& [figure, expected] : std::vector<std::pair<std::string, std::string>>{
           {"robots.r2.truth_position_error_mm.rigid.after.mean", "has no key 'mean'"},
           {"'robots.r2.servo.failures[3].frames'", "a list of 1 items, no item '3'"},
           {"robots.r2.truth_position_error_mm.rigid", "a map (keys: after)"},
           {"status", "'\"ok\"', not a number"},
           {"robots.r2.truth_position_error_mm.rigid.after.rms.x", "is a value"}}) {
    const Acceptance a =
        ParseAcceptance(WithAcceptance("    - {figure: " + figure + ", max: 1}\n"));
    nlohmann::json report = kReport;
    const std::string msg = ErrorOf([&] { EvaluateAcceptance(a, &report); });
    EXPECT_NE(msg.find("acc.yaml:"), std::string::npos) << msg;
    EXPECT_NE(msg.find(expected), std::string::npos) << figure << ": " << msg;
  }
}

TEST(Acceptance, JunitHasOneTestCasePerCriterion) {
  const Acceptance a = ParseAcceptance(WithAcceptance(
      "    - {figure: robots.r2.truth_position_error_mm.rigid.after.rms, max: 0.3}\n"
      "    - {figure: robots.r2.truth_position_error_mm.rigid.after.max, max: 0.5, "
      "name: 'max <error> & more'}\n"));
  nlohmann::json report = kReport;
  const std::string xml = JunitXml("paper_reinovo", EvaluateAcceptance(a, &report), 12.5);
  EXPECT_NE(xml.find("<testsuite name=\"paper_reinovo\" tests=\"2\" failures=\"1\""),
            std::string::npos) << xml;
  EXPECT_NE(xml.find("name=\"robots.r2.truth_position_error_mm.rigid.after.rms &lt;= 0.3\""),
            std::string::npos) << xml;
  EXPECT_NE(xml.find("name=\"max &lt;error&gt; &amp; more\""), std::string::npos) << xml;
  EXPECT_NE(xml.find("<failure type=\"acceptance\""), std::string::npos) << xml;
  EXPECT_EQ(xml.find("<failure", xml.find("<failure") + 1), std::string::npos) << xml;
  const std::string empty = JunitXml("s", AcceptanceVerdict{}, 1.0);
  EXPECT_NE(empty.find("<testcase classname=\"twinbench.s\" name=\"run\""), std::string::npos)
      << empty;
}

}  // namespace
}  // namespace twin

namespace twin {
namespace {

// On a cell without truth every criterion on a figure against the truth is left out (the
// figure is null there), and every other one kept: the paths of the optical-axis, handclasp,
// workflow and tracker reports.
TEST(Acceptance, WithoutTruthKeepsOnlyFiguresThatNeedNoTruth) {
  const std::vector<std::string> against_truth = {
      "robots.r2.truth_position_error_mm.rigid.after.rms",
      "robots.r1.truth_position_error_mm_physical.calibrated_model.rigid.rms",
      "robots.r2.parameters[3].true",
      "robots.r2.scale.true",
      "robots.r2.identifiable_combinations.rms_error",
      "intrinsics.error_px.fx",
      "base_frame.constrained.e_tran_mm",
      "base_frame.workflow.calibrated_kinematics.e_rot_deg",
      "base_frame.batch.general.mean_e_tran_mm",
      "base_frame.coupled_motion.max_deviation_mm",
      "base_frame.physical_truth.xyz_mm[0]",
      "base_frame.scoring_frame.link1_offsets[0].dd1_mm",
      "base_frame.workflow.nominal_kinematics.physical_truth.e_tran_mm",
      "base_frame.operator_error_mm",
      "truth_position_error_mm.rigid.after.rms",
      "parameters.within_3_sigma",
      "tracker.sigma_mm"};
  const std::vector<std::string> kept = {
      "robots.r2.misaligned_error_mm.validation.after",
      "robots.r2.parameters[3].estimated",
      "robots.r2.scale.estimated",
      "intrinsics.rms_reprojection_px",
      "base_frame.constrained.rms_residual_mm",
      "heldout.region.after.rms",
      "status"};
  Acceptance all;
  for (const std::vector<std::string>* figures : {&against_truth, &kept}) {
    for (const std::string& f : *figures) {
      AcceptanceCriterion c;
      c.figure = f;
      c.name = f;
      c.max = 1.0;
      all.criteria.push_back(c);
    }
  }
  const Acceptance left = WithoutTruthCriteria(all, true);
  std::vector<std::string> figures;
  for (const AcceptanceCriterion& c : left.criteria) figures.push_back(c.figure);
  EXPECT_EQ(figures, kept);
}

}  // namespace
}  // namespace twin
