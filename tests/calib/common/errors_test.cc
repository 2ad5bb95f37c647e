// The two kinds of error (calib/common/errors.h): a broken precondition is a PreconditionError
// (a logic_error, reported as an internal error), never an InputError (bad input, exit 2).
#include "calib/common/errors.h"

#include <string>

#include <gtest/gtest.h>

namespace twin {
namespace {

int Halve(int n) {
  TWIN_REQUIRE(n % 2 == 0, "Halve needs an even number, got " + std::to_string(n));
  return n / 2;
}

TEST(Errors, RequireHoldsAndPassesTheValueThrough) { EXPECT_EQ(Halve(8), 4); }

TEST(Errors, BrokenPreconditionIsALogicErrorNamingTheCondition) {
  try {
    Halve(7);
    FAIL() << "no exception";
  } catch (const InputError&) {
    FAIL() << "a broken precondition must not read as bad input";
  } catch (const PreconditionError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("n % 2 == 0"), std::string::npos) << what;
    EXPECT_NE(what.find("got 7"), std::string::npos) << what;
    EXPECT_NE(what.find("errors_test.cc:"), std::string::npos) << what;
  }
}

TEST(Errors, InputErrorNamesWhereFirst) {
  const InputError e("models/r1.yaml:12 links[2].alpha", "must be finite");
  EXPECT_EQ(std::string(e.what()), "models/r1.yaml:12 links[2].alpha: must be finite");
}

}  // namespace
}  // namespace twin
