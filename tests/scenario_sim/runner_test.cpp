#include "colorfree/sim/runner.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "colorfree/perception/error.h"
#include "test_support.h"

namespace colorfree::sim {
namespace {

// A renderer that draws the ball as a bright column, 1 px per mm of its x, on a dark image, and
// remembers what it was told. Lets the runner's timing be checked without MuJoCo.
struct FakeLog {
  int scenes_made = 0;
  int renders = 0;
  int object_map_renders = 0;
  std::vector<double> lighting;
};

class FakeRenderer : public SceneRenderer {
 public:
  FakeRenderer(const SceneSpec& spec, FakeLog& log) : spec_(spec), log_(log) { ++log_.scenes_made; }
  void setObserver(const RobotMotionState& motion, const HeadAngles& head) override {
    observer_ = motion.pose;
    head_ = head;
  }
  void setRobot(int index, const RobotMotionState&) override {
    ASSERT_LT(index, spec_.robot_count);
  }
  void setBall(const BallMotionState& ball) override { ball_x_ = ball.position_m.x(); }
  void setLighting(const LightingState& lighting) override {
    log_.lighting.push_back(lighting.intensity_scale);
  }
  CameraModel cameraModel(NaoCamera, int w, int h) const override {
    CameraPose pose;
    pose.height_m = 0.5;
    pose.yaw_rad = head_.yaw_rad;
    return CameraModel(CameraIntrinsics::fromHorizontalFov(w, h, 1.0), pose);
  }
  Eigen::Isometry3d cameraToField(NaoCamera camera) const override {
    return robotToField(observer_) * cameraModel(camera, 16, 12).cameraToRobot();
  }
  RenderOutput render(NaoCamera, int w, int h, bool object_map) override {
    ++log_.renders;
    RenderOutput out;
    out.gray = GrayImage(w, h, 20);
    const int column = static_cast<int>(std::floor(ball_x_ * 1000));
    if (object_map) {
      ++log_.object_map_renders;
      out.object_map.width = w;
      out.object_map.height = h;
      out.object_map.labels.assign(static_cast<std::size_t>(w) * h, kObjectCarpet);
    }
    for (int y = 0; y < h; ++y) {
      if (spec_.ball && column >= 0 && column < w) {
        out.gray.at(column, y) = 220;
        if (object_map)
          out.object_map.labels[static_cast<std::size_t>(y) * w + column] = kObjectBall;
      }
    }
    return out;
  }

 private:
  SceneSpec spec_;
  FakeLog& log_;
  FieldPose observer_;
  HeadAngles head_;
  double ball_x_ = 0;
};

RendererFactory fakeFactory(FakeLog& log) {
  return [&log](const SceneSpec& spec) -> std::unique_ptr<SceneRenderer> {
    return std::make_unique<FakeRenderer>(spec, log);
  };
}

std::string scenario(const std::string& extra) {
  return R"(name: fake
camera: top
resolution: [200, 16]
frames: 3
frame_rate_hz: 10
seed: 3
observer: {x_m: -1, y_m: 0, heading_deg: 0, head: {yaw_deg: 10}}
robots:
  - {x_m: 1, y_m: 0, heading_deg: 180, motion: {type: walk, speed_mps: 0.1}}
ball: {x_m: 0.0502, y_m: 0, velocity_x_mps: 1.0, deceleration_mps2: 0}
lighting: {preset: normal}
)" + extra;
}

int brightColumn(const GrayImage& g, int row) {
  int best = -1;
  for (int x = 0; x < g.width(); ++x) {
    if (g.at(x, row) > 200) best = x;
  }
  return best;
}

TEST(RunnerTest, FrameTruthFollowsTheScenario) {
  FakeLog log;
  ScenarioRunner runner(Scenario::parse(scenario(""), "fake.yaml"), fakeFactory(log));
  const RenderedFrame f = runner.render(0, 1);
  EXPECT_EQ(f.frame_index, 1);
  EXPECT_DOUBLE_EQ(f.truth.time_s, 0.1);
  ASSERT_EQ(f.truth.robots.size(), 1u);
  EXPECT_NEAR(f.truth.robots[0].pose.x_m, 1 - 0.01, test::kMetreTolerance);
  EXPECT_EQ(f.truth.robots[0].posture, "walking");
  EXPECT_DOUBLE_EQ(f.truth.robots[0].speed_mps, 0.1);
  EXPECT_TRUE(f.truth.ball.present);
  EXPECT_NEAR(f.truth.ball.position_m.x(), 0.1502, test::kMetreTolerance);
  EXPECT_NEAR(f.truth.observer_head_yaw_rad, 10 * std::numbers::pi / 180, 1e-12);
  EXPECT_EQ(f.truth.camera.name, "top");
  EXPECT_EQ(f.truth.camera.model.width(), 200);
  EXPECT_NEAR(f.truth.camera.camera_to_field.translation().x(), -1, test::kMetreTolerance);
  // The image and the object map show the ball where the truth has it.
  EXPECT_EQ(brightColumn(f.image, 0), 150);
  ASSERT_EQ(f.truth.object_map.labels.size(), 200u * 16u);
  EXPECT_EQ(f.truth.object_map.at(150, 5), kObjectBall);
  EXPECT_EQ(log.renders, 1);
  EXPECT_EQ(runner.render(0, 2, false).truth.object_map.labels.size(), 0u);
}

// The largest difference between two poses' matrix entries.
double poseDifference(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  double d = 0;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) d = std::max(d, std::abs(a.matrix()(i, j) - b.matrix()(i, j)));
  }
  return d;
}

