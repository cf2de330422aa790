#pragma once

#include <mujoco/mujoco.h>

#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace colorfree::sim {

struct MjModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
using MjModelPtr = std::unique_ptr<mjModel, MjModelDeleter>;

/// Compiles MJCF text together with in-memory files it refers to (textures) through MuJoCo's
/// virtual file system. Throws colorfree::Error naming `origin` and MuJoCo's message when MuJoCo
/// rejects the model.
MjModelPtr loadMjcf(const std::string& mjcf,
                    const std::map<std::string, std::vector<std::uint8_t>>& files,
                    const std::string& origin);

}  // namespace colorfree::sim
