#include "colorfree/sim/motion.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace colorfree::sim {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

double wrapAngle(double a) {
  a = std::remainder(a, kTwoPi);
  return a;
}

double wrapPhase(double p) {
  p -= std::floor(p);
  return p >= 1 ? 0 : p;
}

}  // namespace

RobotMotionState robotMotionAt(const FieldPose& start, const MotionSpec& motion, double t_s) {
  RobotMotionState s;
  s.pose = start;
  s.pose.heading_rad = wrapAngle(start.heading_rad);
  switch (motion.kind) {
    case MotionSpec::Kind::kStand:
      break;
    case MotionSpec::Kind::kWalk: {
      const double direction = start.heading_rad + motion.direction_rad;
      s.pose.x_m = start.x_m + motion.speed_mps * t_s * std::cos(direction);
      s.pose.y_m = start.y_m + motion.speed_mps * t_s * std::sin(direction);
      s.speed_mps = motion.speed_mps;
      s.walk_direction_rad = wrapAngle(direction);
      s.gait_speed_mps = motion.speed_mps;
      s.gait_phase = wrapPhase(motion.phase + t_s / kGaitCycleS);
      break;
    }
    case MotionSpec::Kind::kTurn:
      s.pose.heading_rad = wrapAngle(start.heading_rad + motion.turn_rate_radps * t_s);
      s.turn_rate_radps = motion.turn_rate_radps;
      s.walk_direction_rad = s.pose.heading_rad;
      s.gait_speed_mps = std::abs(motion.turn_rate_radps) * kTurnStepMetresPerRad;
      s.gait_phase = wrapPhase(motion.phase + t_s / kGaitCycleS);
      break;
  }
  if (motion.kind == MotionSpec::Kind::kStand) s.walk_direction_rad = s.pose.heading_rad;
  return s;
}

HeadAngles headAt(const HeadSpec& head, double t_s) {
  HeadAngles a;
  a.yaw_rad = head.yaw_rad + head.yaw_amplitude_rad * std::sin(kTwoPi * t_s / head.yaw_period_s);
  a.pitch_rad =
      head.pitch_rad + head.pitch_amplitude_rad * std::sin(kTwoPi * t_s / head.pitch_period_s);
  return a;
}

BallMotionState ballAt(const BallSpec& ball, double radius_m, const Eigen::Quaterniond& start,
                       double t_s) {
  BallMotionState s;
  const Eigen::Vector2d v0(ball.velocity_x_mps, ball.velocity_y_mps);
  const double speed0 = v0.norm();
  double distance = 0;
  double speed = speed0;
  if (speed0 > 0) {
    const double a = ball.deceleration_mps2;
    const double t_stop = a > 0 ? speed0 / a : std::numeric_limits<double>::infinity();
    const double t = std::clamp(t_s, 0.0, t_stop);
    distance = speed0 * t - 0.5 * a * t * t;
    speed = t_s >= t_stop ? 0 : speed0 - a * t;
  }
  const Eigen::Vector2d dir = speed0 > 0 ? Eigen::Vector2d(v0 / speed0) : Eigen::Vector2d::Zero();
  s.position_m =
      Eigen::Vector3d(ball.x_m + dir.x() * distance, ball.y_m + dir.y() * distance, radius_m);
  s.velocity_mps = Eigen::Vector3d(dir.x() * speed, dir.y() * speed, 0);
  s.orientation = start;
  if (distance > 0) {
    // Rolling without slip about the horizontal axis perpendicular to the travel: z × direction.
    const Eigen::Vector3d axis =
        Eigen::Vector3d::UnitZ().cross(Eigen::Vector3d(dir.x(), dir.y(), 0));
    s.orientation =
        Eigen::Quaterniond(Eigen::AngleAxisd(distance / radius_m, axis.normalized())) * start;
    s.orientation.normalize();
  }
  return s;
}

double lightingScaleAt(const LightingSpec& lighting, double t_s) {
  const double flicker =
      1.0 + lighting.flicker_amplitude * std::sin(kTwoPi * lighting.flicker_frequency_hz * t_s);
  return std::max(0.0, lighting.scale * flicker);
}

}  // namespace colorfree::sim