// The believed camera of a camera posed by yaw and pitch alone is that pose with the errors added.
TEST(RunnerTest, PerceivedCameraAddsTheErrorToTheCamerasPose) {
  const CameraIntrinsics in = CameraIntrinsics::fromHorizontalFov(640, 480, 1.06);
  CameraPose pose;
  pose.x_m = 0.05;
  pose.y_m = -0.01;
  pose.height_m = 0.51;
  pose.pitch_rad = 0.3;
  pose.yaw_rad = -0.6;
  const CameraModel truth(in, pose);
  CameraErrorSpec error;
  EXPECT_EQ(poseDifference(perceivedCamera(truth, error).cameraToRobot(), truth.cameraToRobot()), 0);
  error.pitch_rad = 0.035;
  error.roll_rad = -0.02;
  error.yaw_rad = 0.01;
  error.height_m = 0.015;
  CameraPose believed = pose;
  believed.pitch_rad += error.pitch_rad;
  believed.roll_rad += error.roll_rad;
  believed.yaw_rad += error.yaw_rad;
  believed.height_m += error.height_m;
  const CameraModel got = perceivedCamera(truth, error);
  EXPECT_LT(poseDifference(got.cameraToRobot(), CameraModel(in, believed).cameraToRobot()), 1e-12)
      << got.cameraToRobot().matrix() << "\n" << CameraModel(in, believed).cameraToRobot().matrix();
  EXPECT_EQ(got.intrinsics().focal_x_px, in.focal_x_px);
  // A camera believed to look further down sees the horizon higher in the image (its believed
  // horizon row is above the true one's).
  CameraErrorSpec down;
  down.pitch_rad = 0.035;
  EXPECT_LT(*perceivedCamera(truth, down).horizonY(320), *truth.horizonY(320) - 15);
}

TEST(RunnerTest, PerceptionCameraCarriesTheScenariosCameraError) {
  FakeLog log;
  ScenarioRunner plain(Scenario::parse(scenario(""), "fake.yaml"), fakeFactory(log));
  const RenderedFrame a = plain.render(0, 1);
  EXPECT_EQ(poseDifference(a.perception_camera.cameraToRobot(), a.truth.camera.model.cameraToRobot()), 0);
  ScenarioRunner off(Scenario::parse(scenario("camera_error: {pitch_deg: 2, height_m: 0.02}\n"), "fake.yaml"),
                     fakeFactory(log));
  const RenderedFrame b = off.render(0, 1);
  // The image and the truth are those of the true camera; only the perception's model moves.
  EXPECT_EQ(b.image.pixels(), a.image.pixels());
  EXPECT_EQ(poseDifference(b.truth.camera.model.cameraToRobot(), a.truth.camera.model.cameraToRobot()), 0);
  EXPECT_NEAR(b.perception_camera.position().z(), a.truth.camera.model.position().z() + 0.02, 1e-12);
  EXPECT_EQ(poseDifference(b.perception_camera.cameraToRobot(),
                           perceivedCamera(b.truth.camera.model, off.scenarioCase(0).settings.camera_error)
                               .cameraToRobot()),
            0);
}

