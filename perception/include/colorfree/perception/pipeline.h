#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "colorfree/perception/ball_detector.h"
#include "colorfree/perception/ball_proposer.h"
#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/field_lines.h"
#include "colorfree/perception/high_contrast.h"
#include "colorfree/perception/ignore_regions.h"
#include "colorfree/perception/image.h"
#include "colorfree/perception/percepts.h"
#include "colorfree/perception/robot_detector.h"
#include "colorfree/perception/robot_orientation.h"
#include "colorfree/perception/robot_proposer.h"

namespace colorfree {

/// The per-frame blackboard: the input and one member per stage output. A member that is empty
/// was not produced (its stage is absent from the pipeline or has not run).
struct Frame {
  GrayView image;
  CameraModel camera;
  double time_s = 0;  ///< the frame's time (the orientation filter's buffer expires by it)

  std::optional<FieldBoundary> field_boundary;
  std::optional<BodyContour> body_contour;
  std::optional<IgnoreMask> ignore_mask;
  /// The frame's pixel noise over the looked-at area (pixelNoiseGray, gray levels), estimated once
  /// with the ignore mask; the robot and ball proposers' thresholds follow it.
  std::optional<double> pixel_noise_gray;
  /// The frame's light (frameLightGray, gray levels), estimated once with the ignore mask; the
  /// high-contrast stage's and the ball proposer's thresholds follow it.
  std::optional<double> light_gray;
  std::optional<ContrastRegions> contrast_regions;
  std::optional<FieldLineResult> field_lines;
  /// The robot proposals RobotNet classified: the proposer's, then the held-back ones it freed.
  std::optional<std::vector<RobotProposal>> robot_proposals;
  std::optional<std::vector<RobotPercept>> robot_percepts;
  /// RobotNet's robot probability per proposal (same order as robot_proposals).
  std::optional<std::vector<float>> robot_net_confidences;
  std::optional<std::vector<BallProposal>> ball_proposals;
  std::optional<std::vector<BallPercept>> ball_percepts;
  /// The ball cascade's decision per proposal (same order as ball_proposals).
  std::optional<std::vector<BallDecision>> ball_decisions;

  /// The detected field lines and features, or none when the field lines stage did not run (as
  /// the orientation stage is given them).
  const FieldFeatures& fieldFeatures() const {
    static const FieldFeatures kNone;
    return field_lines ? field_lines->features : kNone;
  }

  Frame(GrayView image_in, CameraModel camera_in)
      : image(image_in), camera(std::move(camera_in)) {}
};

/// The pipeline's stages, in the order they run (the paper's profiling table rows).
enum class Stage {
  kIgnoreRegions,
  kHighContrast,
  kFieldLines,
  kRobotProposals,
  kRobotDetector,
  kRobotOrientation,
  kBallProposals,
  kBallDetector,
};
inline constexpr int kStageCount = 8;
const char* stageName(Stage stage);

/// Timing of one stage over the frames processed so far.
struct StageTiming {
  long frames = 0;
  double total_ms = 0;
  double max_ms = 0;
  double meanMs() const { return frames > 0 ? total_ms / frames : 0; }
};

/// Per-stage timing, kept by the caller and handed to `Pipeline::process` (no hidden state).
/// A stage that never ran is absent (`timing` empty), not zero.
class PipelineStats {
 public:
  void add(Stage stage, double ms);
  const std::optional<StageTiming>& timing(Stage stage) const {
    return timings_[static_cast<int>(stage)];
  }
  /// A table of mean and max per stage, "absent" for the stages that never ran.
  std::string table() const;

 private:
  std::array<std::optional<StageTiming>, kStageCount> timings_;
};

/// Which stages run, and their parameters.
struct PipelineConfig {
  FieldBoundaryParams field_boundary;
  BodyModelParams body_model;
  HighContrastParams high_contrast;
  FieldLineParams field_lines;
  FieldDimensions field;
  RobotProposerParams robot_proposer;
  RobotDetectorParams robot_detector;
  RobotOrientationParams robot_orientation;
  BallProposerParams ball_proposer;
  BallDetectorParams ball_detector;
  bool robot_stages = true;  ///< run robot proposals, RobotNet and the orientation (needs the nets)
  bool ball_stages = true;   ///< run ball proposals and the ball detector (needs the ball nets)
  std::string model_dir;    ///< the nets' directory; empty = the shipped perception/models
  bool use_body_contour = true;  ///< the observer's body (bottom camera)
  bool keep_rejected = false;    ///< keep rejected candidates with their reason

  /// All parameters from the shipped files in perception/params.
  static PipelineConfig loadDefault();
  /// All parameters from the files in `dir` (same names as the shipped ones).
  static PipelineConfig load(const std::string& dir);
};

/// Runs the stages on a Frame in a fixed order and times each.
class Pipeline {
 public:
  explicit Pipeline(PipelineConfig config);
  /// Throws colorfree::Error when the image does not match the camera model. `tracks` is the
  /// caller's state between frames (the robots' orientation filters); without it every frame's
  /// filtered orientation comes from that frame alone.
  void process(Frame& frame, PipelineStats* stats = nullptr, RobotTracks* tracks = nullptr) const;

 private:
  PipelineConfig config_;
  FieldBoundaryDetector field_boundary_;
  BodyContourProvider body_contour_;
  HighContrastDetector high_contrast_;
  FieldLineDetector field_lines_;
  RobotProposer robot_proposer_;
  std::optional<RobotDetector> robot_detector_;
  std::optional<RobotOrientationEstimator> robot_orientation_;
  BallProposer ball_proposer_;
  std::optional<BallDetector> ball_detector_;
};

}  // namespace colorfree
