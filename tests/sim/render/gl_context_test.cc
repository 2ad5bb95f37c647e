// TWINBENCH_GL's values (sim/render/gl_context.h). Which back end renders, and that EGL and
// OSMesa draw the same pixels, is tested across processes by gl_backends_test.sh: one process
// renders with one back end.
#include "sim/render/gl_context.h"

#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

namespace twin {
namespace {

TEST(GlChoiceTest, AcceptsTheDocumentedValues) {
  EXPECT_EQ(ParseGlChoice("").kind, GlChoice::Kind::kAuto);
  EXPECT_EQ(ParseGlChoice("auto").kind, GlChoice::Kind::kAuto);
  EXPECT_EQ(ParseGlChoice("osmesa").kind, GlChoice::Kind::kOsmesa);
  const GlChoice egl = ParseGlChoice("egl");
  EXPECT_EQ(egl.kind, GlChoice::Kind::kEgl);
  EXPECT_EQ(egl.egl_device, -1);
  const GlChoice third = ParseGlChoice("egl:2");
  EXPECT_EQ(third.kind, GlChoice::Kind::kEgl);
  EXPECT_EQ(third.egl_device, 2);
  EXPECT_EQ(ParseGlChoice("egl:0").egl_device, 0);
}

TEST(GlChoiceTest, RefusesOthersNamingTheValueAndTheAcceptedOnes) {
  for (const std::string bad : {"EGL", "gpu", "egl:", "egl:x", "egl:-1", "egl:1a", "egl:99999",
                                " osmesa", "osmesa "}) {
    try {
      ParseGlChoice(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const std::invalid_argument& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("'" + bad + "'"), std::string::npos) << what;
      EXPECT_NE(what.find("auto, osmesa, egl or egl:N"), std::string::npos) << what;
    }
  }
}

}  // namespace
}  // namespace twin
