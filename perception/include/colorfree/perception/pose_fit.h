#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "colorfree/perception/field_dimensions.h"
#include "colorfree/perception/field_pose.h"
#include "colorfree/perception/percepts.h"

namespace colorfree {

/// The field's markings in field coordinates, built from FieldDimensions only.
struct FieldModel {
  struct Segment {
    Eigen::Vector2d a, b;
  };
  struct Intersection {
    IntersectionType type;
    Eigen::Vector2d position;
  };
  std::vector<Segment> lines;
  std::vector<Intersection> intersections;
  Eigen::Vector2d centre_circle_centre = Eigen::Vector2d::Zero();
  double centre_circle_radius_m = 0.75;
  std::vector<Eigen::Vector2d> penalty_marks;

  explicit FieldModel(const FieldDimensions& field);
};

/// Parameters of the pose fit (perception/params/pose_fit.yaml).
struct PoseFitParams {
  int iterations = 30;
  double line_sample_spacing_m = 0.1;   ///< points taken along each detected line
  /// Residuals beyond this many metres from the model count with a capped (Huber) weight.
  double huber_m = 0.15;
  /// Associations farther than this from every model element are left out in an iteration.
  double max_association_m = 0.8;
  double intersection_weight = 2.0;     ///< relative to one line sample
  /// The heading is first corrected so the detected lines (at least this long) run along x or y,
  /// by at most this much.
  double heading_prior_min_line_m = 0.3;
  double heading_prior_max_correction_deg = 20;
  double circle_weight = 4.0;
  double penalty_mark_weight = 2.0;
  double converged_step_m = 1e-6;

  bool operator==(const PoseFitParams&) const = default;
  static PoseFitParams load(const std::string& path);
  static PoseFitParams loadDefault();
};

struct PoseFitResult {
  FieldPose pose;
  int used_observations = 0;     ///< associated observations in the last iteration
  double rms_residual_m = 0;     ///< of the associated observations
  int iterations = 0;
  bool ok = false;               ///< false when too few features constrain the pose
};

/// The field pose that best explains detected features (robot frame) against the field model,
/// starting from a guess: iterative closest-element Gauss–Newton on (x, y, θ).
class PoseFitter {
 public:
  explicit PoseFitter(PoseFitParams params = {}, FieldDimensions field = FieldDimensions{});
  PoseFitResult fit(const FieldFeatures& features, const FieldPose& initial_guess) const;
  const FieldModel& model() const { return model_; }

 private:
  PoseFitParams params_;
  FieldModel model_;
};

}  // namespace colorfree
