#pragma once

#include <optional>
#include <string>
#include <vector>

#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/cnn/classifier.h"
#include "colorfree/perception/field_dimensions.h"
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
  /// A proposal from a wide row of feet points (RobotProposal::wide_group: mostly a field line
  /// with the background above it) becomes a percept only at this robot probability or more.
  double min_wide_group_confidence = 0.9;
  /// Such a piece is split off where the row's width says, not where a robot stands: one RobotNet
  /// scores from wide_group_min_shift_confidence to under min_wide_group_confidence is looked at
  /// again moved sideways by -2, -1, 1 and 2 times wide_group_shift_width_fraction of its width,
  /// and the best-scored of the five stays (shiftWidePieces; 0: never).
  double wide_group_shift_width_fraction = 0.125;
  double wide_group_min_shift_confidence = 0.2;
  /// A box RobotNet scores from mirror_min_confidence to under mirror_max_confidence is looked at
  /// mirrored left to right too, and its score is the mean of the two looks (RobotNet learnt from
  /// mirrored samples: a robot mirrored is a robot, and an unsure look is seldom unsure the same
  /// way twice). Not where the image's left, right or bottom border cuts the box (near robots:
  /// RobotNet rejected their mirrored looks). Equal bounds: never.
  double mirror_min_confidence = 0.3;
  double mirror_max_confidence = 0.8;
  /// A box at least this many times RobotNet's patch width (a near robot) is looked at by area
  /// resampling too (each sample the mean of the pixels under it), and its score is the mean of
  /// that look and the bilinear one, before the mirrored look: read bilinearly alone, such a box is
  /// sampled at one pixel in every several, and a move of a pixel or two changes what the net
  /// sees. Not where the image's left, right or bottom border cuts the box (as for the mirrored
  /// look). 0: never.
  double area_min_patch_widths = 6;
  /// A held-back candidate behind a nearer box RobotNet accepted is a robot standing behind that
  /// one (its feet at the nearer robot's knees or hands in the image), or the nearer robot's own
  /// knee, crotch or hand. It is classified too and takes part in the choice of percepts at this
  /// robot probability or more, unless another box RobotNet accepted lies max_inside_fraction
  /// inside its box (its patch then holds that robot, not one standing at its feet point, and the
  /// robot would become its part), or it overlaps an accepted box it stands behind by more than
  /// max_overlap_iou (it is that robot's knee or hand, which RobotNet may score higher than the
  /// robot). 1: such candidates are not classified.
  double min_behind_robot_confidence = 0.97;
  /// An accepted box whose feet point lies in the lower part of a nearer accepted box (up to this
  /// fraction of its height above its feet: feetInLowerPart; the proposer's
  /// own_body_height_fraction) stays only from min_behind_robot_confidence too, wherever the
  /// proposer put it: it is that robot's knee or hand, or a robot behind it. Above that part, a
  /// box of at least min_behind_robot_confidence max_inside_fraction inside a larger accepted one
  /// is a robot behind it, not its part (keptRobotBoxes); and an accepted box inside a held-back
  /// candidate's box with its feet in that part of it is its knee or hand, which does not shut
  /// it out as a nearer robot's body would. 0: none of these tests.
  double behind_lower_part_fraction = 0.4;
  /// With RobotBehindNet: a box inside a nearer robot's (a held-back candidate behind an accepted
  /// robot, or an accepted box whose feet point lies inside a nearer accepted box) that it scores
  /// under this is no robot, whatever RobotNet says; from this on RobotNet's score stands.
  /// 0: never.
  double behind_net_veto_confidence = 0.5;
  /// Shins below an accepted robot's feet (feetOnShins): in backlit light a robot's knees, in their
  /// own shade, can have the carpet's gray over more than a run's gap, and the proposal's feet
  /// stand at the knees or thighs, its box too high. The lit stretch below the feet at most this
  /// fraction of the robot's height away is looked for (0: never).
  double shin_gap_height_fraction = 0.10;
  /// ... on scan lines every 2 px within this fraction of the robot's width left and right of the
  /// feet point. A scan line's stretch counts when lit (brighter than the carpet beside the robot
  /// by max(shin_min_jump_gray, shin_jump_ratio × the carpet)), of a shin's height (below) at
  /// its lower end, with carpet below it, and lit shin_beside_width_factor robot widths left or
  /// right on at most half its rows (widths of the robot the percept's feet point stands for; a
  /// line runs on, legs end; so does a nearer robot's body), and lit on at least
  /// shin_min_fill_fraction of its rows (a shin is lit throughout; a field line below the robot
  /// with the carpet's noise pixels lit around it is not).
  double shin_reach_width_fraction = 0.6;
  double shin_min_jump_gray = 16;
  double shin_jump_ratio = 0.18;
  double shin_beside_width_factor = 0.8;
  double shin_min_fill_fraction = 0.6;
  /// A shin is shin_min_height_fraction to shin_max_height_fraction of the robot's height tall;
  /// unlit rows inside it up to max(shin_max_gap_px, shin_max_gap_height_fraction of the height),
  /// as inside the proposer's runs (its max_gap_px, max_gap_height_fraction): more end it.
  double shin_min_height_fraction = 0.1;
  double shin_max_height_fraction = 0.45;
  int shin_max_gap_px = 3;
  double shin_max_gap_height_fraction = 0.04;
  /// The shins need at least 3 such scan lines spanning this fraction of the robot's width, their
  /// lower ends within max(3 px, this fraction of the height) (interquartile range: feet stand on
  /// flat ground; the ball's lower edge is round).
  double shin_min_span_width_fraction = 0.4;
  double shin_max_spread_height_fraction = 0.04;
  /// RobotFeetNet (moveFeet): a box RobotNet accepted is moved down (up) by
  /// feet_step_height_fraction of the robot's height while RobotFeetNet gives at least
  /// feet_min_confidence that the robot's feet lie lower (higher) than the box's, up to
  /// feet_max_steps times, never back, and never out of the image's rows (0 steps: never; so
  /// without the net). Boxes the image's top or bottom row cuts, and boxes whose feet point lies
  /// in a nearer accepted box (that robot hides the feet, or the box is its part), stay.
  double feet_min_confidence = 0.6;
  double feet_step_height_fraction = 0.05;
  int feet_max_steps = 6;
  /// A proposal RobotNet scores from feet_search_min_confidence to under min_confidence (not a
  /// wide group's piece) is moved to its robot's feet by RobotFeetNet as an accepted box is, and
  /// looked at there: from feet_search_accept_confidence it stays at its new place (a robot whose
  /// shaded legs the carpet's gray hides, proposed at its knees). Such a box is not moved again;
  /// it goes where its feet then lie in a nearer accepted box's lower part (that robot's leg), and
  /// it yields to a box accepted at its first look that overlaps it (IoU over max_overlap_iou) or
  /// holds it (max_inside_fraction). feet_search_min_confidence >= min_confidence: never.
  double feet_search_min_confidence = 0.05;
  double feet_search_accept_confidence = 0.97;
  /// The robot's ground point (between its feet: the pose's position) lies this far beyond its
  /// feet point, the nearest edge of its feet in the image, along the line of sight (m).
  double feet_to_centre_m = 0.07;
  /// A percept whose feet point lies below a detected ball's top and within ball_feet_radii x
  /// the ball's image radius of its centre, RobotNet not above ball_feet_max_confidence, stood
  /// its box on the ball: it is looked at again with its feet at the ball's top (a robot behind
  /// the ball) and stays there from min_held_back_confidence; otherwise it was the ball with what
  /// stands behind it and goes (see RobotDetector::liftOffBalls; 0 radii: never).
  double ball_feet_radii = 1.5;
  double ball_feet_max_confidence = 1.0;
  /// Tracked robots (the caller's RobotTracks, seen in at least track_prior_min_hits frames): a
  /// box whose ground point lies within track_prior_distance_m of one has its RobotNet odds
  /// multiplied by this for every bar and rule (a robot seen there a moment ago is likely still
  /// there; 1: off). `confidences` stay RobotNet's own.
  double track_prior_odds = 2.0;
  int track_prior_min_hits = 2;
  double track_prior_distance_m = 0.3;

  bool operator==(const RobotDetectorParams&) const = default;
  static RobotDetectorParams load(const std::string& path);
  static RobotDetectorParams loadDefault();
};

