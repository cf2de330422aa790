#pragma once

#include <string>
#include <vector>

#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/cnn/classifier.h"
#include "colorfree/perception/cnn/patch.h"
#include "colorfree/perception/image.h"
#include "colorfree/perception/percepts.h"

namespace colorfree {

/// Parameters of the ball classification stage (perception/params/ball_detector.yaml).
struct BallDetectorParams {
  double ball_radius_m = 0.05;
  /// Side of the square patch cut around a proposal, in ball diameters (both nets, and training).
  double patch_diameters = 1.25;
  int boost_keep_count = 5;              ///< BoostBallNet passes at most this many to BallNet
  double boost_min_confidence = 0.05;    ///< ... and only those with at least this "ball" score
  double ball_min_confidence = 0.5;      ///< BallNet's "ball" score for a detection
  int max_balls = 1;                     ///< detections per frame at most (the strongest)
  /// A proposal whose centre lies more than this × its radius outside the image shows less than
  /// about half of a ball: it is not passed on to BallNet (nor reported).
  double max_centre_outside_radii = 0.25;

  bool operator==(const BallDetectorParams&) const = default;
  static BallDetectorParams load(const std::string& path);
  static BallDetectorParams loadDefault();
};

/// The square patch the nets see for a ball of `radius_px` at `centre_px`.
cnn::PatchBox ballPatchBox(const Eigen::Vector2d& centre_px, double radius_px,
                           double patch_diameters);

/// How far `centre_px` lies outside an image of `width` × `height` pixels, in units of `radius_px`
/// (0 inside; the image spans [0, width] × [0, height], pixel centres at +0.5).
double centreOutsideRadii(const Eigen::Vector2d& centre_px, double radius_px, int width, int height);

/// What the cascade decided for every proposal (for scoring, active learning and the report).
struct BallDecision {
  int proposal = 0;                ///< index into the proposals
  float boost_confidence = 0;      ///< BoostBallNet's "ball" probability
  bool passed_boost = false;       ///< among the kept ones
  float ball_confidence = -1;      ///< BallNet's "ball" probability; -1 when it did not run
  bool detected = false;
};

/// Ball classification (paper 2.4): BoostBallNet (12×12) sorts the proposals by confidence and
/// keeps at most five; BallNet (26×26) decides. Nets read from perception/models by default.
class BallDetector {
 public:
  BallDetector(BallDetectorParams params, cnn::Classifier boost_net, cnn::Classifier ball_net);
  /// The shipped nets (boost_ball_net, ball_net) from `model_dir` (default: perception/models);
  /// throws colorfree::Error naming the file when a model is missing or broken.
  static BallDetector load(BallDetectorParams params, const std::string& model_dir = "");

  std::vector<BallPercept> run(const GrayView& image, const CameraModel& camera,
                               const std::vector<BallProposal>& proposals,
                               std::vector<BallDecision>* decisions = nullptr) const;
  const BallDetectorParams& params() const { return params_; }

 private:
  BallDetectorParams params_;
  cnn::Classifier boost_net_;
  cnn::Classifier ball_net_;
};

}  // namespace colorfree
