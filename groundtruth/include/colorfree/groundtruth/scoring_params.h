#pragma once

#include <string>

namespace colorfree {

/// The "should be detected" rule, the truth body model and the matching thresholds of the bench.
/// Loaded strictly from groundtruth/params/scoring.yaml; the defaults here equal that file.
struct ScoringParams {
  // Should-detect rule.
  double ball_min_visible_fraction = 0.5;  ///< object-map pixels / projected-ball pixels
  double ball_min_distance_m = 0.0;        ///< ground distance from the observer
  double ball_max_distance_m = 6.0;
  double ball_min_radius_px = 2.0;
  double robot_min_visible_fraction = 0.5;
  double robot_min_distance_m = 0.0;
  double robot_max_distance_m = 6.0;
  double robot_min_height_px = 12.0;  ///< projected whole-body box height
  // Robot body model (width and height from FieldDimensions).
  double robot_depth_m = 0.21;  ///< side view with arms and stride; the outline is an ellipse
  double robot_feet_region_height_m = 0.12;
  double foot_lateral_offset_m = 0.05;
  // Matching.
  double ball_match_radius_fraction = 0.5;
  double ball_match_min_px = 2.0;
  double robot_match_min_iou = 0.5;
  double robot_match_max_feet_distance_m = 0.3;
  // Orientation.
  double orientation_tolerance_deg = 11.25;
  double orientation_heading_bin_deg = 22.5;
  // Field features.
  double field_feature_max_distance_m = 6.0;  ///< markings farther from the observer are left out
  double line_min_length_px = 20.0;
  double line_match_max_px = 6.0;
  double intersection_match_max_px = 12.0;
  int feature_visibility_window_px = 3;
  /// The feature-based pose fit starts from the true pose moved by this much (diagonally) and
  /// turned by this angle, so a fit that does not move shows the offset as its error.
  double pose_guess_offset_m = 0.2;
  double pose_guess_offset_deg = 5.0;
  // Report.
  double distance_bin_m = 0.5;
  double visibility_bin_fraction = 0.1;  ///< detection rate against the visible fraction
  int gallery_max_crops = 24;
  int gallery_worst_frames = 6;

  /// Throws colorfree::Error naming the file and key on a missing, unknown or impossible value.
  static ScoringParams load(const std::string& path);
  /// groundtruth/params/scoring.yaml in the source tree.
  static std::string defaultPath();
  static ScoringParams loadDefault() { return load(defaultPath()); }

  /// The should-detect rule in words, as the report prints it.
  std::string shouldDetectRule() const;
  /// The matching rule in words.
  std::string matchingRule() const;
};

}  // namespace colorfree
