#pragma once

#include "colorfree/perception/pipeline.h"
#include "colorfree/perception/robot_detector.h"
#include "colorfree/perception/robot_orientation.h"
#include "colorfree/perception/robot_proposer.h"

namespace colorfree {

/// The three robot stages (paper 2.3, 2.4) run on a Frame after Pipeline::process: fills
/// robot_proposals and robot_percepts (with orientations and track ids) and times the stages.
/// The tracks are the caller's state between frames.
class RobotModule {
 public:
  RobotModule(RobotProposer proposer, RobotDetector detector, RobotOrientationEstimator orientation);
  /// The shipped parameters and nets.
  static RobotModule loadDefault();
  /// Throws colorfree::Error when the frame lacks the ignore mask or the contrast regions.
  void process(Frame& frame, RobotTracks& tracks, double time_s, PipelineStats* stats = nullptr) const;

  const RobotProposer& proposer() const { return proposer_; }
  const RobotDetector& detector() const { return detector_; }
  const RobotOrientationEstimator& orientation() const { return orientation_; }

 private:
  RobotProposer proposer_;
  RobotDetector detector_;
  RobotOrientationEstimator orientation_;
};

}  // namespace colorfree
