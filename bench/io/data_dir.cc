#include "bench/io/data_dir.h"

#include <cstdlib>
#include <filesystem>
#include <system_error>

#include "calib/common/errors.h"

// Set by bench/CMakeLists.txt on this file only (so that moving a tree recompiles nothing
// else): the source tree, the build tree's bin/, and the data folder relative to the
// installed executable's folder (from GNUInstallDirs: ../share/twinbench).
#ifndef TWINBENCH_SOURCE_DATA_DIR
#error "TWINBENCH_SOURCE_DATA_DIR must be defined (bench/CMakeLists.txt)"
#endif
#ifndef TWINBENCH_BUILD_BIN_DIR
#error "TWINBENCH_BUILD_BIN_DIR must be defined (bench/CMakeLists.txt)"
#endif
#ifndef TWINBENCH_INSTALLED_DATA_FROM_BIN
#error "TWINBENCH_INSTALLED_DATA_FROM_BIN must be defined (bench/CMakeLists.txt)"
#endif

namespace twin {
namespace fs = std::filesystem;
namespace {

constexpr const char* kEnv = "TWINBENCH_DATA_DIR";

bool IsDir(const fs::path& p) {
  std::error_code ec;
  return fs::is_directory(p, ec);
}

bool SameDir(const fs::path& a, const fs::path& b) {
  std::error_code ec;
  return fs::equivalent(a, b, ec) && !ec;
}

}  // namespace

std::string DataDir() {
  if (const char* env = std::getenv(kEnv); env != nullptr && *env != '\0') {
    if (!IsDir(env)) {
      throw InputError(kEnv, std::string("'") + env + "' is not a folder; set it to the folder "
                             "holding twinbench's models/ and scenarios/, or unset it");
    }
    return env;
  }
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) {
    throw InputError("data folder", "cannot find twinbench's own executable (/proc/self/exe: " +
                                        ec.message() + "); set " + kEnv +
                                        " to the folder holding models/ and scenarios/");
  }
  const fs::path bin = exe.parent_path();
  if (SameDir(bin, TWINBENCH_BUILD_BIN_DIR) && IsDir(TWINBENCH_SOURCE_DATA_DIR)) {
    return TWINBENCH_SOURCE_DATA_DIR;
  }
  const fs::path installed = (bin / TWINBENCH_INSTALLED_DATA_FROM_BIN).lexically_normal();
  if (IsDir(installed / "models")) return installed.string();
  throw InputError("data folder", "twinbench's data (models/, scenarios/) is not installed: no " +
                                      (installed / "models").string() + " beside " +
                                      exe.string() + "; reinstall twinbench or set " + kEnv +
                                      " to the folder holding models/ and scenarios/");
}

std::string DataFile(const std::string& relative) {
  const fs::path p = fs::path(DataDir()) / relative;
  std::error_code ec;
  if (!fs::exists(p, ec)) {
    throw InputError("data folder", "twinbench's data file " + p.string() +
                                        " is missing; reinstall twinbench or set " + kEnv);
  }
  return p.string();
}

}  // namespace twin
