#include "colorfree/sim/scenario.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <numbers>

#include "colorfree/perception/error.h"
#include "test_support.h"

namespace colorfree::sim {
namespace {

constexpr double kDeg = std::numbers::pi / 180;

const char* kMinimal = R"(name: minimal
camera: top
frames: 3
frame_rate_hz: 30
seed: 5
observer:
  x_m: -1.0
  y_m: 0.5
  heading_deg: 90
lighting:
  preset: dim
)";

// The message of the colorfree::Error that parsing `text` throws ("" when it does not throw).
std::string errorOf(const std::string& text) {
  try {
    Scenario::parse(text, "bad.yaml");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(ScenarioTest, MinimalScenarioGetsItsValuesAndTheDefaults) {
  const Scenario s = Scenario::parse(kMinimal, "minimal.yaml");
  EXPECT_EQ(s.name, "minimal");
  ASSERT_EQ(s.cases.size(), 1u);
  const CaseSettings& c = s.cases[0].settings;
  EXPECT_EQ(c.camera, NaoCamera::kTop);
  EXPECT_EQ(c.width_px, 640);
  EXPECT_EQ(c.height_px, 480);
  EXPECT_EQ(c.frames, 3);
  EXPECT_EQ(c.seed, 5u);
  EXPECT_DOUBLE_EQ(c.observer.pose.x_m, -1.0);
  EXPECT_DOUBLE_EQ(c.observer.pose.heading_rad, 90 * kDeg);
  EXPECT_EQ(c.lighting.preset, LightingPreset::kDim);
  EXPECT_DOUBLE_EQ(c.lighting.scale, 1.0);
  EXPECT_FALSE(c.ball.has_value());
  EXPECT_TRUE(c.robots.empty());
  EXPECT_EQ(c.effects.blur_subframes, 1);
  EXPECT_TRUE(s.cases[0].values.empty());
}

TEST(ScenarioTest, LightingPresetsAreSpelledAsTheWorldSpellsThem) {
  for (LightingPreset p :
       {LightingPreset::kNormal, LightingPreset::kDim, LightingPreset::kOverexposed,
        LightingPreset::kDirectional, LightingPreset::kUneven, LightingPreset::kFlicker}) {
    std::string text = kMinimal;
    text.replace(text.find("preset: dim"), 11, "preset: " + lightingPresetName(p));
    EXPECT_EQ(Scenario::parse(text, "x.yaml").cases[0].settings.lighting.preset, p);
  }
}

TEST(ScenarioTest, NaoVersionPicksTheCameraFieldOfView) {
  EXPECT_DOUBLE_EQ(Scenario::parse(kMinimal, "x").cases[0].settings.camera_horizontal_fov_deg,
                   60.9);
  const Scenario v6 = Scenario::parse(std::string(kMinimal) + "nao: v6\n", "x");
  EXPECT_DOUBLE_EQ(v6.cases[0].settings.camera_horizontal_fov_deg, 56.3);
  EXPECT_NE(
      errorOf(std::string(kMinimal) + "nao: v7\n").find("bad.yaml:12: nao: 'v7' is not one of"),
      std::string::npos);
}

TEST(ScenarioTest, BottomCameraDefaultsToItsResolution) {
  std::string text = kMinimal;
  text.replace(text.find("camera: top"), 11, "camera: bottom");
  const Scenario s = Scenario::parse(text, "x.yaml");
  EXPECT_EQ(s.cases[0].settings.width_px, 320);
  EXPECT_EQ(s.cases[0].settings.height_px, 240);
}

TEST(ScenarioTest, RobotsBallMotionEffectsAndExpectations) {
  const std::string text = std::string(kMinimal) + R"(resolution: [320, 240]
robots:
  - x_m: 1.0
    y_m: -0.5
    heading_deg: 180
    jersey_gray: 0.2
    motion: {type: walk, speed_mps: 0.12, direction_deg: 90}
  - distance_m: 1.2
    bearing_deg: 0
    heading_deg: 45
    motion: {type: turn, rate_degps: -30}
  - x_m: 0
    y_m: 0
    heading_deg: 0
    motion: stand
ball:
  x_m: 0.3
  y_m: 0.1
  velocity_x_mps: 1.0
  deceleration_mps2: 0.4
effects:
  gain: 1.5
  noise_sigma: 2
  exposure_ms: 10
  blur_subframes: 4
  rolling_shutter: true
expect:
  - "ball.detection_rate >= 0.97"
  - robot.orientation.perceived_rate>0.9
)";
  const Scenario s = Scenario::parse(text, "x.yaml");
  const CaseSettings& c = s.cases[0].settings;
  EXPECT_EQ(c.width_px, 320);
  ASSERT_EQ(c.robots.size(), 3u);
  EXPECT_EQ(c.robots[0].motion.kind, MotionSpec::Kind::kWalk);
  EXPECT_DOUBLE_EQ(c.robots[0].motion.speed_mps, 0.12);
  EXPECT_DOUBLE_EQ(c.robots[0].motion.direction_rad, 90 * kDeg);
  EXPECT_DOUBLE_EQ(c.robots[0].jersey_gray, 0.2);
  // 1.2 m straight ahead of the observer at (-1, 0.5) facing +y.
  EXPECT_NEAR(c.robots[1].pose.x_m, -1.0, test::kMetreTolerance);
  EXPECT_NEAR(c.robots[1].pose.y_m, 1.7, test::kMetreTolerance);
  EXPECT_EQ(c.robots[1].motion.kind, MotionSpec::Kind::kTurn);
  EXPECT_DOUBLE_EQ(c.robots[1].motion.turn_rate_radps, -30 * kDeg);
  EXPECT_EQ(c.robots[2].motion.kind, MotionSpec::Kind::kStand);
  ASSERT_TRUE(c.ball.has_value());
  EXPECT_DOUBLE_EQ(c.ball->velocity_x_mps, 1.0);
  EXPECT_DOUBLE_EQ(c.ball->deceleration_mps2, 0.4);
  EXPECT_DOUBLE_EQ(c.effects.gain, 1.5);
  EXPECT_DOUBLE_EQ(c.effects.exposure_s, 0.01);
  EXPECT_TRUE(c.effects.rolling_shutter);
  ASSERT_EQ(s.expect.size(), 2u);
  EXPECT_EQ(s.expect[0].metric, "ball.detection_rate");
  EXPECT_EQ(s.expect[0].comparison, Expectation::Comparison::kGreaterEqual);
  EXPECT_DOUBLE_EQ(s.expect[0].bound, 0.97);
  EXPECT_EQ(s.expect[1].metric, "robot.orientation.perceived_rate");
  EXPECT_EQ(s.expect[1].comparison, Expectation::Comparison::kGreater);
  EXPECT_EQ(s.expect[1].line, 40);
}

TEST(ScenarioTest, ParsesEachComparison) {
  EXPECT_EQ(parseExpectation("a <= 1", "t").comparison, Expectation::Comparison::kLessEqual);
  EXPECT_EQ(parseExpectation("a < 1", "t").comparison, Expectation::Comparison::kLess);
  EXPECT_EQ(parseExpectation("a == 1", "t").comparison, Expectation::Comparison::kEqual);
  EXPECT_EQ(parseExpectation("a>=-2.5e-1", "t").bound, -0.25);
  const Expectation e = parseExpectation("x.y >= 0.5", "t");
  EXPECT_TRUE(e.holds(0.5));
  EXPECT_FALSE(e.holds(0.49));
  EXPECT_FALSE(e.holds(std::nan("")));
  for (const char* bad : {"", ">= 0.9", "ball.rate", "ball.rate => 0.9", "ball.rate >= high",
                          "ball.rate >= 0.9 or so", "ball.rate >= nan"}) {
    EXPECT_THROW(parseExpectation(bad, "t"), Error) << bad;
  }
}

// Each kind of bad file: the message names the file, the line and the key.
TEST(ScenarioTest, UnknownKeyNamesFileLineAndKey) {
  const std::string msg = errorOf(std::string(kMinimal) + "colour: red\n");
  EXPECT_NE(msg.find("bad.yaml:12:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("colour"), std::string::npos) << msg;
  EXPECT_NE(msg.find("unknown key"), std::string::npos) << msg;

  const std::string nested = errorOf(std::string(kMinimal) + "effects:\n  noise_sigmaa: 3\n");
  EXPECT_NE(nested.find("bad.yaml:13: effects.noise_sigmaa: unknown key"), std::string::npos)
      << nested;
}

TEST(ScenarioTest, MissingRequiredKeyNamesFileLineAndKey) {
  std::string text = kMinimal;
  text.erase(text.find("  heading_deg: 90\n"), 17);
  const std::string msg = errorOf(text);
  EXPECT_NE(msg.find("bad.yaml:7: observer.heading_deg: missing required key"), std::string::npos)
      << msg;
  std::string no_camera = kMinimal;
  no_camera.erase(no_camera.find("camera: top\n"), 12);
  EXPECT_NE(errorOf(no_camera).find("camera: missing required key"), std::string::npos);
}

TEST(ScenarioTest, WrongTypeNamesFileLineAndKey) {
  std::string text = kMinimal;
  text.replace(text.find("frames: 3"), 9, "frames: many");
  const std::string msg = errorOf(text);
  EXPECT_NE(msg.find("bad.yaml:3: frames: expected an integer, got 'many'"), std::string::npos)
      << msg;
  std::string list = kMinimal;
  list.replace(list.find("x_m: -1.0"), 9, "x_m: [1, 2]");
  EXPECT_NE(errorOf(list).find("bad.yaml:7: observer.x_m: expected a number"), std::string::npos)
      << errorOf(list);
  const std::string robots = errorOf(std::string(kMinimal) + "robots: {x_m: 1}\n");
  EXPECT_NE(robots.find("bad.yaml:12: robots: expected a list"), std::string::npos) << robots;
}

TEST(ScenarioTest, ValueOutOfRangeNamesFileLineAndKey) {
  std::string text = kMinimal;
  text.replace(text.find("x_m: -1.0"), 9, "x_m: -9.0");
  const std::string msg = errorOf(text);
  EXPECT_NE(msg.find("bad.yaml:7: observer.x_m: value -9.0 is out of range"), std::string::npos)
      << msg;
  const std::string gray = errorOf(
      std::string(kMinimal) + "robots:\n  - {x_m: 0, y_m: 0, heading_deg: 0, jersey_gray: 1.5}\n");
  EXPECT_NE(gray.find("bad.yaml:13: robots[0].jersey_gray: value 1.5 is out of range"),
            std::string::npos)
      << gray;
  const std::string preset = errorOf(std::string(kMinimal).replace(
      std::string(kMinimal).find("preset: dim"), 11, "preset: disco"));
  EXPECT_NE(preset.find("bad.yaml:11: lighting.preset: 'disco' is not one of"), std::string::npos)
      << preset;
  const std::string nan = errorOf(std::string(kMinimal) + "effects: {gain: .nan}\n");
  EXPECT_NE(nan.find("effects.gain"), std::string::npos) << nan;
  const std::string glare = errorOf(std::string(kMinimal) + "effects: {defocus_px: 1.5, veiling_glare: 1.2}\n");
  EXPECT_NE(glare.find("effects.veiling_glare: value 1.2 is out of range"), std::string::npos) << glare;
  const std::string defocus = errorOf(std::string(kMinimal) + "effects: {defocus_px: -1}\n");
  EXPECT_NE(defocus.find("effects.defocus_px: value -1 is out of range"), std::string::npos) << defocus;
  const std::string head =
      errorOf(std::string(kMinimal).replace(std::string(kMinimal).find("  heading_deg: 90\n"), 17,
                                            "  heading_deg: 90\n  head: {pitch_deg: 40}\n"));
  EXPECT_NE(head.find("observer.head.pitch_deg"), std::string::npos) << head;
}

TEST(ScenarioTest, CameraErrorIsReadInDegreesAndMetresAndChecked) {
  EXPECT_FALSE(Scenario::parse(kMinimal, "x.yaml").cases[0].settings.camera_error.any());
  const Scenario s = Scenario::parse(
      std::string(kMinimal) + "camera_error: {pitch_deg: 2, roll_deg: -1, yaw_deg: 0.5, height_m: -0.01}\n",
      "x.yaml");
  const CameraErrorSpec& e = s.cases[0].settings.camera_error;
  EXPECT_TRUE(e.any());
  EXPECT_DOUBLE_EQ(e.pitch_rad, 2 * kDeg);
  EXPECT_DOUBLE_EQ(e.roll_rad, -1 * kDeg);
  EXPECT_DOUBLE_EQ(e.yaw_rad, 0.5 * kDeg);
  EXPECT_DOUBLE_EQ(e.height_m, -0.01);
  const std::string range = errorOf(std::string(kMinimal) + "camera_error: {pitch_deg: 25}\n");
  EXPECT_NE(range.find("bad.yaml:12: camera_error.pitch_deg: value 25 is out of range"), std::string::npos)
      << range;
  const std::string key = errorOf(std::string(kMinimal) + "camera_error: {tilt_deg: 1}\n");
  EXPECT_NE(key.find("camera_error.tilt_deg: unknown key"), std::string::npos) << key;
  // Sweepable like any key, the section created when the file leaves it out.
  const Scenario swept = Scenario::parse(
      std::string(kMinimal) + "sweep:\n  - path: camera_error.pitch_deg\n    values: [-2, 0, 3]\n", "x.yaml");
  ASSERT_EQ(swept.cases.size(), 3u);
  EXPECT_DOUBLE_EQ(swept.cases[0].settings.camera_error.pitch_rad, -2 * kDeg);
  EXPECT_FALSE(swept.cases[1].settings.camera_error.any());
  EXPECT_DOUBLE_EQ(swept.cases[2].settings.camera_error.pitch_rad, 3 * kDeg);
}

TEST(ScenarioTest, MalformedYamlNamesFileAndLine) {
  const std::string msg = errorOf(std::string(kMinimal) + "robots: [\n  {x_m: 1\n");
  EXPECT_NE(msg.find("bad.yaml:"), std::string::npos) << msg;
  EXPECT_NE(msg.find("malformed YAML"), std::string::npos) << msg;
  EXPECT_NE(errorOf("just a string").find("expected a scenario"), std::string::npos);
}

TEST(ScenarioTest, MissingFileIsAnError) {
  try {
    Scenario::load("/nonexistent/scenario.yaml");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scenario.yaml: cannot open"),
              std::string::npos);
  }
}

TEST(ScenarioTest, TooManyRobotsAndBothPositionFormsAreErrors) {
  std::string text = std::string(kMinimal) + "robots:\n";
  for (int i = 0; i < 10; ++i) text += "  - {x_m: 0, y_m: 0, heading_deg: 0}\n";
  EXPECT_NE(errorOf(text).find("at most 9"), std::string::npos);
  const std::string both =
      errorOf(std::string(kMinimal) + "ball: {x_m: 0, y_m: 0, distance_m: 1}\n");
  EXPECT_NE(both.find("not both"), std::string::npos) << both;
}

const char* kSweep = R"(sweep:
  - path: robots[0].heading_deg
    values: [0, 22.5, 45]
  - path: lighting.scale
    values: [0.5, 2]
robots:
  - distance_m: 1.2
    bearing_deg: 0
    heading_deg: 180
)";

TEST(ScenarioTest, SweepExpandsToTheCartesianProductFirstAxisSlowest) {
  const Scenario s = Scenario::parse(std::string(kMinimal) + kSweep, "sweep.yaml");
  ASSERT_EQ(s.sweep.size(), 2u);
  ASSERT_EQ(s.cases.size(), 6u);
  const double headings[] = {0, 0, 22.5, 22.5, 45, 45};
  const double scales[] = {0.5, 2, 0.5, 2, 0.5, 2};
  for (int k = 0; k < 6; ++k) {
    const ScenarioCase& c = s.cases[static_cast<std::size_t>(k)];
    EXPECT_EQ(c.index, k);
    EXPECT_NEAR(c.settings.robots[0].pose.heading_rad, headings[k] * kDeg, 1e-12);
    EXPECT_DOUBLE_EQ(c.settings.lighting.scale, scales[k]);
    ASSERT_EQ(c.values.size(), 2u);
    EXPECT_EQ(c.values[0].path, "robots[0].heading_deg");
    EXPECT_EQ(std::stod(c.values[0].value), headings[k]);
    EXPECT_EQ(c.values[1].path, "lighting.scale");
    EXPECT_EQ(std::stod(c.values[1].value), scales[k]);
  }
  EXPECT_EQ(s.cases[4].name(), "case_004");
}

TEST(ScenarioTest, SweepCanSetKeysTheFileLeavesToDefaultsAndRelativeDistance) {
  const std::string text = std::string(kMinimal) + R"(robots:
  - {distance_m: 1.0, bearing_deg: 0, heading_deg: 0}
sweep:
  - path: robots[0].distance_m
    values: [0.5, 2.0]
  - path: effects.noise_sigma
    values: [0, 3]
)";
  const Scenario s = Scenario::parse(text, "x.yaml");
  ASSERT_EQ(s.cases.size(), 4u);
  // The observer at (-1, 0.5) faces +y.
  EXPECT_NEAR(s.cases[0].settings.robots[0].pose.y_m, 1.0, test::kMetreTolerance);
  EXPECT_NEAR(s.cases[3].settings.robots[0].pose.y_m, 2.5, test::kMetreTolerance);
  EXPECT_DOUBLE_EQ(s.cases[1].settings.effects.noise_sigma, 3);
  EXPECT_DOUBLE_EQ(s.cases[2].settings.effects.noise_sigma, 0);
}

TEST(ScenarioTest, BadSweepsNameTheLineAndPath) {
  const std::string out_of_range = errorOf(std::string(kMinimal) +
                                           "sweep:\n  - path: lighting.scale\n    values: [1, 2]\n"
                                           "  - path: effects.gain\n    values: [1, 100]\n");
  EXPECT_NE(out_of_range.find("effects.gain: value 100 is out of range"), std::string::npos)
      << out_of_range;
  EXPECT_NE(out_of_range.find(":16:"), std::string::npos) << out_of_range;
  EXPECT_NE(out_of_range.find("effects.gain = 100"), std::string::npos) << out_of_range;

  const std::string no_robot =
      errorOf(std::string(kMinimal) + "sweep:\n  - path: robots[3].heading_deg\n    values: [1]\n");
  EXPECT_NE(no_robot.find("bad.yaml:13: sweep[0]: 'robots[3].heading_deg'"), std::string::npos)
      << no_robot;
  const std::string unknown =
      errorOf(std::string(kMinimal) + "sweep:\n  - path: lighting.brightness\n    values: [1]\n");
  EXPECT_NE(unknown.find("bad.yaml:14: lighting.brightness: unknown key"), std::string::npos)
      << unknown;
  const std::string malformed =
      errorOf(std::string(kMinimal) + "sweep:\n  - path: robots[x].heading_deg\n    values: [1]\n");
  EXPECT_NE(malformed.find("bad.yaml:13: sweep[0].path: malformed setting path"), std::string::npos)
      << malformed;
  const std::string empty =
      errorOf(std::string(kMinimal) + "sweep:\n  - path: lighting.scale\n    values: []\n");
  EXPECT_NE(empty.find("bad.yaml:14: sweep[0].values: expected a non-empty list"),
            std::string::npos)
      << empty;
  const std::string extra = errorOf(
      std::string(kMinimal) + "sweep:\n  - path: lighting.scale\n    values: [1]\n    step: 2\n");
  EXPECT_NE(extra.find("bad.yaml:15: sweep[0].step: unknown key"), std::string::npos) << extra;
}

TEST(ScenarioTest, EveryShippedScenarioLoads) {
  int count = 0;
  for (const auto& path : test::shippedScenarioFiles()) {
    const Scenario s = Scenario::load(path.string());
    EXPECT_FALSE(s.cases.empty()) << path;
    ++count;
  }
  EXPECT_GE(count, 4);
}

TEST(ScenarioTest, StaticOrientationSceneIsThePapers) {
  const Scenario s = Scenario::load(test::sourceDir() + "/scenes/orientation_static.yaml");
  // 16 headings (the slower axis) under each of the 6 lighting presets.
  ASSERT_EQ(s.cases.size(), 16u * 6u);
  for (const ScenarioCase& c : s.cases) {
    const RobotSpec& r = c.settings.robots.at(0);
    const FieldPose& o = c.settings.observer.pose;
    EXPECT_NEAR(std::hypot(r.pose.x_m - o.x_m, r.pose.y_m - o.y_m), 1.2, test::kMetreTolerance);
    EXPECT_NEAR(c.settings.orientation_tolerance_rad, 11.25 * kDeg, 1e-12);
    EXPECT_NEAR(r.pose.heading_rad, 22.5 * kDeg * (c.index / 6), 1e-12);
  }
}

TEST(ScenarioTest, DynamicOrientationSceneIsThePapers) {
  const Scenario s = Scenario::load(test::sourceDir() + "/scenes/orientation_dynamic.yaml");
  ASSERT_EQ(s.cases.size(), 8u);
  for (const ScenarioCase& c : s.cases) {
    const RobotSpec& r = c.settings.robots.at(0);
    EXPECT_EQ(r.motion.kind, MotionSpec::Kind::kWalk);
    EXPECT_DOUBLE_EQ(r.motion.speed_mps, 0.12);
    EXPECT_NEAR(c.settings.orientation_tolerance_rad, 22.5 * kDeg, 1e-12);
  }
}

}  // namespace
}  // namespace colorfree::sim
