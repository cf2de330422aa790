#include "colorfree/sim/motion.h"

#include <gtest/gtest.h>

#include <numbers>

#include "test_support.h"

namespace colorfree::sim {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(MotionTest, WalkMovesAlongHeadingPlusDirectionAtItsSpeed) {
  MotionSpec walk;
  walk.kind = MotionSpec::Kind::kWalk;
  walk.speed_mps = 0.12;
  walk.direction_rad = kPi / 2;  // side step to the left
  const FieldPose start{1.0, 2.0, kPi / 2};
  const RobotMotionState s = robotMotionAt(start, walk, 2.5);
  // Facing +y, stepping left means travelling towards -x.
  EXPECT_NEAR(s.pose.x_m, 1.0 - 0.3, test::kMetreTolerance);
  EXPECT_NEAR(s.pose.y_m, 2.0, test::kMetreTolerance);
  EXPECT_NEAR(s.pose.heading_rad, kPi / 2, 1e-12);
  EXPECT_DOUBLE_EQ(s.speed_mps, 0.12);
  EXPECT_NEAR(std::abs(s.walk_direction_rad), kPi, 1e-12);
  EXPECT_DOUBLE_EQ(s.gait_speed_mps, 0.12);
}

TEST(MotionTest, GaitPhaseAdvancesOneCyclePerCycleTime) {
  MotionSpec walk;
  walk.kind = MotionSpec::Kind::kWalk;
  walk.speed_mps = 0.1;
  walk.phase = 0.25;
  EXPECT_NEAR(robotMotionAt({}, walk, 0).gait_phase, 0.25, 1e-12);
  EXPECT_NEAR(robotMotionAt({}, walk, kGaitCycleS / 2).gait_phase, 0.75, 1e-12);
  EXPECT_NEAR(robotMotionAt({}, walk, kGaitCycleS).gait_phase, 0.25, 1e-12);
  EXPECT_LT(robotMotionAt({}, walk, 123.456).gait_phase, 1.0);
}

TEST(MotionTest, TurnInPlaceKeepsPositionAndWrapsHeading) {
  MotionSpec turn;
  turn.kind = MotionSpec::Kind::kTurn;
  turn.turn_rate_radps = kPi / 4;
  const RobotMotionState s = robotMotionAt({0.5, -0.5, 0}, turn, 6.0);  // 270°
  EXPECT_DOUBLE_EQ(s.pose.x_m, 0.5);
  EXPECT_DOUBLE_EQ(s.pose.y_m, -0.5);
  EXPECT_NEAR(s.pose.heading_rad, -kPi / 2, 1e-12);
  EXPECT_DOUBLE_EQ(s.speed_mps, 0);
  EXPECT_GT(s.gait_speed_mps, 0);
}

TEST(MotionTest, StandingStaysPut) {
  const RobotMotionState s = robotMotionAt({0.5, -0.5, 1.0}, MotionSpec{}, 10.0);
  EXPECT_DOUBLE_EQ(s.pose.x_m, 0.5);
  EXPECT_DOUBLE_EQ(s.pose.heading_rad, 1.0);
  EXPECT_DOUBLE_EQ(s.gait_speed_mps, 0);
}

TEST(MotionTest, BallDeceleratesStopsAndRollsWithoutSlip) {
  BallSpec ball;
  ball.x_m = 1;
  ball.y_m = 0;
  ball.velocity_x_mps = 0;
  ball.velocity_y_mps = 1.0;
  ball.deceleration_mps2 = 0.5;
  const double r = 0.05;
  const Eigen::Quaterniond q0 = Eigen::Quaterniond::Identity();
  const BallMotionState mid = ballAt(ball, r, q0, 1.0);
  EXPECT_NEAR(mid.position_m.y(), 1.0 - 0.25, test::kMetreTolerance);
  EXPECT_NEAR(mid.position_m.x(), 1.0, test::kMetreTolerance);
  EXPECT_NEAR(mid.position_m.z(), r, test::kMetreTolerance);
  EXPECT_NEAR(mid.velocity_mps.y(), 0.5, test::kMetreTolerance);
  // It stops after 2 s, 1 m on, and stays.
  for (double t : {2.0, 5.0}) {
    const BallMotionState end = ballAt(ball, r, q0, t);
    EXPECT_NEAR(end.position_m.y(), 1.0, test::kMetreTolerance);
    EXPECT_EQ(end.velocity_mps.norm(), 0.0);
  }
  // Rolled 0.75 m: the ball turned 0.75 / r about -x (z × +y = -x), so its top moved towards +y.
  const Eigen::Vector3d top = mid.orientation * Eigen::Vector3d::UnitZ();
  const double angle = 0.75 / r;
  EXPECT_NEAR(top.y(), std::sin(angle), 1e-9);
  EXPECT_NEAR(top.z(), std::cos(angle), 1e-9);
  const BallMotionState still = ballAt(BallSpec{}, r, q0, 3.0);
  EXPECT_TRUE(still.orientation.isApprox(q0));
}

TEST(MotionTest, HeadSweepsSinusoidally) {
  HeadSpec head;
  head.yaw_rad = 0.1;
  head.yaw_amplitude_rad = 0.5;
  head.yaw_period_s = 4;
  head.pitch_rad = 0.2;
  EXPECT_NEAR(headAt(head, 0).yaw_rad, 0.1, 1e-12);
  EXPECT_NEAR(headAt(head, 1).yaw_rad, 0.6, 1e-12);
  EXPECT_NEAR(headAt(head, 3).yaw_rad, -0.4, 1e-12);
  EXPECT_NEAR(headAt(head, 3).pitch_rad, 0.2, 1e-12);
}

TEST(MotionTest, FlickerModulatesTheScale) {
  LightingSpec light;
  light.scale = 2;
  light.flicker_amplitude = 0.25;
  light.flicker_frequency_hz = 1;
  EXPECT_NEAR(lightingScaleAt(light, 0), 2, 1e-12);
  EXPECT_NEAR(lightingScaleAt(light, 0.25), 2.5, 1e-12);
  EXPECT_NEAR(lightingScaleAt(light, 0.75), 1.5, 1e-12);
}

}  // namespace
}  // namespace colorfree::sim
