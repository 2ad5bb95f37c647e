// TWINBENCH_GL's values (sim/render/gl_context.h). Which back end renders, and that EGL and
// OSMesa draw the same pixels, is tested across processes by gl_backends_test.sh: one process
// renders with one back end.
#include "sim/render/gl_context.h"

#include <dlfcn.h>
#include <stdlib.h>
#include <unistd.h>

#include <cstdio>
#include <stdexcept>
#include <string>

#include <gtest/gtest.h>

#include "calib/common/errors.h"

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

// Chooses the back end TWINBENCH_GL=value names by making a context, then checks what MuJoCo's
// GL loader will see (gl_context.h): eglGetProcAddress in the global namespace exactly when EGL
// was chosen. On llvmpipe the pixels cannot tell (OSMesa's function pointers also draw into a
// current Mesa EGL context: they share libglapi), so this is the check that the promotion of
// libEGL happened, and only then. Ends the process: 0 consistent, 1 not, 3 EGL absent here.
[[noreturn]] void ChooseAndCheck(const char* value) {
  setenv("TWINBENCH_GL", value, 1);
  try {
    const auto context = MakeGlContext(16, 16);
  } catch (const InputError& e) {
    const std::string what = e.what();
    std::fprintf(stderr, "%s\n", what.c_str());
    const bool absent = what.find("cannot open libEGL") != std::string::npos ||
                        what.find("EGL enumerates no device") != std::string::npos ||
                        what.find("EGL lacks device enumeration") != std::string::npos;
    _exit(absent ? 3 : 1);
  }
  const std::string description = GlBackendDescription();
  const bool egl = description.rfind("egl (", 0) == 0;
  const bool global = dlsym(RTLD_DEFAULT, "eglGetProcAddress") != nullptr;
  std::fprintf(stderr, "chose %s; eglGetProcAddress global: %s\n", description.c_str(),
               global ? "yes" : "no");
  _exit(egl == global ? 0 : 1);  // _exit: no leak check of the GL drivers' allocations
}

bool ConsistentOrEglAbsent(int status) {
  return WIFEXITED(status) && (WEXITSTATUS(status) == 0 || WEXITSTATUS(status) == 3);
}

// Each in a process of its own (threadsafe death tests re-run the binary for this test alone),
// since one process chooses once.
TEST(GlBackendDeathTest, MujocoSeesEglExactlyWhenItIsChosen) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(ChooseAndCheck("osmesa"), ::testing::ExitedWithCode(0),
              "chose osmesa \\(.*eglGetProcAddress global: no");
  EXPECT_EXIT(ChooseAndCheck("egl"), ConsistentOrEglAbsent, "");
  EXPECT_EXIT(ChooseAndCheck("auto"), ::testing::ExitedWithCode(0), "chose ");
}

}  // namespace
}  // namespace twin