/// Which of the boxes RobotNet accepted (`confidence` >= min_confidence) become percepts, most
/// confident first: a box overlapping a kept one by more than max_overlap_iou is dropped, and a
/// box lying max_inside_fraction inside a larger kept one is a part of it (hand, arm) and dropped
/// even when it is the more confident, but for one of at least min_behind_robot_confidence whose
/// lower edge stands more than behind_lower_part_fraction of the larger box's height above that
/// box's lower edge (a robot behind a near one, whose box reaches round it). Indices into `boxes`.
std::vector<int> keptRobotBoxes(const std::vector<PixelBox>& boxes,
                                const std::vector<float>& confidence,
                                const RobotDetectorParams& params);

/// The proposal box as RobotNet's patch.
cnn::PatchBox robotPatchBox(const RobotProposal& proposal);

/// A robot's ground point in the robot frame: the feet point's on the ground, moved
/// `feet_to_centre_m` farther from the camera. Empty above the horizon.
std::optional<Eigen::Vector2d> robotGroundPoint(const CameraModel& camera,
                                                const Eigen::Vector2d& feet_px,
                                                double feet_to_centre_m);

/// The percept moved down to its shins when a robot's legs stand below its feet point, a knee's gap
/// away (see shin_gap_height_fraction): the feet at the shins' median lower end, the box scaled by
/// the expected heights' ratio and centred on the shins. Empty when there are none.
std::optional<RobotPercept> feetOnShins(const GrayView& image, const CameraModel& camera,
                                        const RobotPercept& percept,
                                        const RobotDetectorParams& params,
                                        const FieldDimensions& field);

