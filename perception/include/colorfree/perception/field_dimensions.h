#pragma once

#include <string>

namespace colorfree {

/// The SPL field, ball and NAO sizes that every module shares (SPL rule book 2020; NAO H25).
/// Field coordinates: origin at the centre, x towards the opponent goal, y to the left, z up.
/// Loaded from perception/params/field_dimensions.yaml; the defaults here equal that file.
struct FieldDimensions {
  double field_length_m = 9.0;             ///< between goal-line centres
  double field_width_m = 6.0;              ///< between touch-line centres
  double line_width_m = 0.05;
  double border_strip_m = 0.7;             ///< carpet outside the lines
  double centre_circle_diameter_m = 1.5;   ///< to the line centre
  double penalty_area_length_m = 1.65;     ///< depth from the goal line
  double penalty_area_width_m = 4.0;
  double goal_area_length_m = 0.6;
  double goal_area_width_m = 2.2;
  double penalty_mark_distance_m = 1.3;    ///< from the goal line
  double penalty_mark_size_m = 0.1;        ///< arm length of the cross
  double goal_inner_width_m = 1.5;
  double goal_depth_m = 0.5;
  double goal_height_m = 0.8;
  double goal_post_diameter_m = 0.1;
  double ball_diameter_m = 0.1;
  double robot_height_m = 0.574;           ///< standing NAO
  double robot_width_m = 0.311;            ///< shoulder to shoulder with arms down

  double halfLength() const { return field_length_m / 2; }
  double halfWidth() const { return field_width_m / 2; }
  double ballRadius() const { return ball_diameter_m / 2; }
  double carpetHalfLength() const { return halfLength() + border_strip_m; }
  double carpetHalfWidth() const { return halfWidth() + border_strip_m; }

  /// Loads and validates the file; throws colorfree::Error naming the file and key.
  static FieldDimensions load(const std::string& path);
  /// The shipped file, perception/params/field_dimensions.yaml.
  static FieldDimensions loadDefault();
};

}  // namespace colorfree
