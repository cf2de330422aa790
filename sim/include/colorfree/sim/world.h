#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "colorfree/groundtruth/world_state.h"
#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/field_dimensions.h"
#include "colorfree/perception/image.h"

namespace colorfree::sim {

/// Lighting presets a scenario picks (docs/scenarios.md describes each).
enum class LightingPreset { kNormal, kDim, kOverexposed, kDirectional, kUneven, kFlicker };
LightingPreset lightingPresetFromName(const std::string& name);  // throws colorfree::Error
std::string lightingPresetName(LightingPreset preset);

/// What is built once per scene: which objects exist and how the hall looks.
struct SceneSpec {
  FieldDimensions field;
  int robot_count = 0;                   ///< other robots, at most 10 with the observer
  std::vector<double> jersey_gray;       ///< per robot, 0 black .. 1 white; default 0.5
  bool ball = true;
  LightingPreset lighting = LightingPreset::kNormal;
  std::uint64_t seed = 1;                ///< textures, hall clutter, uneven-light patches
  bool shadows = true;
  int multisamples = 4;                  ///< 0 disables anti-aliasing
  int max_width_px = 640;                ///< off-screen buffer size
  int max_height_px = 480;
  double observer_jersey_gray = 0.5;     ///< 0 black .. 1 white
  double camera_horizontal_fov_deg = 60.9;  ///< horizontal; NAO V4/V5 60.9, V6 56.3
  int shadow_map_px = 2048;  ///< 4096 halves the shadow edges' steps, costs about 40 % more time
};

/// NAO joint angles in radians (NAO names and signs; right-side roll joints as on the robot)
/// plus the torso's height above the ground and its sway.
struct NaoPosture {
  double head_yaw = 0, head_pitch = 0;
  double l_shoulder_pitch = 1.5, l_shoulder_roll = 0.15, l_elbow_yaw = -1.2, l_elbow_roll = -0.5;
  double r_shoulder_pitch = 1.5, r_shoulder_roll = -0.15, r_elbow_yaw = 1.2, r_elbow_roll = 0.5;
  double l_hip_yaw_pitch = 0, l_hip_roll = 0, l_hip_pitch = -0.4, l_knee_pitch = 0.8,
         l_ankle_pitch = -0.4, l_ankle_roll = 0;
  double r_hip_yaw_pitch = 0, r_hip_roll = 0, r_hip_pitch = -0.4, r_knee_pitch = 0.8,
         r_ankle_pitch = -0.4, r_ankle_roll = 0;
};

/// The NAO's posture in a procedural walk at `speed_mps` (0 = standing), `phase` in [0, 1) of the
/// gait cycle; the torso's height follows from the leg kinematics so the feet stay on the ground.
NaoPosture walkPosture(double phase, double speed_mps);

/// A NAO placed on the field: ground point and heading, and its posture.
struct NaoState {
  FieldPose pose;
  NaoPosture posture;
};

enum class NaoCamera { kTop, kBottom };

/// One rendered frame: luma, rows top-down, and the per-pixel object map (labels as
/// groundtruth's ObjectLabel, robot i = kObjectRobotBase + i).
struct RenderOutput {
  GrayImage gray;
  ObjectMap object_map;
};

/// Per-frame light level: a factor on every light of the preset (flicker and sweeps use it).
struct LightingState {
  double intensity_scale = 1.0;
};

/// A flickering hall light's intensity factor for a frame (mains-driven lamps beating with the
/// camera's frame rate, plus seeded irregular dips), about 0.4..1.05; deterministic per seed.
double flickerScale(std::uint64_t seed, int frame_index);

/// The MuJoCo world of one scene with its off-screen renderer. Builds the MJCF (field, goals,
/// hall, ball, NAOs) and its textures in memory from a SceneSpec; not copyable; one GL context per
/// World, so one World per thread.
class World {
 public:
  /// Throws colorfree::Error when the spec is impossible, MuJoCo rejects the model, or no
  /// off-screen GL context can be made.
  explicit World(const SceneSpec& spec);
  ~World();
  World(const World&) = delete;
  World& operator=(const World&) = delete;

  void setObserver(const NaoState& observer);
  void setRobot(int index, const NaoState& robot);
  /// Ball centre in field coordinates, and its orientation (rolling).
  void setBall(const Eigen::Vector3d& centre_in_field, const Eigen::Quaterniond& orientation);
  void setLighting(const LightingState& lighting);

  /// The observer's camera as a CameraModel relative to the observer's robot frame (ground under
  /// the torso), at the given resolution, for the current posture.
  CameraModel cameraModel(NaoCamera camera, int width_px, int height_px) const;
  /// The same camera's pose on the field.
  Eigen::Isometry3d cameraToField(NaoCamera camera) const;

  /// Renders the observer's camera. With `object_map` false the map is left empty.
  RenderOutput render(NaoCamera camera, int width_px, int height_px, bool object_map = true);

  /// The MJCF the world was built from (for debugging and for tests).
  const std::string& mjcf() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace colorfree::sim
