#include <gtest/gtest.h>

#include <cmath>

#include "colorfree/sim/runner.h"
#include "colorfree/sim/world_renderer.h"
#include "test_support.h"

namespace colorfree::sim {
namespace {

// Small frames keep these tests quick; the scene still has a walking robot, a rolling ball,
// a moving head, blur and noise.
const char* kScenario = R"(name: render_test
camera: top
resolution: [160, 120]
frames: 2
frame_rate_hz: 30
seed: 11
shadows: false
multisamples: 0
observer:
  x_m: 0
  y_m: 0
  heading_deg: 0
  head: {pitch_deg: 12, yaw_amplitude_deg: 10, yaw_period_s: 1}
robots:
  - {distance_m: 1.3, bearing_deg: 8, heading_deg: 150, motion: {type: walk, speed_mps: 0.15}}
ball: {distance_m: 0.9, bearing_deg: -12, velocity_x_mps: 0.4, deceleration_mps2: 0.3}
lighting: {preset: normal}
effects: {noise_sigma: 2, shot_noise: 0.1, exposure_ms: 10, blur_subframes: 2}
)";

TEST(ScenarioRenderTest, SameScenarioAndSeedGiveIdenticalFrames) {
  ScenarioRunner a(Scenario::parse(kScenario, "render_test.yaml"), worldRendererFactory());
  ScenarioRunner b(Scenario::parse(kScenario, "render_test.yaml"), worldRendererFactory());
  const RenderedFrame a1 = a.render(0, 1);
  const RenderedFrame b1 = b.render(0, 1);
  EXPECT_EQ(a1.image.pixels(), b1.image.pixels());
  EXPECT_EQ(a1.truth.object_map.labels, b1.truth.object_map.labels);
  // Rendering another frame in between does not change a frame.
  a.render(0, 0);
  EXPECT_EQ(a.render(0, 1).image.pixels(), a1.image.pixels());
  // A frame later the scene has moved.
  EXPECT_NE(a.render(0, 0).image.pixels(), a1.image.pixels());
}

// Projected with the truth's camera model, the robot's and the ball's true positions land on
// their labels in the object map: image, truth and camera model agree.
TEST(ScenarioRenderTest, TruthProjectsOntoTheObjectMap) {
  ScenarioRunner runner(Scenario::parse(kScenario, "render_test.yaml"), worldRendererFactory());
  for (int frame : {0, 1}) {
    const RenderedFrame f = runner.render(0, frame);
    const WorldState& s = f.truth;
    ASSERT_EQ(s.object_map.width, 160);
    const Eigen::Isometry3d field_to_robot = robotToField(s.observer).inverse();
    auto labelAt = [&](const Eigen::Vector3d& in_field) {
      const auto px = s.camera.model.robotToPixel(field_to_robot * in_field);
      EXPECT_TRUE(px.has_value());
      if (!px) return -1;
      const int x = static_cast<int>(std::floor(px->x()));
      const int y = static_cast<int>(std::floor(px->y()));
      EXPECT_TRUE(x >= 0 && y >= 0 && x < 160 && y < 120) << x << "," << y;
      if (!(x >= 0 && y >= 0 && x < 160 && y < 120)) return -1;
      return static_cast<int>(s.object_map.at(x, y));
    };
    EXPECT_EQ(labelAt(s.ball.position_m), kObjectBall) << "frame " << frame;
    const RobotTruth& r = s.robots.at(0);
    // The robot's chest, 0.4 m above its ground point.
    EXPECT_EQ(labelAt(Eigen::Vector3d(r.pose.x_m, r.pose.y_m, 0.4)), kObjectRobotBase + 0)
        << "frame " << frame;
    // The camera pose in the truth is the one the model was made from.
    const Eigen::Isometry3d composed = robotToField(s.observer) * s.camera.model.cameraToRobot();
    EXPECT_TRUE(composed.isApprox(s.camera.camera_to_field, 1e-9));
  }
}

}  // namespace
}  // namespace colorfree::sim
