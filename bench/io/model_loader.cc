#include "bench/io/model_loader.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
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

namespace {

// `out` without trailing '/': the staging siblings are OUT.partial and OUT.old beside it, never
// "OUT/.partial" inside it.
std::string WithoutTrailingSlash(std::string out) {
  while (out.size() > 1 && out.back() == '/') out.pop_back();
  return out;
}

}  // namespace

void PublishDirectory(const std::string& staging, const std::string& out_given) {
  namespace fs = std::filesystem;
  const std::string out = WithoutTrailingSlash(out_given);
  // Held off from the interrupt clean-up: either the staging folder is removed before the
  // renames, or the output is complete after them. The old output is kept aside until the new
  // one is in place. Only what twinbench marked as its own is moved aside or removed: OUT was
  // checked to be new, empty or marked (ValidateOutputFolder) and is checked again here.
  WithCleanupHeld([&] {
    ValidateOutputFolder(out, out);
    std::error_code ec;
    const fs::path old = out + ".old";
    if (fs::exists(fs::symlink_status(old, ec))) fs::remove_all(old, ec);  // marked or empty
    if (fs::exists(fs::symlink_status(out, ec))) {
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

std::string CreateStagingDirectory(const std::string& out_given) {
  const std::string out = WithoutTrailingSlash(out_given);
  ValidateOutputFolder(out, out);
  const std::string staging = out + ".partial";
  std::error_code ec;
  // Left by a killed run (SIGKILL); ValidateOutputFolder accepted it only as empty or marked.
  if (std::filesystem::exists(std::filesystem::symlink_status(staging, ec))) {
    std::filesystem::remove_all(staging, ec);
  }
  RegisterCleanupPath(staging);
  if (!std::filesystem::create_directories(staging, ec) && ec) {
    DiscardStaging(staging);
    throw InputError(out, "cannot create the output folder: " + ec.message());
  }
  try {
    MarkFolder(staging);
  } catch (...) {
    DiscardStaging(staging);
    throw;
  }
  return staging;
}

void WriteFileAtomically(const std::string& path, const std::string& text) {
  // The temporary file is new (O_EXCL), so no file of the user's is ever truncated by it.
  std::string tmp;
  int fd = -1;
  for (int k = 0; k < 100 && fd < 0; ++k) {
    tmp = path + "." + std::to_string(getpid()) + (k ? "." + std::to_string(k) : "") + ".partial";
    fd = open(tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd < 0 && errno != EEXIST) break;
  }
  if (fd < 0) throw InputError(path, std::string("cannot open for writing: ") + std::strerror(errno));
  RegisterCleanupPath(tmp);
  if (!WriteAll(fd, text)) {
    const std::string why = std::strerror(errno);
    close(fd);
    DiscardStaging(tmp);
    throw InputError(path, "write failed: " + why);
  }
  if (close(fd) != 0) {
    DiscardStaging(tmp);
    throw InputError(path, "write failed");
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
