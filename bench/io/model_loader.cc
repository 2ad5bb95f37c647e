#include "bench/io/model_loader.h"

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "bench/io/model_yaml.h"
#include "bench/io/urdf_model.h"
#include "calib/common/errors.h"

namespace twin {
namespace {

bool EndsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

}  // namespace

KinematicModel LoadRobotModel(const std::string& path) {
  if (EndsWith(path, ".yaml") || EndsWith(path, ".yml")) return LoadModelYaml(path);
  if (EndsWith(path, ".urdf")) return LoadUrdf(path);
  throw InputError(path, "unknown model format; expected a .yaml, .yml or .urdf file");
}

void PublishDirectory(const std::string& staging, const std::string& out) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path old = out + ".old";
  fs::remove_all(old, ec);
  if (fs::exists(out)) fs::rename(out, old);
  fs::rename(staging, out);
  fs::remove_all(old, ec);
}

std::string CreateStagingDirectory(const std::string& out) {
  const std::string staging = out + ".partial";
  std::error_code ec;
  std::filesystem::remove_all(staging, ec);
  if (!std::filesystem::create_directories(staging, ec) && ec) {
    throw InputError(out, "cannot create the output folder: " + ec.message());
  }
  return staging;
}

void WriteFileAtomically(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".partial";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(path, "cannot open for writing");
    out << text;
    out.flush();
    if (!out) {
      std::remove(tmp.c_str());
      throw InputError(path, "write failed");
    }
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    std::remove(tmp.c_str());
    throw InputError(path, "cannot move the written file into place");
  }
}

}  // namespace twin
