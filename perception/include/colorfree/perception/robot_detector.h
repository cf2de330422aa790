#pragma once

#include <string>
#include <vector>

#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/cnn/classifier.h"
#include "colorfree/perception/image.h"
#include "colorfree/perception/percepts.h"

namespace colorfree {

/// Parameters of the robot detector (perception/params/robot_detector.yaml).
struct RobotDetectorParams {
  double min_confidence = 0.5;   ///< RobotNet's robot probability needed for a percept
  double max_overlap_iou = 0.3;  ///< of two accepted boxes overlapping more, the more confident stays
  /// An accepted box with at least this fraction of its area inside a larger accepted box is a
  /// part of that robot (its hand, arm or shoulder), whatever the confidences: the larger stays.
  double max_inside_fraction = 0.9;
  /// A held-back candidate's patch holds parts of the nearer boxes RobotNet rejected, which may
  /// be a robot RobotNet missed: it becomes a percept only at this robot probability or more.
  double min_held_back_confidence = 0.7;

  bool operator==(const RobotDetectorParams&) const = default;
  static RobotDetectorParams load(const std::string& path);
  static RobotDetectorParams loadDefault();
};

/// Which of the boxes RobotNet accepted (`confidence` >= min_confidence) become percepts, most
/// confident first: a box overlapping a kept one by more than max_overlap_iou is dropped, and a
/// box lying max_inside_fraction inside a larger kept one is a part of it (hand, arm) and dropped
/// even when it is the more confident. Indices into `boxes`.
std::vector<int> keptRobotBoxes(const std::vector<PixelBox>& boxes,
                                const std::vector<float>& confidence,
                                const RobotDetectorParams& params);

/// The proposal box as RobotNet's patch.
cnn::PatchBox robotPatchBox(const RobotProposal& proposal);

/// Classifies robot proposals with RobotNet (24×24, paper 2.3) and turns the accepted ones into
/// percepts with their ground point in the robot frame.
class RobotDetector {
 public:
  RobotDetector(RobotDetectorParams params, cnn::Classifier robot_net);
  /// The shipped parameters and RobotNet (perception/models/robot_net.*).
  static RobotDetector loadDefault();
  /// `confidences` (optional) gets RobotNet's output for every proposal, in order.
  std::vector<RobotPercept> run(const GrayView& image, const CameraModel& camera,
                                const std::vector<RobotProposal>& proposals,
                                std::vector<float>* confidences = nullptr) const;
  /// The same, and then the held-back candidates none of whose nearer proposals RobotNet accepted
  /// (what a box without a robot seemed to hide is free), accepted from min_held_back_confidence.
  /// `classified` (optional) gets every proposal RobotNet saw: `proposals`, then those held-back
  /// ones; `confidences` one output each.
  std::vector<RobotPercept> run(const GrayView& image, const CameraModel& camera,
                                const std::vector<RobotProposal>& proposals,
                                const std::vector<HeldBackRobotProposal>& held_back,
                                std::vector<RobotProposal>* classified,
                                std::vector<float>* confidences = nullptr) const;

 private:
  RobotDetectorParams params_;
  cnn::Classifier net_;
};

}  // namespace colorfree
