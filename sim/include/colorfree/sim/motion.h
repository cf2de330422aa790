#pragma once

#include <Eigen/Geometry>

#include "colorfree/sim/scenario.h"

namespace colorfree::sim {

/// Duration of one gait cycle (two steps) of the procedural walk, seconds.
inline constexpr double kGaitCycleS = 0.5;
/// Turning in place swings the legs as a walk at this speed per rad/s of turn rate.
inline constexpr double kTurnStepMetresPerRad = 0.12;

/// Where a robot is and how its legs move at one instant; a pure function of time.
struct RobotMotionState {
  FieldPose pose;
  double gait_phase = 0;          ///< [0, 1) of the gait cycle
  double gait_speed_mps = 0;      ///< the leg swing's speed for walkPosture (0 = standing)
  double speed_mps = 0;           ///< ground speed
  double walk_direction_rad = 0;  ///< field direction of travel
  double turn_rate_radps = 0;
};

/// A robot's state at time `t_s` after the scenario starts: walking moves straight at its speed,
/// turning in place rotates at its rate.
RobotMotionState robotMotionAt(const FieldPose& start, const MotionSpec& motion, double t_s);

/// The observer's head angles at `t_s` (sinusoidal sweeps around the set angles).
struct HeadAngles {
  double yaw_rad = 0;
  double pitch_rad = 0;
};
HeadAngles headAt(const HeadSpec& head, double t_s);

/// The ball at `t_s`: rolling on the ground, slowing at its deceleration until it stops; its
/// orientation turns with the distance rolled (no slip).
struct BallMotionState {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  ///< centre
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};
BallMotionState ballAt(const BallSpec& ball, double radius_m, const Eigen::Quaterniond& start,
                       double t_s);

/// The light level at `t_s`: the scale times the flicker (a sinusoid).
double lightingScaleAt(const LightingSpec& lighting, double t_s);

}  // namespace colorfree::sim
