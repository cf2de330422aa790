#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/image.h"

namespace colorfree {

/// Parameters of the field boundary detector (perception/params/field_boundary.yaml).
struct FieldBoundaryParams {
  int block_width_px = 16;    ///< width of a sampled column block
  int block_height_px = 8;    ///< height of a sampled column block
  int sample_step_px = 2;     ///< pixel step inside a block (both directions) for mean and spread
  /// A block is carpet when its mean is within this of the carpet luminance (gray levels) ...
  double carpet_luminance_tolerance = 25;
  /// ... or within this fraction of it, whichever is larger (dim light, gradients).
  double carpet_luminance_tolerance_ratio = 0.25;
  /// ... and its standard deviation is at most this factor times the carpet's typical one ...
  double carpet_spread_factor = 3.0;
  /// ... plus this (gray levels), so that a flat carpet still admits some noise.
  double carpet_spread_offset = 8;
  /// The field's top in a column is the top of its highest run of at least this many carpet
  /// blocks (a wide line or a robot below it does not end the field).
  int min_run_blocks = 2;
  /// How much of the image, from the bottom, estimates the carpet's luminance (fraction of the
  /// rows below the horizon).
  double reference_fraction = 0.5;
  /// Rows kept above the boundary found from the texture, so that a line at the edge stays in.
  int margin_px = 8;

  bool operator==(const FieldBoundaryParams&) const = default;
  static FieldBoundaryParams load(const std::string& path);
  static FieldBoundaryParams loadDefault();
};

/// Mean and standard deviation (gray levels) of the pixels (x, y), x0 <= x < x1, y0 <= y < y1,
/// taking every `step`-th row and column from (x0, y0); zero when there are none. Exposed for the
/// tests (the detector's blocks are summed 16 pixels at a time).
struct BlockStats {
  float mean = 0;
  float spread = 0;
};
BlockStats blockStats(const GrayView& image, int x0, int y0, int x1, int y1, int step);

/// Where the field ends towards the top of the image, per image column.
struct FieldBoundary {
  std::vector<int> horizon_y;   ///< first row below the horizon, clamped to [0, height]
  std::vector<int> boundary_y;  ///< first row of the field (>= horizon_y), clamped to [0, height]
  /// The points found where the carpet's texture ends (before the convex hull), for drawing.
  std::vector<Eigen::Vector2d> texture_points_px;
};

/// Finds the field boundary in a grayscale image: the camera model's horizon, lowered to where the
/// carpet (blocks of roughly the carpet's luminance and texture) ends in each column; the points
/// are joined by their upper convex hull so that robots standing in front of the boundary do not
/// cut into the field. Where no carpet is found the boundary stays at the horizon.
class FieldBoundaryDetector {
 public:
  explicit FieldBoundaryDetector(FieldBoundaryParams params = {});
  FieldBoundary run(const GrayView& image, const CameraModel& camera) const;
  const FieldBoundaryParams& params() const { return params_; }

 private:
  FieldBoundaryParams params_;
};

/// A standing NAO's body as boxes in its robot frame (perception/params/body_model.yaml): what of
/// the observer's own chest, legs and feet the bottom camera sees.
struct BodyModelParams {
  double foot_length_m = 0.16;
  double foot_width_m = 0.09;
  double foot_height_m = 0.045;
  double foot_centre_x_m = 0.025;   ///< foot box centre ahead of the robot-frame origin
  double feet_separation_m = 0.10;  ///< between the foot centres (2 × HipOffsetY)
  double leg_width_m = 0.095;       ///< thigh and tibia diameter, as a square box
  double hip_height_m = 0.25;       ///< hip joints above the ground
  double chest_front_x_m = 0.07;    ///< front of the chest ahead of the origin
  double chest_back_x_m = -0.06;
  double chest_width_m = 0.20;
  double chest_bottom_m = 0.24;     ///< chest box from this height ...
  double chest_top_m = 0.42;        ///< ... to this one (the neck)
  int margin_px = 4;                ///< grown by this many rows upwards in the image

  bool operator==(const BodyModelParams&) const = default;
  static BodyModelParams load(const std::string& path);
  static BodyModelParams loadDefault();
};

/// The observer's own body in the image, per column: rows at or below top_y belong to it.
struct BodyContour {
  std::vector<int> top_y;  ///< first body row per column, `height` when the body is not seen
  std::vector<std::vector<Eigen::Vector2d>> polygons_px;  ///< projected boxes, for drawing
};

/// Projects the body model through the camera model (robot frame in, pixels out).
class BodyContourProvider {
 public:
  explicit BodyContourProvider(BodyModelParams params = {});
  BodyContour run(const CameraModel& camera) const;
  const BodyModelParams& params() const { return params_; }

 private:
  BodyModelParams params_;
};

/// The part of the image later stages look at: pixel (x, y) is looked at iff
/// top_y[x] <= y < bottom_y[x].
struct IgnoreMask {
  int width = 0;
  int height = 0;
  std::vector<int> top_y;
  std::vector<int> bottom_y;

  bool looked(int x, int y) const { return y >= top_y[x] && y < bottom_y[x]; }
  /// Everything looked at (no boundary, no body).
  static IgnoreMask all(int width, int height);
  /// Combines the field boundary (above) and the body contour (below).
  static IgnoreMask combine(const FieldBoundary& boundary, const BodyContour& body, int width,
                            int height);
};

}  // namespace colorfree
