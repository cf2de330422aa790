#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "colorfree/sim/world.h"

namespace colorfree::sim {

/// How a robot (or the observer) moves. Walking direction is relative to the robot's heading
/// (0 forward, 90° a side step to the left); turning is in place at a constant rate.
struct MotionSpec {
  enum class Kind { kStand, kWalk, kTurn };
  Kind kind = Kind::kStand;
  double speed_mps = 0;        ///< walk: speed over the ground
  double direction_rad = 0;    ///< walk: direction of travel relative to the heading
  double turn_rate_radps = 0;  ///< turn: positive turns left
  double phase = 0;            ///< gait phase at time 0, in [0, 1)
};
std::string motionKindName(MotionSpec::Kind kind);

/// The observer's head: a fixed angle plus an optional sinusoidal sweep per joint.
struct HeadSpec {
  double yaw_rad = 0;
  double pitch_rad = 0;  ///< positive looks down, as the NAO's HeadPitch
  double yaw_amplitude_rad = 0;
  double yaw_period_s = 2;
  double pitch_amplitude_rad = 0;
  double pitch_period_s = 2;
};

struct ObserverSpec {
  FieldPose pose;
  double jersey_gray = 0.5;
  HeadSpec head;
  MotionSpec motion;
};

struct RobotSpec {
  FieldPose pose;  ///< at time 0
  double jersey_gray = 0.5;
  MotionSpec motion;
};

/// The ball at time 0 and how it rolls: straight, slowing at a constant deceleration until it
/// stops.
struct BallSpec {
  double x_m = 0;
  double y_m = 0;
  double velocity_x_mps = 0;
  double velocity_y_mps = 0;
  double deceleration_mps2 = 0.5;
};

struct LightingSpec {
  LightingPreset preset = LightingPreset::kNormal;
  double scale = 1.0;               ///< factor on every light of the preset
  double flicker_amplitude = 0;     ///< sinusoidal flicker, relative: 0.2 = ±20 % over time
  double flicker_frequency_hz = 0;  ///< (the flicker preset adds world.h's flickerScale too)
};

/// Camera effects applied after rendering (camera_effects.h applies them).
struct EffectsSpec {
  double gain = 1.0;              ///< exposure/gain: factor on the rendered luma, clipped at 255
  double noise_sigma = 0;         ///< Gaussian read noise, grey levels
  double shot_noise = 0;          ///< shot noise: variance = shot_noise × luma (grey levels)
  double exposure_s = 0;          ///< exposure time, for motion blur
  int blur_subframes = 1;         ///< renders averaged across the exposure; 1 = no blur
  bool rolling_shutter = false;   ///< NAO V6: rows exposed one after the other
  double readout_s = 0.03;        ///< rolling shutter: time from the first to the last row
  int rolling_shutter_bands = 8;  ///< rolling shutter: renders across the readout at least
  double defocus_px = 0;          ///< lens blur: σ of a Gaussian point spread, pixels; 0 = sharp
  double veiling_glare = 0;       ///< share of the light the lens scatters evenly over the frame
};

/// An error in the camera pose the perception is given (what the robot believes its camera's pose
/// is, from joint encoders, the torso's IMU and its calibration), against the pose the frame is
/// rendered and scored with. Zero: the perception gets the true camera.
struct CameraErrorSpec {
  double pitch_rad = 0;  ///< the believed camera looks this much further down (about its own left axis)
  double roll_rad = 0;   ///< ... is turned this much about its viewing axis (the camera file's roll_deg sense)
  double yaw_rad = 0;    ///< ... looks this much further left (about the robot's vertical)
  double height_m = 0;   ///< ... sits this much higher
  bool any() const { return pitch_rad != 0 || roll_rad != 0 || yaw_rad != 0 || height_m != 0; }
};

/// One expectation, e.g. "ball.detection_rate >= 0.97". The metric names are checked by the
/// scorer, not here.
struct Expectation {
  enum class Comparison { kGreaterEqual, kLessEqual, kGreater, kLess, kEqual };
  std::string metric;
  Comparison comparison = Comparison::kGreaterEqual;
  double bound = 0;
  std::string text;  ///< as written
  int line = 0;      ///< 1-based line in the scenario file
  bool holds(double value) const;
};
std::string comparisonSymbol(Expectation::Comparison comparison);
/// Parses "metric OP bound"; throws colorfree::Error naming `origin` when malformed.
Expectation parseExpectation(const std::string& text, const std::string& origin);

/// Everything one case renders: the scenario with its sweep values applied.
struct CaseSettings {
  NaoCamera camera = NaoCamera::kTop;
  int width_px = 640;
  int height_px = 480;
  ObserverSpec observer;
  std::vector<RobotSpec> robots;
  std::optional<BallSpec> ball;
  LightingSpec lighting;
  EffectsSpec effects;
  CameraErrorSpec camera_error;
  double camera_horizontal_fov_deg = 60.9;  ///< NAO V4/V5 (V6: 56.3)
  bool shadows = true;
  int multisamples = 4;
  int frames = 1;
  double frame_rate_hz = 30;
  std::uint64_t seed = 1;
  double ball_radius_m = 0.05;                ///< from the field dimensions file
  double orientation_tolerance_rad = 0.3927;  ///< scoring: 22.5° unless the scenario says
};

/// One swept setting: the path it addresses and the values it takes.
struct SweepAxis {
  std::string path;                 ///< e.g. "robots[0].heading_deg"
  std::vector<std::string> values;  ///< as written (scalars)
  int line = 0;
};

/// A value a case took for a swept setting.
struct SweepValue {
  std::string path;
  std::string value;  ///< as written
};

struct ScenarioCase {
  int index = 0;
  std::vector<SweepValue> values;  ///< one per sweep axis, in the file's order
  CaseSettings settings;
  /// "case_003"
  std::string name() const;
};

/// A scenario file, parsed strictly and expanded into its cases (the cartesian product of the
/// sweep, the first axis varying slowest). Format: docs/scenarios.md.
struct Scenario {
  std::string name;
  std::string path;
  std::vector<SweepAxis> sweep;
  std::vector<ScenarioCase> cases;
  std::vector<Expectation> expect;

  /// Throws colorfree::Error naming the file, the line and the key when anything is wrong.
  static Scenario load(const std::string& path);
  /// Parses scenario text; `origin` names it in errors.
  static Scenario parse(const std::string& text, const std::string& origin);
};

/// Largest number of cases a sweep may expand to.
inline constexpr int kMaxScenarioCases = 10000;
/// Other robots at most (10 NAOs with the observer).
inline constexpr int kMaxRobots = 9;

}  // namespace colorfree::sim