/// The box moved by `dir` steps of `step_height_fraction` of the robot's expected height at its
/// feet point (down for positive), scaled about the feet by the expected heights' ratio. Empty
/// where no robot can stand.
std::optional<RobotProposal> feetMoved(const RobotProposal& box, const CameraModel& camera,
                                       double step_height_fraction, int dir,
                                       const FieldDimensions& field);
/// The box with its feet point moved to `feet`, scaled about the feet by the expected heights'
/// ratio. Empty where no robot can stand.
std::optional<RobotProposal> feetMovedTo(const RobotProposal& box, const CameraModel& camera,
                                         const Eigen::Vector2d& feet, const FieldDimensions& field);

/// Classifies robot proposals with RobotNet (24×24, paper 2.3) and turns the accepted ones into
/// percepts with their ground point in the robot frame. With RobotFeetNet (24×24: the feet row
/// right, lower or higher than the box's) the accepted boxes' feet are moved to the robot's. With
/// RobotBehindNet (RobotNet's shape, trained with the boxes inside nearer robots' boxes as well)
/// a box inside a nearer robot's that it rejects is no robot (a robot behind it, or its hand, arm
/// or knee, which RobotNet takes for robots; see behind_net_veto_confidence).
class RobotDetector {
 public:
  RobotDetector(RobotDetectorParams params, cnn::Classifier robot_net, FieldDimensions field = {},
                std::optional<cnn::Classifier> feet_net = std::nullopt,
                std::optional<cnn::Classifier> behind_net = std::nullopt);
  /// The shipped parameters, RobotNet, RobotFeetNet and RobotBehindNet
  /// (perception/models/robot_net.*, robot_feet_net.*, robot_behind_net.*).
  static RobotDetector loadDefault();
  /// `confidences` (optional) gets RobotNet's output for every proposal, in order.
  std::vector<RobotPercept> run(const GrayView& image, const CameraModel& camera,
                                const std::vector<RobotProposal>& proposals,
                                std::vector<float>* confidences = nullptr) const;
  /// The same, and then the held-back candidates: those none of whose nearer proposals RobotNet
  /// accepted (what a box without a robot seemed to hide is free), accepted from
  /// min_held_back_confidence; the others (behind a robot) as min_behind_robot_confidence says.
  /// `classified` (optional) gets every proposal RobotNet saw: `proposals`, then those held-back
  /// ones; `confidences` RobotNet's output for each (RobotBehindNet's veto aside).
  /// `tracked_in_robot` (optional): the ground points of the robots the caller tracks (see
  /// track_prior_odds).
  std::vector<RobotPercept> run(const GrayView& image, const CameraModel& camera,
                                const std::vector<RobotProposal>& proposals,
                                const std::vector<HeldBackRobotProposal>& held_back,
                                std::vector<RobotProposal>* classified,
                                std::vector<float>* confidences = nullptr,
                                const std::vector<Eigen::Vector2d>* tracked_in_robot = nullptr) const;
  /// Once the ball is detected: each percept whose feet point lies on a ball (see
  /// ball_feet_radii, ball_feet_max_confidence) is looked at again by RobotNet with its feet at
  /// the ball's top; it stays there (box, feet, confidence, ground point) when RobotNet gives that
  /// look min_held_back_confidence, and goes otherwise. The others stay as they are.
  std::vector<RobotPercept> liftOffBalls(const GrayView& image, const CameraModel& camera,
                                         const std::vector<RobotPercept>& robots,
                                         const std::vector<BallPercept>& balls) const;

