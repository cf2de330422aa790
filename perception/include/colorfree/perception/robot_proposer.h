#pragma once

#include <optional>
#include <string>
#include <vector>

#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/field_dimensions.h"
#include "colorfree/perception/high_contrast.h"
#include "colorfree/perception/ignore_regions.h"
#include "colorfree/perception/image.h"
#include "colorfree/perception/percepts.h"

namespace colorfree {

/// Parameters of the robot proposal stage (perception/params/robot_proposer.yaml).
struct RobotProposerParams {
  int column_step_px = 4;  ///< distance between two scan lines inside a high-contrast column
  /// A pixel leaves the carpet when it is brighter than the running carpet luminance by more than
  /// max(min_jump_gray, jump_ratio × carpet luminance) (gray levels).
  double min_jump_gray = 16;
  double jump_ratio = 0.18;
  /// ... and by more than this many times the frame's pixel noise (pixelNoiseGray): on a noisy
  /// frame (a dark hall's high gain) single carpet pixels would pass for the robot's, and the runs
  /// they start would swallow the feet above them. 0: no such bound.
  double noise_jump_factor = 2.5;
  /// A frame with at least this much pixel noise (gray levels) is scanned on a copy whose rows are
  /// averaged over smooth_width_px pixels (odd: the pixel and as many on each side; its noise, for
  /// the jump, divided by the square root of that). 0: never.
  double smooth_min_noise_gray = 24;
  int smooth_width_px = 3;
  /// Carpet pixels are averaged into the running carpet luminance with this weight.
  double carpet_update_weight = 0.25;
  /// After a darker stretch (a shadow, the ball's black patches) the reference a robot must be
  /// brighter than falls to the running carpet luminance by at most this fraction per row.
  double carpet_dark_decay = 0.02;
  /// Uneven light: a wide band of carpet lit brighter than the carpet before it makes a run as a
  /// robot's legs would, and that run would end the scan line's stretch below the robot standing
  /// beyond it. A run whose lowest lit_band_height_fraction of the needed height is filled by no
  /// pixel brighter than the pixel this many expected robot widths to its left or right too (and
  /// none darker than the carpet) is such lit carpet: the scan goes on above its lower edge with
  /// the carpet's brightness taken from there. Only the lowest part: a far robot's legs have the
  /// field's bright boards and goals beside them higher up. 0: no such test.
  double lit_band_beside_width_factor = 1.0;
  double lit_band_height_fraction = 0.25;
  /// Carpet-like pixels tolerated inside a robot run (a joint, a seam): this many, or this
  /// fraction of the expected robot height when more; a longer gap ends the run.
  int max_gap_px = 3;
  double max_gap_height_fraction = 0.04;
  /// A stretch darker than the carpet just below the feet (their dark lower part, the contact
  /// shadow) up to this fraction of the expected robot height moves the feet point to its bottom.
  double feet_dark_height_fraction = 0.08;
  /// A run is a robot's lower body when it reaches at least this fraction of the expected pixel height
  /// of a robot whose feet are at its lower end (lines, the ball and shadows are shorter).
  double min_run_height_fraction = 0.4;
  /// ... and at least this fraction of the pixels up to that height must differ from the carpet
  /// (brighter than it, or darker: legs in shade).
  double min_fill_fraction = 0.6;
  /// Where the scan stretch starts at the lower edge of the image or the own body (the carpet
  /// unknown: the stretch may start on the ball cut by the border), a pixel brighter than the
  /// reference fills a run only when it is brighter by the jump than the pixel this many expected
  /// robot widths to its left or to its right too (the carpet beside the robot). 0: no such test.
  double beside_width_factor = 1.0;
  /// There the reference the robot must be brighter than starts at the darkest of the stretch's
  /// lowest pixel and the pixels beside_width_factor robot widths to its left and right: a near
  /// robot whose feet the border cuts starts on its own foot or shin, which would otherwise be
  /// the carpet and hide the legs above it. false: the lowest pixel alone.
  bool border_reference_beside = true;
  /// A lit stretch at a run's lower end no taller than this many field-line widths seen there,
  /// with more than the gap of unlit rows above it (carpet, or shade the run would take for legs)
  /// and lit pixels line_beside_width_factor expected robot widths to its left or right (a line
  /// runs on, feet end) is a field line in front of a shadow or a farther robot: the scan goes on
  /// above it. 0: no such test.
  double line_stripe_factor = 2.5;
  double line_beside_width_factor = 1.5;
  /// A robot's knee joint in its own shade (backlit: the lamp beyond the robot) can sit at the
  /// carpet's gray for longer than the run's gap. One gap up to this fraction of the expected
  /// height is bridged when the lit stretch at the run's lower end (the shins) is at least
  /// knee_min_lit_height_fraction of the height tall and has lit pixels
  /// line_beside_width_factor robot widths to its left or right on at most half of its rows
  /// (feet end within their robot's width; the carpet's lit side of a light edge runs on).
  /// 0: no knee gap (README "Robots and orientation", robot11 and robot14).
  double knee_gap_height_fraction = 0.10;
  double knee_min_lit_height_fraction = 0.10;
  /// With a knee gap: where only the bridged run makes a feet point, the point is a candidate of
  /// its own, grouped apart from the others, and the scan goes on as without the gap; up to this
  /// many such boxes are proposed besides the others (held back as they are), which stay those
  /// found without the gap. 0: bridged runs give feet points like any other (robot11's way, which
  /// moved other robots' boxes).
  int max_knee_proposals = 4;
  /// An accepted run whose object (pixels brighter or darker than the carpet one robot width
  /// beside them) ends within this fraction of the expected height above its feet, more than a
  /// gap of rows like that carpet above it, is no robot that hides what stands behind it (the
  /// ball in front of a robot, whose shadow lowered the reference so that the carpet above it
  /// filled the run): the scan goes on above it, and the feet points found there make candidates
  /// of their own, after all others, held back behind the boxes whose columns they stand in
  /// (0: one feet point per stretch, the lowest; README robot25).
  double short_object_height_fraction = 0.3;
  /// ... and at least this fraction tall (a field line's stripe is no such object).
  double short_object_min_height_fraction = 0.1;
  double min_expected_height_px = 10;  ///< robots smaller than this (far away) are not proposed
  /// A group of feet points whose ground point lies farther from the observer than this many
  /// carpet diagonals (the farthest two points of the carpet lie apart) stands off the field: no
  /// robot (0: no such test).
  double max_distance_carpet_diagonals = 1.0;
  /// Feet points of neighbouring scan lines join when their rows differ by at most this fraction
  /// of the expected height (plus 2 px).
  double join_height_fraction = 0.12;
  /// ... and when the columns between them are at most this fraction of the expected robot width
  /// (the gap between two legs).
  double join_gap_width_fraction = 0.45;
  /// A group narrower than this fraction of the expected robot width is dropped (a goal post's
  /// width is about 0.3 of it, so RobotNet still sees posts).
  double min_width_fraction = 0.2;
  /// A group wider than this many expected widths is split into robots side by side.
  double split_width_factor = 1.7;
  /// The boxes of a group wider than this many expected widths (a far field line, the field's
  /// edge against the wall: rows of boxes, rarely robots) come after every other candidate under
  /// the cap, so they do not take the places of far robots.
  double defer_width_factor = 2.5;
  /// A robot nearer than the lowest ground row the image shows (its feet below the image, the
  /// lower border across its body): a span of the lowest row whose pixels are brighter than the
  /// carpet beside them (the lower median of the pixels one to three robot widths left and right;
  /// gaps up to join_gap_width_fraction of a robot's width, at least min_fill_fraction of the span
  /// bright) wider than this many widths of a robot standing on that row. It is proposed as a
  /// robot whose box is as wide as the span, its feet below the image where a robot is that wide,
  /// after all other proposals. 0: no such proposals.
  double border_robot_min_width_factor = 1.25;
  /// ... whose pixels this many robot widths (of one standing on that row) above the lowest row
  /// still differ from that carpet (a field line along the border ends lower).
  double border_robot_rise_width_fraction = 0.3;
  /// ... and brighter than that carpet by this many of the scan's jumps (a robot's white body is
  /// far brighter; the carpet's own slope across the image, in bright light, is not).
  double border_robot_jump_factor = 1.25;
  double box_width_factor = 1.25;   ///< proposed box width in expected robot widths
  double box_height_factor = 1.08;  ///< proposed box height in expected robot heights
  double box_below_feet_fraction = 0.04;  ///< box bottom below the feet, in expected heights
  /// A feet point inside a nearer proposal's box up to this fraction of its height above its
  /// feet is that robot's knee, hip or hand (higher: a robot behind it). It is held back: the
  /// detector classifies it only when RobotNet finds no robot in any such nearer box.
  double own_body_height_fraction = 0.4;
  double max_overlap_iou = 0.45;  ///< of two proposals overlapping more, the one lower in the image stays
  int max_proposals = 16;
  int max_held_back = 6;  ///< candidates held back behind nearer proposals, at most

