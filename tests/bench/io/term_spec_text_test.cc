// The TYPE[:JOINT[:ORDERS]] text of a term (--declare, diagnosis.candidates): joints 1-based
// in the text, 0-based in the spec; an empty joint before orders is a whole-robot term.
#include "bench/io/term_spec_text.h"

#include <gtest/gtest.h>

#include "calib/common/errors.h"

namespace twin {
namespace {

TEST(TermSpecText, JointsOrdersAndWholeRobotTerms) {
  const TermSpec compliance = ParseTermSpec("joint_compliance:2", "--declare");
  EXPECT_EQ(compliance.type, "joint_compliance");
  EXPECT_EQ(compliance.joint, 1);
  EXPECT_TRUE(compliance.orders.empty());
  const TermSpec harmonic = ParseTermSpec("transmission_error:4:1,2", "--declare");
  EXPECT_EQ(harmonic.joint, 3);
  EXPECT_EQ(harmonic.orders, (std::vector<int>{1, 2}));
  const TermSpec drift = ParseTermSpec("thermal_drift", "--declare");
  EXPECT_EQ(drift.joint, -1);
  const TermSpec warmup = ParseTermSpec("thermal_warmup::30", "--declare");
  EXPECT_EQ(warmup.type, "thermal_warmup");
  EXPECT_EQ(warmup.joint, -1);
  EXPECT_EQ(warmup.orders, (std::vector<int>{30}));
}

TEST(TermSpecText, MalformedTextNamesWhereAndTheForm) {
  for (const char* text : {"", "joint_compliance:", "joint_compliance:x", "a:1:2:3",
                           "transmission_error:4:one", "joint_compliance::"}) {
    try {
      ParseTermSpec(text, "--declare");
      ADD_FAILURE() << "accepted '" << text << "'";
    } catch (const InputError& e) {
      EXPECT_EQ(e.where(), "--declare") << text;
      EXPECT_NE(std::string(e.what()).find("TYPE[:JOINT[:ORDERS]]"), std::string::npos)
          << text << ": " << e.what();
    }
  }
}

}  // namespace
}  // namespace twin
