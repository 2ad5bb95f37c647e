#include "calib/model/parameters.h"

#include <random>
#include <set>

#include <gtest/gtest.h>

#include "calib/common/errors.h"
#include "test_models.h"

namespace twin {
namespace {

TEST(Parameters, NamesAreUniqueAndFollowTheFlatOrder) {
  KinematicModel r1;
  r1.name = "r1";
  const std::vector<std::string> names = ParameterNames(r1);
  ASSERT_EQ(names.size(), static_cast<size_t>(35));
  EXPECT_EQ(std::set<std::string>(names.begin(), names.end()).size(), names.size());
  EXPECT_EQ(names[0], "r1.link1.theta");
  EXPECT_EQ(names[ParameterIndex(3, DhParameter::kAlpha)], "r1.link3.alpha");
  EXPECT_EQ(names[35 - 1], "r1.link7.beta");
  for (int i = 0; i < 35; ++i) EXPECT_EQ(FindParameter(r1, names[i]), i);
}

TEST(Parameters, LengthParametersAreDAndA) {
  EXPECT_TRUE(IsLengthParameter(ParameterIndex(2, DhParameter::kD)));
  EXPECT_TRUE(IsLengthParameter(ParameterIndex(7, DhParameter::kA)));
  EXPECT_FALSE(IsLengthParameter(ParameterIndex(2, DhParameter::kBeta)));
  EXPECT_FALSE(IsLengthParameter(ParameterIndex(1, DhParameter::kTheta)));
}

// Only our own code looks names up (no user's name reaches FindParameter): an unknown one is a
// broken precondition, not bad input.
TEST(Parameters, UnknownNameIsAPreconditionErrorWithTheExpectedForm) {
  KinematicModel r1;
  r1.name = "r1";
  try {
    FindParameter(r1, "r1.link9.alpha");
    FAIL() << "expected PreconditionError";
  } catch (const PreconditionError& e) {
    EXPECT_NE(std::string(e.what()).find("r1.link9.alpha"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("r1.link<1..7>.<theta|d|a|alpha|beta>"),
              std::string::npos);
  }
}

TEST(Parameters, GetAndWithRoundTripAndTouchTheNamedField) {
  const KinematicModel m = testing::ReinovoLikeModel();
  ParameterVector p = GetParameters(m);
  EXPECT_DOUBLE_EQ(p(ParameterIndex(6, DhParameter::kD)), 0.1215);
  p(ParameterIndex(3, DhParameter::kAlpha)) += 0.01;
  const KinematicModel m2 = WithParameters(m, p);
  EXPECT_DOUBLE_EQ(m2.links[2].dh.alpha, m.links[2].dh.alpha + 0.01);
  EXPECT_TRUE(GetParameters(m2) == p);  // plain copies: bitwise equal
}

}  // namespace
}  // namespace twin