  bool operator==(const RobotProposerParams&) const = default;
  static RobotProposerParams load(const std::string& path);
  static RobotProposerParams loadDefault();
};

/// Why a scan-line run or a group did not become a proposal (only filled when asked for).
enum class RobotRejectReason {
  kRunTooShort,
  kTooNarrow,
  kTooFar,
  kAboveHorizon,
  kOverlap,
  kTooMany,
  kFieldLine,  ///< a field line in front of shade (see line_stripe_factor)
  kLitCarpet,  ///< carpet lit brighter than the carpet before it (see lit_band_beside_width_factor)
};
const char* robotRejectReasonName(RobotRejectReason reason);

struct RejectedRobotCandidate {
  Eigen::Vector2d feet_px = Eigen::Vector2d::Zero();
  RobotRejectReason reason = RobotRejectReason::kRunTooShort;
};

struct RobotProposals {
  std::vector<RobotProposal> proposals;
  /// Candidates in the lower part of nearer proposals' boxes (see own_body_height_fraction),
  /// lowest first, then the knee candidates among them (see max_knee_proposals).
  std::vector<HeldBackRobotProposal> held_back;
  /// Feet points (lower ends of long enough runs) found by the scan lines, for drawing.
  std::vector<Eigen::Vector2d> feet_points_px;
  std::vector<RejectedRobotCandidate> rejected;  ///< only with keep_rejected
};

/// Colour-free robot proposals (paper 2.3): vertical scan lines over the image columns with
/// high-contrast windows, walking up from the bottom of the looked-at region, follow the carpet's
/// luminance and find where a run of non-carpet pixels starts (a robot's feet). A run must be tall
/// enough for a robot whose feet are there (camera model); neighbouring feet points join into
/// groups whose width must suit a robot; each group (split when several robots stand side by
/// side) gives a box of the expected robot size above its feet. A robot cut by the lower image
/// border is proposed with its feet on the border (its box is then too small: out of scope for the
/// feet point). Fallen robots are out of scope (their runs are short; they are not proposed).
class RobotProposer {
 public:
  explicit RobotProposer(RobotProposerParams params = {}, FieldDimensions field = {});
  /// `pixel_noise_gray`: the frame's pixelNoiseGray(image, ignore) when the caller has it (the
  /// pipeline's Frame does); estimated here when absent.
  RobotProposals run(const GrayView& image, const CameraModel& camera, const IgnoreMask& ignore,
                     const ContrastRegions& regions, bool keep_rejected = false,
                     std::optional<double> pixel_noise_gray = std::nullopt) const;
  const RobotProposerParams& params() const { return params_; }

 private:
  RobotProposerParams params_;
  double robot_height_m_;
  double robot_width_m_;
  double line_width_m_;
  double carpet_diagonal_m_;
};

}  // namespace colorfree
