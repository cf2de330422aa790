#include "colorfree/perception/pipeline.h"

#include <gtest/gtest.h>

#include "colorfree/perception/error.h"
#include "colorfree/perception/noise.h"
#include "synthetic_field.h"

namespace colorfree {
namespace {

TEST(Pipeline, FillsEveryStageInOrder) {
  const CameraModel cam = test::testCamera(22);
  const GrayImage image = test::renderScene(cam, test::sceneFromField(FieldDimensions{}, {-2.0, 0, 0}));
  const Pipeline pipeline(PipelineConfig::loadDefault());
  Frame frame(image.view(), cam);
  PipelineStats stats;
  pipeline.process(frame, &stats);
  ASSERT_TRUE(frame.field_boundary && frame.body_contour && frame.ignore_mask);
  ASSERT_TRUE(frame.contrast_regions && frame.field_lines);
  EXPECT_FALSE(frame.field_lines->features.lines.empty());
  EXPECT_GT(frame.contrast_regions->markedCount(), 0);
  EXPECT_TRUE(frame.robot_proposals && frame.robot_percepts);  // the robot stages (issue 7)
  EXPECT_TRUE(frame.ball_proposals && frame.ball_percepts);    // the ball stages (issue 6)
  // The noise both proposers follow, estimated once over the looked-at area.
  ASSERT_TRUE(frame.pixel_noise_gray);
  EXPECT_EQ(*frame.pixel_noise_gray, pixelNoiseGray(image.view(), *frame.ignore_mask));
  for (int i = 0; i < kStageCount; ++i) {
    const Stage s = static_cast<Stage>(i);
    ASSERT_TRUE(stats.timing(s)) << stageName(s);
    EXPECT_EQ(stats.timing(s)->frames, 1);
    EXPECT_GE(stats.timing(s)->max_ms, stats.timing(s)->meanMs());
  }
  pipeline.process(frame, &stats);
  EXPECT_EQ(stats.timing(Stage::kFieldLines)->frames, 2);
  EXPECT_EQ(stats.table().find("absent"), std::string::npos);
}

TEST(Pipeline, StagesSwitchedOffAreAbsentNotZero) {
  const CameraModel cam = test::testCamera(22);
  const GrayImage image = test::renderScene(cam, test::sceneFromField(FieldDimensions{}, {-2.0, 0, 0}));
  PipelineConfig config = PipelineConfig::loadDefault();
  config.robot_stages = false;
  config.ball_stages = false;
  const Pipeline pipeline(config);
  Frame frame(image.view(), cam);
  PipelineStats stats;
  pipeline.process(frame, &stats);
  EXPECT_TRUE(frame.field_lines);
  EXPECT_FALSE(frame.robot_proposals || frame.robot_percepts || frame.ball_proposals || frame.ball_percepts);
  for (Stage s : {Stage::kRobotProposals, Stage::kRobotDetector, Stage::kRobotOrientation,
                  Stage::kBallProposals, Stage::kBallDetector}) {
    EXPECT_FALSE(stats.timing(s)) << stageName(s);
  }
  const std::string table = stats.table();
  EXPECT_NE(table.find("ball detector"), std::string::npos);
  EXPECT_NE(table.find("absent"), std::string::npos);
}

TEST(PipelineStats, MeanAndMax) {
  PipelineStats stats;
  stats.add(Stage::kHighContrast, 1.0);
  stats.add(Stage::kHighContrast, 3.0);
  EXPECT_DOUBLE_EQ(stats.timing(Stage::kHighContrast)->meanMs(), 2.0);
  EXPECT_DOUBLE_EQ(stats.timing(Stage::kHighContrast)->max_ms, 3.0);
  EXPECT_FALSE(stats.timing(Stage::kFieldLines));
}

TEST(Pipeline, ImageThatDoesNotFitTheCameraIsAnError) {
  const Pipeline pipeline(PipelineConfig{});
  const GrayImage small(320, 240, 80);
  Frame frame(small.view(), test::testCamera(22));
  EXPECT_THROW(pipeline.process(frame), Error);
  Frame empty(GrayView{}, test::testCamera(22));
  EXPECT_THROW(pipeline.process(empty), Error);
}

TEST(Pipeline, BlackAndWhiteFramesGiveAnEmptyResult) {
  const Pipeline pipeline(PipelineConfig{});
  for (std::uint8_t v : {std::uint8_t{0}, std::uint8_t{255}}) {
    const GrayImage flat(640, 480, v);
    Frame frame(flat.view(), test::testCamera(22));
    pipeline.process(frame);
    EXPECT_EQ(frame.contrast_regions->markedCount(), 0);
    EXPECT_TRUE(frame.field_lines->spots.empty());
    EXPECT_TRUE(frame.field_lines->features.lines.empty());
  }
}

}  // namespace
}  // namespace colorfree
