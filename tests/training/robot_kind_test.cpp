#include "colorfree/training/robot_kind.h"

#include <gtest/gtest.h>

#include <set>

#include "colorfree/groundtruth/scoring_params.h"
#include "colorfree/perception/pipeline.h"
#include "drawn_robots.h"
#include "synthetic_field.h"

using namespace colorfree;
using namespace colorfree::training;

namespace {

RobotInImage robotAt(int index, const Eigen::Vector2d& ground_px, bool should_detect) {
  RobotInImage r;
  r.index = index;
  r.in_view = true;
  r.ground_px = ground_px;
  r.visible_fraction = should_detect ? 1.0 : 0.1;
  r.should_detect = should_detect;
  return r;
}

std::vector<int> labels(const std::vector<Candidate>& candidates) {
  std::vector<int> out;
  for (const Candidate& c : candidates) out.push_back(c.label);
  return out;
}

}  // namespace

// RobotFeetNet's truth samples: the proposer-shaped box about a demanded robot's feet moved by 0,
// -0.15, +0.15, -0.3 and +0.3 of its height is right (0), or the robot's feet are lower (1: the box
// stands too high) or higher (2).
TEST(RobotKind, FeetNetSamplesAreLabelledByWhereTheRobotsFeetAre) {
  const CameraModel cam = test::testCamera(14);
  const GrayImage image(640, 480);
  FrameTruth truth;
  truth.robots = {robotAt(0, {320, 330}, true), robotAt(1, {80, 300}, false)};
  const RobotKind kind(RobotNetChoice::kFeetNet, PipelineConfig::loadDefault(),
                       ScoringParams::loadDefault());
  EXPECT_EQ(kind.name(), "robot_feet");
  EXPECT_EQ(kind.netStems(), std::vector<std::string>{"robot_feet_net"});
  ASSERT_EQ(kind.classNames().size(), 3u);
  const auto samples = kind.truthSamples(image, cam, truth);
  EXPECT_EQ(labels(samples), (std::vector<int>{0, 1, 2, 1, 2}));
  // Each box is as tall as a robot standing at its own feet row: higher up, smaller.
  ASSERT_EQ(samples.size(), 5u);
  EXPECT_GT(samples[0].box.height_px, samples[1].box.height_px);
  EXPECT_LT(samples[0].box.height_px, samples[2].box.height_px);
  EXPECT_NE(samples[0].truth.find("feet_off=0.000"), std::string::npos);

  // A robot too hidden to demand gives none; offsets between the rules' bounds are left out.
  truth.robots[0].should_detect = false;
  EXPECT_TRUE(kind.truthSamples(image, cam, truth).empty());
  truth.robots[0].should_detect = true;
  RobotLabelRules rules;
  rules.feet_off_min_fraction = 0.2;
  const RobotKind strict(RobotNetChoice::kFeetNet, PipelineConfig::loadDefault(),
                         ScoringParams::loadDefault(), rules);
  EXPECT_EQ(labels(strict.truthSamples(image, cam, truth)), (std::vector<int>{0, 1, 2}));
}

// RobotBehindNet's kind is RobotNet's but for the held-back candidates, which it takes too: a near
// robot, one behind it and that one's hand beside the near robot's box (the proposer holds the
// hand's box back behind the robot behind: RobotProposer.HandOfARobotBehindANearerOneIsHeldBack-
// BehindIt). Without robots in the truth every box is "none".
TEST(RobotKind, BehindNetLearnsFromTheHeldBackCandidatesToo) {
  const CameraModel cam = testCamera();
  GrayImage img = carpet(12);
  const Eigen::Vector2d b_feet = drawRobot(img, cam, {2.0, -0.05});
  drawRobot(img, cam, {0.9, 0.15});
  const int hand_x = static_cast<int>(b_feet.x()) + 44;
  const int hand_y = static_cast<int>(b_feet.y() - 0.22 * robotSizePx(cam, b_feet).h);
  cv::rectangle(wrap(img), cv::Point(hand_x - 9, hand_y - 70), cv::Point(hand_x + 9, hand_y - 1),
                cv::Scalar(205), cv::FILLED);
  const FrameTruth truth;
  const RobotKind robot(RobotNetChoice::kRobotNet, PipelineConfig::loadDefault(),
                        ScoringParams::loadDefault());
  const RobotKind behind(RobotNetChoice::kBehindNet, PipelineConfig::loadDefault(),
                         ScoringParams::loadDefault());
  EXPECT_EQ(behind.name(), "robot_behind");
  EXPECT_EQ(behind.netStems(), std::vector<std::string>{"robot_behind_net"});
  EXPECT_EQ(behind.classNames(), robot.classNames());
  const auto of_robot = robot.proposals(img, cam, truth);
  const auto of_behind = behind.proposals(img, cam, truth);
  std::set<std::string> keys;
  for (const Candidate& c : of_behind) {
    keys.insert(c.key);
    EXPECT_EQ(c.label, 0) << c.key;
  }
  for (const Candidate& c : of_robot) EXPECT_TRUE(keys.count(c.key)) << c.key;
  EXPECT_GT(of_behind.size(), of_robot.size());
}
