#include "colorfree/sim/world_renderer.h"

namespace colorfree::sim {
namespace {

class WorldRenderer : public SceneRenderer {
 public:
  explicit WorldRenderer(const SceneSpec& spec) : world_(spec) {}

  void setObserver(const RobotMotionState& motion, const HeadAngles& head) override {
    world_.setObserver(NaoState{motion.pose, postureFor(motion, head)});
  }
  void setRobot(int index, const RobotMotionState& motion) override {
    world_.setRobot(index, NaoState{motion.pose, postureFor(motion)});
  }
  void setBall(const BallMotionState& ball) override {
    world_.setBall(ball.position_m, ball.orientation);
  }
  void setLighting(const LightingState& lighting) override { world_.setLighting(lighting); }
  CameraModel cameraModel(NaoCamera camera, int width_px, int height_px) const override {
    return world_.cameraModel(camera, width_px, height_px);
  }
  Eigen::Isometry3d cameraToField(NaoCamera camera) const override {
    return world_.cameraToField(camera);
  }
  RenderOutput render(NaoCamera camera, int width_px, int height_px, bool object_map) override {
    return world_.render(camera, width_px, height_px, object_map);
  }

 private:
  World world_;
};

}  // namespace

NaoPosture postureFor(const RobotMotionState& motion, const HeadAngles& head) {
  NaoPosture posture = walkPosture(motion.gait_phase, motion.gait_speed_mps);
  posture.head_yaw = head.yaw_rad;
  posture.head_pitch = head.pitch_rad;
  return posture;
}

RendererFactory worldRendererFactory() {
  return [](const SceneSpec& spec) -> std::unique_ptr<SceneRenderer> {
    return std::make_unique<WorldRenderer>(spec);
  };
}

}  // namespace colorfree::sim
