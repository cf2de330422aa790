#pragma once

#include <functional>
#include <memory>

#include "colorfree/groundtruth/world_state.h"
#include "colorfree/sim/camera_effects.h"
#include "colorfree/sim/motion.h"
#include "colorfree/sim/scenario.h"
#include "colorfree/sim/world.h"

namespace colorfree::sim {

/// What the runner needs from a renderer: the MuJoCo World (world_renderer.h), or a synthetic
/// one in tests. The runner sets the whole scene before every render.
class SceneRenderer {
 public:
  virtual ~SceneRenderer() = default;
  virtual void setObserver(const RobotMotionState& motion, const HeadAngles& head) = 0;
  virtual void setRobot(int index, const RobotMotionState& motion) = 0;
  virtual void setBall(const BallMotionState& ball) = 0;
  virtual void setLighting(const LightingState& lighting) = 0;
  virtual CameraModel cameraModel(NaoCamera camera, int width_px, int height_px) const = 0;
  virtual Eigen::Isometry3d cameraToField(NaoCamera camera) const = 0;
  virtual RenderOutput render(NaoCamera camera, int width_px, int height_px, bool object_map) = 0;
};

/// Makes a renderer for a scene; called again only when a case needs a different scene.
using RendererFactory = std::function<std::unique_ptr<SceneRenderer>(const SceneSpec&)>;

/// The scene a case is rendered in (robots, jerseys, ball, lighting preset, quality).
SceneSpec sceneSpecFor(const CaseSettings& settings);
bool sameScene(const SceneSpec& a, const SceneSpec& b);

/// Time of a frame, seconds from the start.
double frameTime(const CaseSettings& settings, int frame_index);

/// The truth that follows from the scenario alone at a frame's time: observer pose and head,
/// robots, ball (the camera and the object map come from the renderer).
WorldState scenarioStateAt(const CaseSettings& settings, int frame_index);

/// The light level of a frame at time `t_s`: scale and sinusoidal flicker, and for the flicker
/// preset world.h's flickerScale of the frame.
double lightingScaleAt(const CaseSettings& settings, int frame_index, double t_s);

/// The ball's orientation at time 0 (seeded, so that the print differs between scenarios).
Eigen::Quaterniond initialBallOrientation(std::uint64_t seed);

/// The camera model a robot with `error` in its camera pose believes in: the true camera's viewing
/// direction turned by the error in its own frame (x along the view, y left, z up):
/// Rz(yaw) · B · Ry(pitch) · Rx(roll), B the true camera's body frame and Rz about the robot's
/// vertical; the optical centre raised by height_m. For a camera with no roll of its own this is the
/// camera file's pose with the errors added to its yaw, pitch, roll and height.
CameraModel perceivedCamera(const CameraModel& truth, const CameraErrorSpec& error);

/// One frame of one case: the image with its camera effects, and the truth at the frame time.
struct RenderedFrame {
  int case_index = 0;
  int frame_index = 0;
  GrayImage image;
  WorldState truth;  ///< object_map filled when it was asked for
  /// The camera model the perception is given: truth.camera.model with the case's camera_error
  /// (the same model when there is none). Scoring projects the truth with truth.camera.model.
  CameraModel perception_camera;
};

/// Renders the cases of a scenario frame by frame. Deterministic: the same scenario gives the same
/// frames byte for byte. Not thread-safe (one renderer, one GL context).
class ScenarioRunner {
 public:
  ScenarioRunner(Scenario scenario, RendererFactory factory);

  const Scenario& scenario() const { return scenario_; }
  int caseCount() const { return static_cast<int>(scenario_.cases.size()); }
  const ScenarioCase& scenarioCase(int case_index) const;

  /// Renders frame `frame_index` of case `case_index` (any frame, in any order; frames past the
  /// scenario's count continue its motion). Throws colorfree::Error on a bad index.
  RenderedFrame render(int case_index, int frame_index, bool object_map = true);

  /// Renders frames 0..frames-1 of a case (frames < 0: the scenario's count) and hands each to
  /// `sink` in order.
  void runCase(int case_index, int frames, bool object_map,
               const std::function<void(const RenderedFrame&)>& sink);

 private:
  SceneRenderer& rendererFor(const CaseSettings& settings);
  void setSceneAt(SceneRenderer& renderer, const CaseSettings& settings, int frame_index,
                  double t_s) const;

  Scenario scenario_;
  RendererFactory factory_;
  std::unique_ptr<SceneRenderer> renderer_;
  SceneSpec renderer_spec_;
};

}  // namespace colorfree::sim
