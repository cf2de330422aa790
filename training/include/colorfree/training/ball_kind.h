#pragma once

#include "colorfree/groundtruth/scoring_params.h"
#include "colorfree/perception/ball_detector.h"
#include "colorfree/perception/ball_proposer.h"
#include "colorfree/perception/pipeline.h"
#include "colorfree/training/active_learning.h"

namespace colorfree::training {

/// The ball-specific part of the loop: BoostBallNet and BallNet, proposals from the real
/// BallProposer (after the real ignore-region and high-contrast stages), labels from the scorer's
/// ball matching rule. Two samples are the same when their case, centre pixel and radius are.
/// `smeared_only`: SmearedBallNet alone, on the patches the detector may give it (inside the image,
/// at least `smeared_min_coherence` elongated: `patchSmear`, radius at least
/// `smeared_min_radius_px`), the ball's truth-cut patches too.
class BallKind : public ObjectKind {
 public:
  BallKind(PipelineConfig pipeline, ScoringParams scoring, bool smeared_only = false);
  std::string name() const override { return smeared_only_ ? "smeared_ball" : "ball"; }
  std::vector<std::string> classNames() const override { return {"none", "ball"}; }
  std::vector<std::string> netStems() const override {
    if (smeared_only_) return {"smeared_ball_net"};
    return {"boost_ball_net", "ball_net"};
  }
  int positiveLabel() const override { return 1; }
  int negativeLabel() const override { return 0; }
  std::vector<Candidate> proposals(const GrayImage& image, const CameraModel& camera,
                                   const FrameTruth& truth) const override;
  std::vector<Candidate> truthSamples(const GrayImage& image, const CameraModel& camera,
                                      const FrameTruth& truth) const override;

 private:
  PipelineConfig config_;
  Pipeline pipeline_;  ///< the early stages only (ball_stages off)
  BallProposer proposer_;
  ScoringParams scoring_;
  bool smeared_only_;
  /// Whether a patch is one this kind's nets see (always, but for `smeared_only`).
  bool takes(const GrayImage& image, const cnn::PatchBox& box, double radius_px) const;
};

}  // namespace colorfree::training
