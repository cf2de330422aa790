#include "colorfree/sim/mjcf_loader.h"

#include <cstring>

#include "colorfree/perception/error.h"
#include "colorfree/sim/mujoco_errors.h"

namespace colorfree::sim {

namespace {
constexpr const char* kModelFileName = "colorfree_scene.xml";

struct VfsDeleter {
  void operator()(mjVFS* vfs) const {
    mj_deleteVFS(vfs);
    delete vfs;
  }
};

void addFile(mjVFS* vfs, const std::string& name, const void* data, std::size_t size,
             const std::string& origin) {
  const int rc = mj_makeEmptyFileVFS(vfs, name.c_str(), static_cast<int>(size));
  if (rc != 0) {
    throw Error(origin + ": cannot add " + name + " to MuJoCo's virtual file system (" +
                (rc == 1 ? "full" : "repeated name") + ")");
  }
  const int index = mj_findFileVFS(vfs, name.c_str());
  std::memcpy(vfs->filedata[index], data, size);
}
}  // namespace

MjModelPtr loadMjcf(const std::string& mjcf,
                    const std::map<std::string, std::vector<std::uint8_t>>& files,
                    const std::string& origin) {
  installMujocoErrorHandlers();
  // mjVFS holds fixed arrays of 2000 names: too large for the stack.
  std::unique_ptr<mjVFS, VfsDeleter> vfs(new mjVFS);
  mj_defaultVFS(vfs.get());
  addFile(vfs.get(), kModelFileName, mjcf.data(), mjcf.size(), origin);
  for (const auto& [name, bytes] : files)
    addFile(vfs.get(), name, bytes.data(), bytes.size(), origin);
  char error[1024] = "";
  mjModel* model = nullptr;
  try {
    model = mj_loadXML(kModelFileName, vfs.get(), error, sizeof(error));
  } catch (const Error& e) {
    throw Error(origin + ": MuJoCo rejected the model: " + e.what());
  }
  if (model == nullptr) throw Error(origin + ": MuJoCo rejected the model: " + std::string(error));
  return MjModelPtr(model);
}

}  // namespace colorfree::sim