 private:
  /// The boxes `which` of `boxes` moved to their robots' feet (RobotFeetNet, see
  /// feet_min_confidence), all of a step in one batch; `robot_net_patches` holds RobotNet's input
  /// for every box as it was. Only with the net and feet_max_steps > 0.
  void moveFeet(const GrayView& image, const CameraModel& camera, std::vector<RobotProposal>& boxes,
                const std::vector<int>& which, const std::vector<float>& robot_net_patches) const;
  /// `net`'s (RobotNet's or RobotBehindNet's) robot probabilities of the `count` inputs in
  /// `patches`, those of `boxes`, with the area look at near boxes (see area_min_patch_widths) and
  /// then the mirrored look where it is unsure (see mirror_min_confidence), appended to `robot`.
  void score(const cnn::Classifier& net, const GrayView& image, const RobotProposal* boxes,
             const float* patches, std::size_t count, std::vector<float>& robot) const;
  /// The pieces of wide groups among the first `count` of `boxes` moved sideways to where RobotNet
  /// scores them best (see wide_group_shift_width_fraction), with their scores in `robot` and their
  /// RobotNet inputs in `patches`, all in one batch.
  void shiftWidePieces(const GrayView& image, std::vector<RobotProposal>& boxes, std::size_t count,
                       std::vector<float>& robot, std::vector<float>& patches) const;
  /// The first `count` of `boxes` RobotNet rejected but not far below min_confidence, moved to
  /// their robots' feet and looked at again (see feet_search_min_confidence): those kept at their
  /// new places, with their scores in `robot` and their RobotNet inputs in `patches`, are marked in
  /// `searched`.
  void searchFeet(const GrayView& image, const CameraModel& camera,
                  std::vector<RobotProposal>& boxes, std::size_t count, std::vector<float>& robot,
                  std::vector<float>& patches, std::vector<bool>& searched) const;

  RobotDetectorParams params_;
  cnn::Classifier net_;
  FieldDimensions field_;
  std::optional<cnn::Classifier> feet_net_;
  std::optional<cnn::Classifier> behind_net_;
};

}  // namespace colorfree
