#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "colorfree/sim/world.h"

namespace colorfree::sim {

/// One light of the scene as built, before the per-frame intensity scale.
struct LightBase {
  float diffuse[3];
  float specular[3];
};

/// The MJCF of a scene and the files it refers to (textures), all in memory.
struct SceneModel {
  std::string mjcf;
  std::map<std::string, std::vector<std::uint8_t>> files;
  std::vector<LightBase> lights;  ///< in the order of the MJCF's <light> elements
  float headlight_ambient = 0;    ///< ambient light (grey) before the intensity scale
};

/// Checks the spec; throws colorfree::Error naming the setting that is impossible.
void validateSceneSpec(const SceneSpec& spec);

/// Builds the MJCF and the textures. Deterministic for a given spec (seed included).
SceneModel buildScene(const SceneSpec& spec);

/// Geom names start with these, so that the object map can label them.
inline constexpr const char* kCarpetPrefix = "carpet";
inline constexpr const char* kLinePrefix = "line_";
inline constexpr const char* kGoalPrefix = "goal_";
inline constexpr const char* kBallPrefix = "ball";
inline constexpr const char* kObserverPrefix = "obs_";
/// Robot i's names start with robotPrefix(i).
std::string robotPrefix(int index);

}  // namespace colorfree::sim
