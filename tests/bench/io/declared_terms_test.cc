#include "bench/io/declared_terms.h"

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "bench/io/model_loader.h"
#include "calib/model/error_term.h"

namespace twin {
namespace {

// The estimator's terms (type, joint, orders) that DeclaredModel starts robot 1 from, for the
// twin effects `effects` of a scenario.
std::vector<TermSpec> DeclaredSpecs(const std::vector<EffectSpec>& effects) {
  const KinematicModel nominal =
      LoadRobotModel(std::string(TWIN_SOURCE_DIR) + "/models/reinovo_r2.yaml");
  Scenario sc;
  sc.path = "s.yaml";
  sc.twin.effects = effects;
  std::vector<std::string> notes;
  const RobotModel m = DeclaredModel(sc, 1, nominal, &notes);
  std::vector<TermSpec> out;
  for (const auto& t : m.terms) out.push_back(t->spec());
  return out;
}

bool Has(const std::vector<TermSpec>& specs, const std::string& type, int joint,
         std::vector<int> orders) {
  for (const TermSpec& s : specs) {
    if (s.type == type && s.joint == joint && s.orders == orders) return true;
  }
  return false;
}

// The twin's bending effects, declared, give the estimator's terms of the same physics, by
// type and joint only: a laterally compliant joint its lateral compliance, a compliant base
// joint 1's lateral compliance (which tilts the whole arm), a wobbling axis its wobble at the
// twin's order (never its amplitude); undeclared ones and other robots' give nothing.
TEST(DeclaredTerms, BendingAndWobblingAxesMapToTheEstimatorsTerms) {
  const std::vector<TermSpec> specs = DeclaredSpecs({
      {"lateral_compliance", true, 1, 2, {{"stiffness_Nm_per_rad", 2000}}, ""},
      {"base_compliance", true, 1, -1, {{"stiffness_Nm_per_rad", 5e5}}, ""},
      {"axis_wobble", true, 1, 0, {{"amplitude_rad", 1e-4}, {"order", 3}}, ""},
      {"axis_wobble", false, 1, 4, {{"order", 2}}, ""},     // undeclared
      {"lateral_compliance", true, 0, 3, {}, ""},             // the other robot
  });
  ASSERT_EQ(specs.size(), 3u);
  EXPECT_TRUE(Has(specs, "lateral_compliance", 2, {}));
  EXPECT_TRUE(Has(specs, "lateral_compliance", 0, {}));
  EXPECT_TRUE(Has(specs, "axis_wobble", 0, {3}));
}

// A declared base compliance and a declared lateral compliance of joint 1 are one term.
TEST(DeclaredTerms, TheBaseAndJointOnesLateralComplianceAreOneTerm) {
  const std::vector<TermSpec> specs = DeclaredSpecs({
      {"base_compliance", true, 1, -1, {}, ""},
      {"lateral_compliance", true, 1, 0, {}, ""},
  });
  ASSERT_EQ(specs.size(), 1u);
  EXPECT_TRUE(Has(specs, "lateral_compliance", 0, {}));
}

}  // namespace
}  // namespace twin
