#include "colorfree/training/ball_kind.h"

#include <cmath>
#include <cstdio>

#include "colorfree/groundtruth/matching.h"
#include "colorfree/perception/error.h"

namespace colorfree::training {

namespace {

PipelineConfig earlyStages(PipelineConfig c) {
  c.ball_stages = false;
  return c;
}

std::string ballTruthText(const BallInImage& b) {
  char text[96];
  std::snprintf(text, sizeof text, "ball r=%.1fpx d=%.2fm visible=%.2f", b.radius_px, b.distance_m,
                b.visible_fraction);
  return text;
}

}  // namespace

BallKind::BallKind(PipelineConfig pipeline, ScoringParams scoring, bool smeared_only)
    : config_(pipeline),
      pipeline_(earlyStages(pipeline)),
      proposer_(pipeline.ball_proposer),
      scoring_(scoring),
      smeared_only_(smeared_only) {
  if (smeared_only_ && config_.ball_detector.smeared_min_coherence > 1) {
    throw Error("learn smeared_ball: a smeared_min_coherence above 1 gives SmearedBallNet no patch");
  }
}

bool BallKind::takes(const GrayImage& image, const cnn::PatchBox& box, double radius_px) const {
  const BallDetectorParams& p = config_.ball_detector;
  return !smeared_only_ ||
         (radius_px >= p.smeared_min_radius_px && patchSmear(image.view(), box) >= p.smeared_min_coherence);
}

std::vector<Candidate> BallKind::proposals(const GrayImage& image, const CameraModel& camera,
                                           const FrameTruth& truth) const {
  Frame frame(image.view(), camera);
  pipeline_.process(frame);
  const auto props =
      proposer_.run(image.view(), camera, *frame.ignore_mask, *frame.contrast_regions, nullptr);
  std::vector<Candidate> out;
  const BallInImage& ball = truth.ball;
  const bool ball_here = truth.ball_present && ball.in_view;
  for (const BallProposal& p : props) {
    Candidate c;
    c.box = ballPatchBox(p.centre_px, p.radius_px, config_.ball_detector.patch_diameters);
    char key[64];
    std::snprintf(key, sizeof key, "%d,%d,%d", static_cast<int>(std::floor(p.centre_px.x())),
                  static_cast<int>(std::floor(p.centre_px.y())), static_cast<int>(std::lround(p.radius_px)));
    c.key = key;
    if (!takes(image, c.box, p.radius_px)) continue;
    if (ball_here && ballMatchCost(ball, p.centre_px, scoring_)) {
      if (!ball.should_detect) continue;  // too hidden or too small to demand: not a sample either way
      c.label = 1;
      c.truth = ballTruthText(ball);
    } else if (ball_here && (p.centre_px - ball.centre_px).norm() < ball.radius_px + p.radius_px) {
      continue;  // overlaps the ball without matching it: ambiguous
    } else {
      c.label = 0;
      c.truth = "no ball";
    }
    out.push_back(c);
  }
  return out;
}

std::vector<Candidate> BallKind::truthSamples(const GrayImage& image, const CameraModel& /*camera*/,
                                              const FrameTruth& truth) const {
  std::vector<Candidate> out;
  const BallInImage& ball = truth.ball;
  if (!truth.ball_present || !ball.in_view || !ball.should_detect) return out;
  Candidate c;
  c.box = ballPatchBox(ball.centre_px, ball.radius_px, config_.ball_detector.patch_diameters);
  if (!takes(image, c.box, ball.radius_px)) return out;
  c.label = 1;
  char key[64];
  std::snprintf(key, sizeof key, "truth %d,%d,%d", static_cast<int>(std::floor(ball.centre_px.x())),
                static_cast<int>(std::floor(ball.centre_px.y())), static_cast<int>(std::lround(ball.radius_px)));
  c.key = key;
  c.truth = ballTruthText(ball);
  out.push_back(c);
  return out;
}

}  // namespace colorfree::training
