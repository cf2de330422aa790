#include "run_perception.h"

#include "pose_fit_adapter.h"

namespace colorfree::app {

std::string stageKey(Stage stage) {
  switch (stage) {
    case Stage::kIgnoreRegions:
      return "ignore_regions";
    case Stage::kHighContrast:
      return "high_contrast";
    case Stage::kFieldLines:
      return "field_features";
    case Stage::kRobotProposals:
      return "robot_proposals";
    case Stage::kRobotDetector:
      return "robot_detector";
    case Stage::kRobotOrientation:
      return "robot_orientation";
    case Stage::kBallProposals:
      return "ball_proposals";
    case Stage::kBallDetector:
      return "ball_detector";
  }
  return "unknown";
}

PerceptionRunner::PerceptionRunner() : pipeline_(PipelineConfig::loadDefault()) {}

FramePercepts PerceptionRunner::process(const GrayImage& image, const CameraModel& camera,
                                        const FieldPose& pose_guess) {
  Frame frame(image.view(), camera);
  PipelineStats this_frame;
  pipeline_.process(frame, &this_frame);
  FramePercepts p;
  for (int i = 0; i < kStageCount; ++i) {
    const Stage stage = static_cast<Stage>(i);
    if (const auto& t = this_frame.timing(stage)) {
      p.stage_times_ms[stageKey(stage)] = t->total_ms;
      stats_.add(stage, t->total_ms);
    }
  }
  p.ball_proposals = frame.ball_proposals;
  p.balls = frame.ball_percepts;
  p.robot_proposals = frame.robot_proposals;
  p.robots = frame.robot_percepts;
  p.orientation_stage = this_frame.timing(Stage::kRobotOrientation).has_value();
  if (frame.field_lines) {
    p.field_features = frame.field_lines->features;
    p.pose_fit_stage = true;
    if (const auto fit = fitPose(frame.field_lines->features,
                                 {pose_guess.x_m, pose_guess.y_m, pose_guess.heading_rad})) {
      p.pose_in_field = FieldPose{fit->x_m, fit->y_m, fit->heading_rad};
    }
  }
  return p;
}

}  // namespace colorfree::app
