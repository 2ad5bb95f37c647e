#include "bench/io/model_loader.h"

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "bench/io/model_yaml.h"
#include "bench/io/output_files.h"
#include "bench/io/urdf_model.h"
#include "calib/common/errors.h"

namespace twin {
namespace {

bool EndsWith(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

}  // namespace

KinematicModel LoadRobotModel(const std::string& path, const ModelLinks& links,
                              std::vector<std::string>* warnings) {
  if (EndsWith(path, ".yaml") || EndsWith(path, ".yml")) {
    if (!links.base_link.empty() || !links.tip_link.empty()) {
      throw InputError(path, "base_link / tip_link choose the chain of a URDF; a YAML model is "
                             "already one chain (remove them or load the URDF)");
    }
    return LoadModelYaml(path);
  }
  if (EndsWith(path, ".urdf")) {
    UrdfImportOptions options;
    options.base_link = links.base_link;
    options.tip_link = links.tip_link;
    return LoadUrdf(path, options, warnings);
  }
  throw InputError(path, "unknown model format; expected a .yaml, .yml or .urdf file");
}

KinematicModel LoadRobotModelAndWarn(const std::string& path, const ModelLinks& links) {
  std::vector<std::string> warnings;
  KinematicModel model = LoadRobotModel(path, links, &warnings);
  PrintWarnings(warnings);
  return model;
}

void PrintWarnings(const std::vector<std::string>& warnings) {
  for (const std::string& w : warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
}

void PublishDirectory(const std::string& staging, const std::string& out) {
  namespace fs = std::filesystem;
  // Held off from the interrupt clean-up: either the staging folder is removed before the
  // renames, or the output is complete after them. The old output is kept aside until the new
  // one is in place.
  WithCleanupHeld([&] {
    std::error_code ec;
    const fs::path old = out + ".old";
    fs::remove_all(old, ec);
    if (fs::exists(out)) {
      fs::rename(out, old, ec);
      if (ec) throw InputError(out, "cannot replace the output folder: " + ec.message());
    }
    fs::rename(staging, out, ec);
    if (ec) {
      std::error_code ignored;
      if (fs::exists(old)) fs::rename(old, out, ignored);
      throw InputError(out, "cannot move the completed output into place: " + ec.message());
    }
    UnregisterCleanupPath(staging);
    fs::remove_all(old, ec);
  });
}

std::string CreateStagingDirectory(const std::string& out) {
  ValidateOutputFolder(out, out);
  const std::string staging = out + ".partial";
  std::error_code ec;
  std::filesystem::remove_all(staging, ec);  // left by a killed run (SIGKILL)
  RegisterCleanupPath(staging);
  if (!std::filesystem::create_directories(staging, ec) && ec) {
    DiscardStaging(staging);
    throw InputError(out, "cannot create the output folder: " + ec.message());
  }
  return staging;
}

void WriteFileAtomically(const std::string& path, const std::string& text) {
  const std::string tmp = path + ".partial";
  RegisterCleanupPath(tmp);
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) {
      UnregisterCleanupPath(tmp);
      throw InputError(path, "cannot open for writing");
    }
    out << text;
    out.flush();
    if (!out) {
      DiscardStaging(tmp);
      throw InputError(path, "write failed");
    }
  }
  WithCleanupHeld([&] {
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
      DiscardStaging(tmp);
      throw InputError(path, "cannot move the written file into place");
    }
    UnregisterCleanupPath(tmp);
  });
}

}  // namespace twin
