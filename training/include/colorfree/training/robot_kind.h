#pragma once

#include <cstdint>
#include <optional>

#include "colorfree/groundtruth/scoring_params.h"
#include "colorfree/perception/pipeline.h"
#include "colorfree/perception/robot_orientation.h"
#include "colorfree/perception/robot_proposer.h"
#include "colorfree/training/active_learning.h"

namespace colorfree::training {

/// Which of the robot nets a RobotKind teaches.
enum class RobotNetChoice {
  kRobotNet,     ///< RobotNet: the real RobotProposer's boxes, robot or none
  kOriBoostNet,  ///< OriBoostNet: the lines generator's regions, usable line or not
  kOriNet,   ///< OriNet: usable regions, front, back or side (facing the observer's left or right)
  kFeetNet,  ///< RobotFeetNet: a box on a robot, its feet row right, too high or too low
  /// RobotBehindNet: as RobotNet, and the held-back candidates too (boxes inside a nearer robot's:
  /// robots behind it, and its hands, arms and knees), on which the detector asks for its veto
  kBehindNet,
};

/// Labelling rules for the robot kinds (angles between a line and the true heading's axis or its
/// normal, whichever is nearer).
struct RobotLabelRules {
  double usable_max_deg =
      12;  ///< OriBoostNet: a line this close to the axis or the normal is usable
  double unusable_min_deg = 20;  ///< ... this far from both, unusable; in between left out
  double classed_max_deg = 9;    ///< OriNet: regions whose line is this close get a class
  int random_negatives = 2;      ///< RobotNet: robot-sized boxes at random ground points per frame
  /// RobotFeetNet: a box whose feet row lies within this fraction of the robot's height of the
  /// true feet is right; from feet_off_min_fraction up to feet_off_max_fraction it is too high or
  /// too low; in between, and farther, left out.
  double feet_right_max_fraction = 0.05;
  double feet_off_min_fraction = 0.1;
  double feet_off_max_fraction = 0.45;
};

/// The robot-specific part of the loop. Proposals come from the real RobotProposer (after the
/// real ignore-region and high-contrast stages); a proposal is a robot when the scorer's matching
/// rule pairs it with a robot that should be detected, none when it pairs with no robot. The
/// orientation kinds run the real lines generator on the proposals that are robots and label its
/// regions from the true heading. RobotFeetNet's kind labels the proposals standing on a robot by
/// where its feet are against theirs (feetCandidate). Random negatives are drawn from a generator seeded by the
/// frame's pixels, so the same frame gives the same samples.
class RobotKind : public ObjectKind {
 public:
  RobotKind(RobotNetChoice which, PipelineConfig pipeline, ScoringParams scoring,
            RobotLabelRules rules = {});
  std::string name() const override;
  std::vector<std::string> classNames() const override;
  std::vector<std::string> netStems() const override;
  /// OriNet's side classes say which way the robot faces in the image: a mirrored side region
  /// faces the other way, so only front and back (and the other nets' classes) may be flipped.
  std::vector<bool> flipAllowed() const override;
  /// RobotNet, RobotBehindNet: robot (1) and none (0). RobotFeetNet and the orientation nets have
  /// no object-free scenes to bootstrap on; their labels here are unused.
  int positiveLabel() const override { return 1; }
  int negativeLabel() const override { return which_ == RobotNetChoice::kOriNet ? 2 : 0; }
  std::vector<Candidate> proposals(const GrayImage& image, const CameraModel& camera,
                                   const FrameTruth& truth) const override;
  /// RobotNet: a proposal-shaped box above every true robot's ground point. RobotFeetNet: such
  /// boxes with the feet moved by 0, ±0.15 and ±0.3 of the robot's height. The orientation kinds:
  /// none (their regions only exist where the lines generator puts them).
  std::vector<Candidate> truthSamples(const GrayImage& image, const CameraModel& camera,
                                      const FrameTruth& truth) const override;

 private:
  /// RobotFeetNet's sample for a box about feet_px: labelled from the robot it stands on, none
  /// when it stands on no demanded robot or between the label rules' bounds.
  std::optional<Candidate> feetCandidate(const CameraModel& camera, const FrameTruth& truth,
                                         const PixelBox& box, const Eigen::Vector2d& feet_px,
                                         const char* what) const;
  /// RobotNet or RobotBehindNet (the same samples but the held-back candidates).
  bool robotNet() const {
    return which_ == RobotNetChoice::kRobotNet || which_ == RobotNetChoice::kBehindNet;
  }

  RobotNetChoice which_;
  PipelineConfig config_;
  Pipeline pipeline_;  ///< the early stages only (robot and ball stages off)
  RobotProposer proposer_;
  RobotOrientationEstimator lines_;  ///< only its lines generator is used (untrained nets)
  ScoringParams scoring_;
  RobotLabelRules rules_;
};

}  // namespace colorfree::training
