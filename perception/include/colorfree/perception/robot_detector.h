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

  bool operator==(const RobotDetectorParams&) const = default;
  static RobotDetectorParams load(const std::string& path);
  static RobotDetectorParams loadDefault();
};

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

 private:
  RobotDetectorParams params_;
  cnn::Classifier net_;
};

}  // namespace colorfree