TEST(RunnerTest, MotionBlurAveragesSubframesAcrossTheExposure) {
  FakeLog log;
  ScenarioRunner runner(
      Scenario::parse(scenario("effects: {exposure_ms: 20, blur_subframes: 4}\n"), "fake.yaml"),
      fakeFactory(log));
  const RenderedFrame f = runner.render(0, 1);
  // Sub-frames at -7.5, -2.5, 2.5, 7.5 ms: the ball at 142.7, 147.7, 152.7, 157.7 mm.
  for (int x : {142, 147, 152, 157}) EXPECT_EQ(f.image.at(x, 3), 20 + 200 / 4) << x;
  EXPECT_EQ(f.image.at(150, 3), 20);
  EXPECT_EQ(log.renders, 5);  // four sub-frames and the object map at the frame time
  EXPECT_EQ(f.truth.object_map.at(150, 3), kObjectBall);
}

// The perception's camera carries the camera's own smear over the exposure (what a robot's
// kinematics would tell it): the head turning left at 20 * 2 pi deg/s at t = 0 moves the still
// scene right by the focal length times the 20 ms turn; none with a still head or without blur.
TEST(RunnerTest, PerceptionCameraCarriesTheExposureSmearOfTheHeadsTurn) {
  const auto smear = [](const std::string& head, const std::string& effects) {
    FakeLog log;
    std::string text = scenario("effects: " + effects + "\n");
    const std::string still = "head: {yaw_deg: 10}";
    text.replace(text.find(still), still.size(), head);
    ScenarioRunner runner(Scenario::parse(text, "fake.yaml"), fakeFactory(log));
    return runner.render(0, 0, false).perception_camera.exposureSmearPx();
  };
  const std::string turning = "head: {yaw_deg: 10, yaw_amplitude_deg: 20, yaw_period_s: 1}";
  const Eigen::Vector2d s = smear(turning, "{exposure_ms: 20, blur_subframes: 4}");
  const double focal = 100 / std::tan(0.5);  // the fake camera: 200 px over 1 rad
  const double turn =
      2 * (20 * std::numbers::pi / 180) * std::sin(2 * std::numbers::pi * 0.010);  // over 20 ms
  EXPECT_NEAR(s.x(), focal * turn, 0.03 * focal * turn);
  EXPECT_NEAR(s.y(), 0, 0.05);
  EXPECT_TRUE(smear("head: {yaw_deg: 10}", "{exposure_ms: 20, blur_subframes: 4}").isZero(1e-9));
  EXPECT_TRUE(smear(turning, "{exposure_ms: 0}").isZero(0));
  // A rolling shutter's sub-frames are readout bands, not exposure: only the exposure smears.
  const Eigen::Vector2d banded =
      smear(turning, "{exposure_ms: 20, blur_subframes: 4, rolling_shutter: true, readout_ms: 16}");
  EXPECT_NEAR(banded.x(), focal * turn, 0.03 * focal * turn);
}

// ... and the shift of a rolling shutter's readout: 16 ms of the same turn from the first row to
// the last; none with a global shutter.
TEST(RunnerTest, PerceptionCameraCarriesTheRollingShuttersShift) {
  const auto shift = [](const std::string& effects) {
    FakeLog log;
    std::string text = scenario("effects: " + effects + "\n");
    const std::string still = "head: {yaw_deg: 10}";
    text.replace(text.find(still), still.size(),
                 "head: {yaw_deg: 10, yaw_amplitude_deg: 20, yaw_period_s: 1}");
    ScenarioRunner runner(Scenario::parse(text, "fake.yaml"), fakeFactory(log));
    return runner.render(0, 0, false).perception_camera.rollingShutterShiftPx();
  };
  const double focal = 100 / std::tan(0.5);
  const double turn =
      2 * (20 * std::numbers::pi / 180) * std::sin(2 * std::numbers::pi * 0.008);  // over 16 ms
  for (const std::string blur : {"", ", exposure_ms: 20, blur_subframes: 4"}) {
    const Eigen::Vector2d s =
        shift("{rolling_shutter: true, readout_ms: 16, rolling_shutter_bands: 16" + blur + "}");
    EXPECT_NEAR(s.x(), focal * turn, 0.03 * focal * turn) << blur;
    EXPECT_NEAR(s.y(), 0, 0.05) << blur;
  }
  EXPECT_TRUE(shift("{exposure_ms: 20, blur_subframes: 4}").isZero(0));
}

