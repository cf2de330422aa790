#include "run_perception.h"

#include <cmath>
#include <numbers>


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

namespace {

// What each ball net said about the proposals that reached it, for the CNN accuracy table (the
// scorer matches each sample to the truth).
void addBallClassifierSamples(const Frame& frame, FramePercepts* out) {
  if (!frame.ball_decisions || !frame.ball_proposals) return;
  for (const BallDecision& d : *frame.ball_decisions) {
    ClassifierSample s;
    s.classifier = "BoostBallNet";
    s.object = ClassifierSample::Object::kBall;
    s.centre_px = (*frame.ball_proposals)[d.proposal].centre_px;
    s.predicted_positive = d.boost_confidence >= 0.5f;
    out->classifier_samples.push_back(s);
    if (!d.passed_boost) continue;
    s.classifier = "BallNet";
    s.predicted_positive = d.ball_confidence >= 0.5f;
    out->classifier_samples.push_back(s);
    if (d.smeared_confidence < 0) continue;  // not smeared: SmearedBallNet did not see it
    s.classifier = "SmearedBallNet";
    s.predicted_positive = d.smeared_confidence >= 0.5f;
    out->classifier_samples.push_back(s);
  }
}

// RobotNet's decision on every robot proposal.
void addRobotClassifierSamples(const Frame& frame, FramePercepts* out) {
  if (!frame.robot_net_confidences || !frame.robot_proposals) return;
  for (std::size_t i = 0; i < frame.robot_proposals->size(); ++i) {
    ClassifierSample s;
    s.classifier = "RobotNet";
    s.object = ClassifierSample::Object::kRobot;
    s.box = (*frame.robot_proposals)[i].box;
    s.feet_px = (*frame.robot_proposals)[i].feet_px;
    s.predicted_positive = (*frame.robot_net_confidences)[i] >= 0.5f;
    out->classifier_samples.push_back(s);
  }
}

}  // namespace

CaseInfo caseInfo(const sim::ScenarioCase& scenario_case) {
  CaseInfo info;
  info.name = scenario_case.name();
  for (const auto& v : scenario_case.values) {
    try {
      std::size_t used = 0;
      const double x = std::stod(v.value, &used);
      if (used == v.value.size()) {
        info.numeric_settings[v.path] = x;
        continue;
      }
    } catch (const std::exception&) {
    }
    info.text_settings[v.path] = v.value;
  }
  return info;
}

PerceptionRunner::PerceptionRunner()
    : pipeline_(PipelineConfig::loadDefault()),
      pose_fitter_(PoseFitParams::loadDefault(), FieldDimensions::loadDefault()) {}

FramePercepts PerceptionRunner::process(const sim::RenderedFrame& rendered, const ScoringParams& scoring) {
  Frame frame(rendered.image.view(), rendered.perception_camera);
  frame.time_s = rendered.truth.time_s;
  PipelineStats this_frame;
  pipeline_.process(frame, &this_frame, &tracks_);
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
  addBallClassifierSamples(frame, &p);
  p.robot_proposals = frame.robot_proposals;
  p.robots = frame.robot_percepts;
  addRobotClassifierSamples(frame, &p);
  p.orientation_stage = this_frame.timing(Stage::kRobotOrientation).has_value();
  if (frame.field_lines) {
    p.field_features = frame.field_lines->features;
    p.pose_fit_stage = true;
    FieldPose guess = rendered.truth.observer;
    guess.x_m += scoring.pose_guess_offset_m / std::sqrt(2.0);
    guess.y_m += scoring.pose_guess_offset_m / std::sqrt(2.0);
    guess.heading_rad += scoring.pose_guess_offset_deg * std::numbers::pi / 180.0;
    const PoseFitResult fit = pose_fitter_.fit(frame.field_lines->features, guess);
    if (fit.ok) p.pose_in_field = fit.pose;
  }
  return p;
}

}  // namespace colorfree::app
