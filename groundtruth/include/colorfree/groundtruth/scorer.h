#pragma once

#include <array>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "colorfree/groundtruth/field_markings.h"
#include "colorfree/groundtruth/scoring_params.h"
#include "colorfree/groundtruth/truth_in_image.h"
#include "colorfree/groundtruth/world_state.h"
#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/image.h"
#include "colorfree/perception/percepts.h"

namespace colorfree {

/// One sample that reached a binary CNN classifier, with the classifier's decision. Its true label
/// comes from matching the sample to the truth (ball: centre rule; robot: box/feet rule).
struct ClassifierSample {
  enum class Object { kBall, kRobot };
  std::string classifier;  ///< e.g. "BallNet", "RobotNet"
  Object object = Object::kBall;
  Eigen::Vector2d centre_px = Eigen::Vector2d::Zero();  ///< ball samples
  PixelBox box;                                         ///< robot samples
  Eigen::Vector2d feet_px = Eigen::Vector2d::Zero();
  bool predicted_positive = false;
};

/// What the perception produced for one frame. A stage the pipeline does not have is left empty
/// (nullopt / false): its metrics are then absent, never zero.
struct FramePercepts {
  std::optional<std::vector<BallProposal>> ball_proposals;
  std::optional<std::vector<BallPercept>> balls;
  std::optional<std::vector<RobotProposal>> robot_proposals;
  std::optional<std::vector<RobotPercept>> robots;
  bool orientation_stage = false;  ///< the robots carry orientation estimates when they have one
  std::optional<FieldFeatures> field_features;
  bool pose_fit_stage = false;
  std::optional<FieldPose> pose_in_field;  ///< the pose fit's result this frame, if it found one
  std::map<std::string, double> stage_times_ms;  ///< this frame's time per stage
  std::vector<ClassifierSample> classifier_samples;
};

enum class OrientationClass { kPerceived, kSemiPerceived, kNotPerceived, kFalsePositive };
inline constexpr int kOrientationClassCount = 4;
const char* orientationClassName(OrientationClass c);

/// The paper's orientation classes: perceived = facing known and within the tolerance;
/// semi-perceived = the axis within the tolerance but facing unknown, or facing flipped by 180°;
/// not perceived = no estimate; false positive = anything else. Boundaries are inclusive.
OrientationClass classifyOrientation(const std::optional<RobotOrientation>& estimate,
                                     double true_angle_rad, double tolerance_rad);

/// A sweep case: its name and the settings that make it (numbers are charted).
struct CaseInfo {
  std::string name = "all";
  std::map<std::string, double> numeric_settings;
  std::map<std::string, std::string> text_settings;
};

/// What names the run in results.json.
struct RunInfo {
  std::string scenario;
  std::uint64_t seed = 0;
  std::string code_version;
};

/// A picture for the report: a PNG as base64, with a caption.
struct GalleryItem {
  std::string kind;  ///< missed_ball, false_ball, missed_robot, false_robot, orientation, worst_frame
  std::string caption;
  double severity = 0;
  int frame = 0;
  std::string png_base64;
};

/// The paper's stages, in the profiling table's order (JSON keys under timing_ms).
const std::vector<std::string>& paperStageNames();
/// The paper's classifiers (JSON keys under cnn).
const std::vector<std::string>& paperClassifierNames();

/// Scores frames against the truth and accumulates the paper's metrics, overall and per case.
class Scorer {
 public:
  Scorer(ScoringParams params, FieldDimensions dims);
  ~Scorer();
  Scorer(Scorer&&) noexcept;
  Scorer& operator=(Scorer&&) noexcept;

  const ScoringParams& params() const { return params_; }
  /// Frames added after this count towards this case (and the total).
  void beginCase(const CaseInfo& info);
  /// Computes the truth from `world` and scores `percepts`. With an image, the gallery gets crops.
  FrameTruth addFrame(const WorldState& world, const FramePercepts& percepts,
                      const GrayImage* image = nullptr);
  /// Scores against a truth computed elsewhere; `camera`/`observer` turn percept feet into field
  /// points (may be null: then feet are not used).
  void addFrame(const FrameTruth& truth, const FramePercepts& percepts, const CameraModel* camera,
                const GrayImage* image = nullptr);

  int frameCount() const;
  /// The metrics as results.json holds them (without the run info).
  nlohmann::json results(const RunInfo& run) const;
  const std::vector<GalleryItem>& gallery() const;

 private:
  struct State;
  ScoringParams params_;
  FieldDimensions dims_;
  FieldMarkings field_;
  std::unique_ptr<State> state_;
};

}  // namespace colorfree
