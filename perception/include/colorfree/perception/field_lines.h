#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/field_dimensions.h"
#include "colorfree/perception/ignore_regions.h"
#include "colorfree/perception/image.h"
#include "colorfree/perception/percepts.h"

namespace colorfree {

/// Parameters of the field line and feature detector (perception/params/field_lines.yaml).
struct FieldLineParams {
  int scan_spacing_px = 8;     ///< between vertical scan lines and between horizontal ones
  int edge_step_px = 2;        ///< an edge is the luminance difference over this many pixels
  double min_edge_contrast = 18;  ///< gray levels of a rising or falling edge
  /// ... and at least this many times the carpet's noise (the spread of the differences of
  /// neighbouring pixels along the scan lines, estimated per frame and scan direction).
  double edge_noise_factor = 3.5;
  /// Above this pixel noise (gray levels, estimated per frame) the scan lines are smoothed
  /// ([1 4 6 4 1] / 16) before the edges are searched.
  double smoothing_min_noise = 16;
  /// The bright run's mean must exceed the mean of the carpet on both of its sides by this much
  /// (gray levels): averaging keeps carpet noise from making spots.
  double min_spot_contrast = 24;
  /// Rising and falling edge must be of similar strength: the weaker at least this fraction.
  double min_edge_balance = 0.4;
  /// Accepted spot width as a factor of the expected width of a line at that row and direction.
  double min_width_factor = 0.4;
  double max_width_factor = 3.5;
  double width_slack_px = 2;   ///< added to the accepted width range on both sides
  double max_distance_m = 6.0; ///< spots farther on the ground are dropped
  /// Chaining spots of neighbouring scan lines: most pixels of jump per pixel of scan spacing.
  double chain_max_slope = 1.5;
  int min_chain_spots = 3;
  /// A piece is straight when its spots are at most this far (metres, plus the fraction of their
  /// distance below) from its fitted ground line; otherwise it is a curve candidate.
  double straight_tolerance_m = 0.03;
  double straight_tolerance_per_metre = 0.01;
  /// Merging pieces: angle and offset between them.
  double merge_max_angle_deg = 8;
  double merge_max_offset_m = 0.08;
  double merge_max_gap_m = 1.0;  ///< free space between the ends of two collinear pieces
  double min_line_length_m = 0.25;
  int min_line_spots = 5;
  /// Spots on a line's ground line up to this far beyond its ends join it.
  double extend_max_gap_m = 0.15;
  /// Not on the ground: a line's spot widths must grow with the width expected where they are.
  /// Checked when the expected widths along it differ by at least `width_trend_min_range`; the
  /// slope of log(width) over log(expected width) must then be at least `min_width_trend`
  /// (a painted line: about 1; an upright white robot part: about 0).
  double width_trend_min_range = 1.6;
  double min_width_trend = 0.45;
  /// Spots scanned the other way than most of the piece's are left out of the range and the slope
  /// when they are at most this share of its spots (a robot's feet standing on the line join it as
  /// a few such spots; 0: none left out)
  double width_trend_minority_fraction = 0.05;
  /// Centre circle: radius tolerance of a fit and the share of its spots that must lie on it.
  double circle_radius_tolerance_m = 0.12;
  double circle_inlier_distance_m = 0.05;
  double circle_inlier_distance_per_metre = 0.02;  ///< added per metre of distance
  int min_circle_spots = 8;
  /// Intersections: angle to a right angle, and how near to a line's end counts as its end.
  double intersection_max_angle_deg = 15;
  double intersection_end_tolerance_m = 0.25;
  double intersection_max_extension_m = 0.35;  ///< how far beyond a line's end it may lie
  /// A line passing this near the centre circle's centre is the halfway line: X intersections.
  double circle_line_max_offset_m = 0.15;
  /// Penalty mark: a cluster of loose spots within this size, with nothing else around it.
  double penalty_mark_max_extent_m = 0.22;
  double penalty_mark_clear_radius_m = 0.25;
  /// Farther away the scan lines are too sparse to tell a mark from a piece of line.
  double penalty_mark_max_distance_m = 3.5;
  /// Share of the pixels within the mark's size that may be darker than the carpet around it by
  /// min_spot_contrast (a ball's black patches are; a painted cross has none).
  double penalty_mark_max_dark_fraction = 0.08;
  int min_penalty_mark_spots = 4;
  /// A mark whose image centre lies within this × a detected ball's image radius of the ball's
  /// centre is the ball (or hidden under it): the pipeline drops it once the ball is detected (a
  /// ball whose black patches a dim hall's glare lifts to the carpet's gray passes the dark test
  /// above). 0: never.
  double penalty_mark_ball_radii = 1.0;

  bool operator==(const FieldLineParams&) const = default;
  static FieldLineParams load(const std::string& path);
  static FieldLineParams loadDefault();
};

/// One crossing of a bright line by a scan line.
struct LineSpot {
  Eigen::Vector2d position_px = Eigen::Vector2d::Zero();  ///< middle of the bright run
  Eigen::Vector2d position_in_robot = Eigen::Vector2d::Zero();
  double width_px = 0;
  double expected_width_px = 0;  ///< of a line at this row crossing the scan line squarely
  bool vertical_scan = true;  ///< found by a vertical scan line (else a horizontal one)
};

/// Why a chain of spots did not become a line (only kept when asked for).
enum class LineRejectReason { kTooShort, kTooFewSpots, kOnCircle, kNotOnGround };
const char* lineRejectReasonName(LineRejectReason reason);

struct RejectedLine {
  LinePercept line;
  LineRejectReason reason = LineRejectReason::kTooShort;
};

/// Everything the field line stage produced.
struct FieldLineResult {
  FieldFeatures features;
  std::vector<LineSpot> spots;
  /// Ground points the centre circle was fitted to (robot frame).
  std::vector<Eigen::Vector2d> circle_points_in_robot;
  std::vector<RejectedLine> rejected;  ///< filled when `keep_rejected` is set
};

/// Colour-free field lines and features (paper 2.6): spots on vertical and horizontal scan lines,
/// chained and fitted into straight lines on the ground; the centre circle; L, T and X
/// intersections; penalty marks.
class FieldLineDetector {
 public:
  explicit FieldLineDetector(FieldLineParams params = {},
                             FieldDimensions field = FieldDimensions{});
  FieldLineResult run(const GrayView& image, const CameraModel& camera, const IgnoreMask& ignore,
                      bool keep_rejected = false) const;
  const FieldLineParams& params() const { return params_; }

 private:
  FieldLineParams params_;
  FieldDimensions field_;
};

}  // namespace colorfree