TEST(RunnerTest, RollingShutterSkewsAMovingBall) {
  FakeLog log;
  ScenarioRunner runner(Scenario::parse(scenario("effects: {rolling_shutter: true, readout_ms: 16, "
                                                 "rolling_shutter_bands: 16}\n"),
                                        "fake.yaml"),
                        fakeFactory(log));
  const RenderedFrame f = runner.render(0, 1, false);
  // Row y is read at (y + 0.5) ms - 8 ms: the ball moves 1 mm (1 px) per row.
  for (int y = 0; y < 16; ++y) {
    EXPECT_EQ(brightColumn(f.image, y), static_cast<int>(std::floor(150 + (y + 0.5) - 8))) << y;
  }
  EXPECT_EQ(log.renders, 16);
}

TEST(RunnerTest, SameScenarioSameBytes) {
  const std::string text =
      scenario("effects: {noise_sigma: 3, shot_noise: 0.2, exposure_ms: 10, blur_subframes: 2}\n");
  FakeLog log_a, log_b;
  ScenarioRunner a(Scenario::parse(text, "fake.yaml"), fakeFactory(log_a));
  ScenarioRunner b(Scenario::parse(text, "fake.yaml"), fakeFactory(log_b));
  for (int k : {0, 2, 1}) EXPECT_EQ(a.render(0, k).image.pixels(), b.render(0, k).image.pixels());
  EXPECT_NE(a.render(0, 0).image.pixels(), a.render(0, 1).image.pixels());
}

TEST(RunnerTest, SceneIsRebuiltOnlyWhenTheCaseNeedsAnother) {
  FakeLog log;
  ScenarioRunner runner(
      Scenario::parse(scenario("sweep:\n  - path: lighting.scale\n    values: [0.5, 1.5]\n"),
                      "fake.yaml"),
      fakeFactory(log));
  runner.render(0, 0);
  runner.render(1, 0);
  EXPECT_EQ(log.scenes_made, 1);
  EXPECT_DOUBLE_EQ(log.lighting.front(), 0.5);
  EXPECT_DOUBLE_EQ(log.lighting.back(), 1.5);

  FakeLog log2;
  ScenarioRunner presets(
      Scenario::parse(scenario("sweep:\n  - path: lighting.preset\n    values: [dim, uneven]\n"),
                      "fake.yaml"),
      fakeFactory(log2));
  int frames = 0;
  for (int k = 0; k < presets.caseCount(); ++k) {
    presets.runCase(k, -1, false, [&](const RenderedFrame& f) {
      EXPECT_EQ(f.case_index, k);
      EXPECT_EQ(f.frame_index, frames % 3);
      ++frames;
    });
  }
  EXPECT_EQ(frames, 6);
  EXPECT_EQ(log2.scenes_made, 2);
}

TEST(RunnerTest, FlickerChangesTheLightOverFrames) {
  FakeLog log;
  std::string text = scenario("");
  text.replace(text.find("{preset: normal}"), 16,
               "{preset: normal, scale: 2, flicker_amplitude: 0.3, flicker_frequency_hz: 2.5}");
  ScenarioRunner runner(Scenario::parse(text, "fake.yaml"), fakeFactory(log));
  runner.render(0, 0);
  runner.render(0, 1);  // a quarter period later: the peak
  EXPECT_DOUBLE_EQ(log.lighting[0], 2.0);
  EXPECT_NEAR(log.lighting[1], 2.6, 1e-12);

  // The flicker preset follows the world's flicker of each frame.
  FakeLog preset_log;
  std::string preset = scenario("");
  preset.replace(preset.find("{preset: normal}"), 16, "{preset: flicker, scale: 0.5}");
  ScenarioRunner flicker(Scenario::parse(preset, "fake.yaml"), fakeFactory(preset_log));
  for (int k = 0; k < 3; ++k) flicker.render(0, k);
  for (int k = 0; k < 3; ++k) {
    EXPECT_DOUBLE_EQ(preset_log.lighting[static_cast<std::size_t>(k)], 0.5 * flickerScale(3, k));
  }
  EXPECT_NE(preset_log.lighting[0], preset_log.lighting[1]);
}

TEST(RunnerTest, BadCaseOrFrameIsAnError) {
  FakeLog log;
  ScenarioRunner runner(Scenario::parse(scenario(""), "fake.yaml"), fakeFactory(log));
  EXPECT_THROW(runner.render(1, 0), Error);
  EXPECT_THROW(runner.render(0, -1), Error);
}

}  // namespace
}  // namespace colorfree::sim
