// bench/io/data_dir: the build tree's binaries read the source tree's data; TWINBENCH_DATA_DIR
// overrides it and must name a folder. (The installed layout, ../share/twinbench beside a
// moved executable, is checked by tests/packaging/packaging_test.sh on the .deb.)
#include "bench/io/data_dir.h"

#include <cstdlib>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include "calib/common/errors.h"

namespace twin {
namespace {

namespace fs = std::filesystem;

// Sets TWINBENCH_DATA_DIR for one test and restores what was there.
class DataDirEnv {
 public:
  explicit DataDirEnv(const char* value) {
    if (const char* old = std::getenv("TWINBENCH_DATA_DIR")) old_ = old, had_ = true;
    if (value) {
      setenv("TWINBENCH_DATA_DIR", value, 1);
    } else {
      unsetenv("TWINBENCH_DATA_DIR");
    }
  }
  ~DataDirEnv() {
    if (had_) {
      setenv("TWINBENCH_DATA_DIR", old_.c_str(), 1);
    } else {
      unsetenv("TWINBENCH_DATA_DIR");
    }
  }

 private:
  std::string old_;
  bool had_ = false;
};

TEST(DataDir, TheBuildTreeReadsTheSourceTree) {
  DataDirEnv env(nullptr);
  EXPECT_TRUE(fs::equivalent(DataDir(), TWIN_SOURCE_DIR));
  EXPECT_TRUE(fs::equivalent(DataFile("models/reinovo_r1.yaml"),
                             fs::path(TWIN_SOURCE_DIR) / "models" / "reinovo_r1.yaml"));
}

TEST(DataDir, TheEnvironmentOverridesIt) {
  const fs::path dir = fs::path(TWIN_SOURCE_DIR) / "scenarios";
  DataDirEnv env(dir.c_str());
  EXPECT_EQ(DataDir(), dir.string());
  EXPECT_EQ(DataFile("twin_demo.yaml"), (dir / "twin_demo.yaml").string());
}

TEST(DataDir, AnOverrideNamingNoFolderIsAnInputErrorNamingTheVariable) {
  DataDirEnv env("/nonexistent/twinbench/data");
  try {
    DataDir();
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.where(), "TWINBENCH_DATA_DIR");
    EXPECT_NE(std::string(e.what()).find("/nonexistent/twinbench/data"), std::string::npos);
  }
}

TEST(DataDir, AMissingFileIsAnInputErrorNamingIt) {
  DataDirEnv env(nullptr);
  try {
    DataFile("models/no_such_arm.yaml");
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("models/no_such_arm.yaml"), std::string::npos);
  }
}

}  // namespace
}  // namespace twin
