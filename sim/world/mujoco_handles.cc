#include "sim/world/mujoco_handles.h"

#include <stdexcept>

namespace twin {
namespace {

void ThrowMujocoError(const char* msg) { throw std::runtime_error(std::string("MuJoCo: ") + msg); }

struct VfsDeleter {
  void operator()(mjVFS* vfs) const {
    mj_deleteVFS(vfs);
    delete vfs;
  }
};

}  // namespace

void InstallMujocoErrorHandlers() {
  mju_user_error = ThrowMujocoError;
  mju_user_warning = ThrowMujocoError;
}

MjModelPtr LoadMjcfFromString(const std::string& mjcf) {
  std::unique_ptr<mjVFS, VfsDeleter> vfs(new mjVFS);  // large: keep it off the stack
  mj_defaultVFS(vfs.get());
  const char* name = "twin.xml";
  if (mj_makeEmptyFileVFS(vfs.get(), name, static_cast<int>(mjcf.size())) != 0) {
    throw std::runtime_error("MuJoCo VFS: cannot allocate the MJCF buffer");
  }
  const int index = mj_findFileVFS(vfs.get(), name);
  std::copy(mjcf.begin(), mjcf.end(), static_cast<char*>(vfs->filedata[index]));
  char error[1000] = "";
  MjModelPtr model(mj_loadXML(name, vfs.get(), error, sizeof(error)));
  if (!model) throw std::runtime_error(std::string("MuJoCo could not compile the MJCF: ") + error);
  return model;
}

int WarningCount(const mjData* d) {
  int n = 0;
  for (int i = 0; i < mjNWARNING; ++i) n += d->warning[i].number;
  return n;
}

}  // namespace twin
