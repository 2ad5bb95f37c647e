#include "calib/planning/plan_store.h"

#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "test_models.h"

namespace twin {
namespace {

using testing::ReinovoLikeModel;

PlanInputs Inputs() {
  PlanInputs in;
  in.active = ReinovoLikeModel(0);
  in.passive = ReinovoLikeModel(1);
  in.X_BaBp.translation() = Vector3(1.2, 0.0, 0.0);
  in.X_FC.translation() = Vector3(0.0, 0.0, 0.05);
  return in;
}

TEST(PlanStoreTest, InputsTextIsStableAndLeavesThreadsOut) {
  const PlanInputs a = Inputs();
  EXPECT_EQ(PlanInputsText(a), PlanInputsText(Inputs()));
  PlanInputs b = a;
  b.options.threads = 7;  // the plan does not depend on it (pose_planner.h)
  EXPECT_EQ(PlanInputsText(a), PlanInputsText(b));
}

TEST(PlanStoreTest, EveryInputThatChangesThePlanChangesTheText) {
  const std::string base = PlanInputsText(Inputs());
  const std::vector<std::pair<const char*, std::function<void(PlanInputs*)>>> edits = {
      {"active link d", [](PlanInputs* p) { p->active.links[2].dh.d += 1e-12; }},
      {"passive tool a", [](PlanInputs* p) { p->passive.tool().dh.a += 1e-9; }},
      {"passive limit", [](PlanInputs* p) { p->passive.links[0].limits.upper -= 1e-9; }},
      {"passive X_LtE", [](PlanInputs* p) { p->passive.X_LtE.translation().z() += 1e-9; }},
      {"X_BaBp", [](PlanInputs* p) { p->X_BaBp.translation().y() = 1e-15; }},
      {"X_FC", [](PlanInputs* p) { p->X_FC.linear()(0, 1) = 1e-15; }},
      {"seed", [](PlanInputs* p) { p->options.seed = 2; }},
      {"swarm", [](PlanInputs* p) { p->options.swarm_size = 11; }},
      {"C3", [](PlanInputs* p) { p->options.max_visibility_angle *= 1.0000001; }},
      {"ik seed", [](PlanInputs* p) { p->options.ik.seed = 9; }},
      {"board normal", [](PlanInputs* p) { p->options.board_normal_in_E.x() = 1e-12; }},
      {"active IK start", [](PlanInputs* p) { p->options.active_ik_seed = JointVector::Zero(6); }},
      {"passive IK start", [](PlanInputs* p) { p->options.passive_ik_seed = JointVector::Zero(6); }},
      {"closed-form IK", [](PlanInputs* p) { p->options.closed_form_ik = true; }},
      {"run selection",
       [](PlanInputs* p) {
         p->options.select_run = PosePlannerOptions::RunSelection::kPredictedError;
       }},
  };
  for (const auto& [what, edit] : edits) {
    PlanInputs p = Inputs();
    edit(&p);
    EXPECT_NE(PlanInputsText(p), base) << what;  // exact (hex) numbers: the last bit counts
  }
  // With the predicted-error selection its configurations and seed choose the run too; with
  // the paper's selection they do not (and the text stays that of plans made before them).
  PlanInputs predicted = Inputs();
  predicted.options.select_run = PosePlannerOptions::RunSelection::kPredictedError;
  PlanInputs other_seed = predicted, other_count = predicted, paper = Inputs();
  other_seed.options.prediction_seed = 2;
  other_count.options.prediction_configurations = 201;
  paper.options.prediction_seed = 2;
  EXPECT_NE(PlanInputsText(other_seed), PlanInputsText(predicted));
  EXPECT_NE(PlanInputsText(other_count), PlanInputsText(predicted));
  EXPECT_EQ(PlanInputsText(paper), base);
  EXPECT_EQ(base.find("select_run"), std::string::npos);
  // Without IK starts (the mid-range) the text is that of plans made before they existed.
  EXPECT_EQ(base.find("ik_seed."), std::string::npos);
  // The closed-form IK is named where on, so the iterative IK's plans (the default, whose text
  // is that of plans made before it existed) are not reused for it.
  EXPECT_EQ(base.find("closed_form"), std::string::npos);
  PlanInputs closed = Inputs();
  closed.options.closed_form_ik = true;
  EXPECT_NE(PlanInputsText(closed).find("ik.closed_form 1\n"), std::string::npos);
}

}  // namespace
}  // namespace twin
