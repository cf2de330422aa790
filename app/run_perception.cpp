#include "run_perception.h"

#include <memory>

#include "colorfree/perception/pipeline.h"

namespace colorfree::app {

struct PerceptionRunner::Impl {
  Pipeline pipeline{PipelineConfig::loadDefault()};
};

PerceptionRunner::PerceptionRunner() : impl_(std::make_shared<Impl>()) {}

FramePercepts PerceptionRunner::process(const GrayImage& image, const CameraModel& camera) {
  Frame frame(image.view(), camera);
  PipelineStats stats;
  impl_->pipeline.process(frame, &stats);
  FramePercepts out;
  // The ball stages; the other stages' outputs are handed over by their own modules.
  if (frame.ball_proposals) out.ball_proposals = *frame.ball_proposals;
  if (frame.ball_percepts) out.balls = *frame.ball_percepts;
  if (frame.ball_decisions && frame.ball_proposals) {
    for (const BallDecision& d : *frame.ball_decisions) {
      if (!d.passed_boost) continue;
      ClassifierSample s;
      s.classifier = "BallNet";
      s.object = ClassifierSample::Object::kBall;
      s.centre_px = (*frame.ball_proposals)[d.proposal].centre_px;
      s.predicted_positive = d.detected || d.ball_confidence >= 0.5f;
      out.classifier_samples.push_back(s);
    }
    for (const BallDecision& d : *frame.ball_decisions) {
      ClassifierSample s;
      s.classifier = "BoostBallNet";
      s.object = ClassifierSample::Object::kBall;
      s.centre_px = (*frame.ball_proposals)[d.proposal].centre_px;
      s.predicted_positive = d.boost_confidence >= 0.5f;
      out.classifier_samples.push_back(s);
    }
  }
  for (Stage s : {Stage::kBallProposals, Stage::kBallDetector}) {
    if (const auto& t = stats.timing(s)) out.stage_times_ms[s == Stage::kBallProposals ? "ball_proposals" : "ball_detector"] = t->total_ms;
  }
  return out;
}

}  // namespace colorfree::app
