#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <optional>
#include <string>
#include <vector>

namespace colorfree {

/// A box in the image, pixels, x right, y down; (x0, y0) top-left corner, (x1, y1) bottom-right.
struct PixelBox {
  double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  double width() const { return x1 - x0; }
  double height() const { return y1 - y0; }
  Eigen::Vector2d centre() const { return {(x0 + x1) / 2, (y0 + y1) / 2}; }
};

/// The area two boxes share.
inline double boxIntersectionArea(const PixelBox& a, const PixelBox& b) {
  const double ix = std::max(0.0, std::min(a.x1, b.x1) - std::max(a.x0, b.x0));
  const double iy = std::max(0.0, std::min(a.y1, b.y1) - std::max(a.y0, b.y0));
  return ix * iy;
}

/// The fraction of a's area inside b (0 when a is empty).
inline double boxInsideFraction(const PixelBox& a, const PixelBox& b) {
  const double area = a.width() * a.height();
  return area > 0 ? boxIntersectionArea(a, b) / area : 0.0;
}

/// Intersection over union of two boxes (0 when both are empty).
inline double boxIou(const PixelBox& a, const PixelBox& b) {
  const double inter = boxIntersectionArea(a, b);
  const double uni = a.width() * a.height() + b.width() * b.height() - inter;
  return uni > 0 ? inter / uni : 0.0;
}

/// A ball candidate from the proposal stage.
struct BallProposal {
  Eigen::Vector2d centre_px = Eigen::Vector2d::Zero();
  double radius_px = 0;
  double response = 0;  ///< proposal strength, larger is stronger
};

/// A detected ball.
struct BallPercept {
  /// In the image at the frame's time: where a rolling shutter read the ball's row early or late
  /// while the camera turned (CameraModel::rollingShutterShiftPx), that share of the shift is out.
  Eigen::Vector2d centre_px = Eigen::Vector2d::Zero();
  double radius_px = 0;
  double confidence = 0;                          ///< classifier output in [0, 1]
  std::optional<Eigen::Vector2d> position_in_robot;  ///< ball centre on the ground, robot frame
};

/// A robot candidate from the proposal stage.
struct RobotProposal {
  PixelBox box;
  Eigen::Vector2d feet_px = Eigen::Vector2d::Zero();  ///< the robot's ground point in the image
  /// A piece of a row of feet points wider than several robots (a field line or the field's edge
  /// with whatever stands behind it above, split into robot-wide boxes; the proposer's
  /// defer_width_factor): placed by the split, not by a robot's feet.
  bool wide_group = false;
};

/// Whether a robot candidate's feet point lies in the lower part of a nearer robot's box: in its
/// column, more than 0.1 and less than `lower_part_fraction` of its height above its feet, where
/// that robot's knee, crotch or hand would be (a NAO's hands hang at about 0.37 of its height), or
/// the feet of a robot beside or behind it.
inline bool feetInLowerPart(const Eigen::Vector2d& feet_px, const RobotProposal& nearer,
                            double lower_part_fraction) {
  const double h = nearer.box.height();
  return feet_px.x() > nearer.box.x0 && feet_px.x() < nearer.box.x1 &&
         feet_px.y() < nearer.feet_px.y() - 0.1 * h &&
         feet_px.y() > nearer.feet_px.y() - lower_part_fraction * h;
}

/// A robot candidate the proposal stage held back: its feet point lies in the lower part of
/// nearer proposals' boxes, where that robot's knee or hand would be. It is another robot (beside
/// or behind) only where none of those nearer boxes holds a robot.
struct HeldBackRobotProposal {
  RobotProposal proposal;
  std::vector<int> nearer;  ///< the nearer proposals' indices
};

/// Which side of a robot a region shows, as OriNet classifies it.
enum class RobotSide { kFront, kBack, kSide };

/// Orientation of a detected robot relative to the observer's robot frame.
struct RobotOrientation {
  double angle_rad = 0;     ///< facing direction in the observer's robot frame, (-π, π]
  bool facing_known = false;  ///< true: perceived; false: only the axis (semi-perceived)
};

/// A detected robot.
struct RobotPercept {
  PixelBox box;
  Eigen::Vector2d feet_px = Eigen::Vector2d::Zero();
  double confidence = 0;
  /// The robot's ground point (between its feet), robot frame (see robotGroundPoint).
  std::optional<Eigen::Vector2d> position_in_robot;
  std::optional<RobotOrientation> orientation_raw;       ///< this frame's estimate
  std::optional<RobotOrientation> orientation_filtered;  ///< after the circular median filter
  int track_id = -1;  ///< association over frames, -1 when not tracked
};

/// A field line segment.
struct LinePercept {
  Eigen::Vector2d start_px = Eigen::Vector2d::Zero(), end_px = Eigen::Vector2d::Zero();
  Eigen::Vector2d start_in_robot = Eigen::Vector2d::Zero(), end_in_robot = Eigen::Vector2d::Zero();
};

enum class IntersectionType { kL, kT, kX };

struct IntersectionPercept {
  IntersectionType type = IntersectionType::kL;
  Eigen::Vector2d position_px = Eigen::Vector2d::Zero();
  Eigen::Vector2d position_in_robot = Eigen::Vector2d::Zero();
  /// For L and T: the direction of the stem/arms in the robot frame, unit vectors.
  Eigen::Vector2d direction1_in_robot = Eigen::Vector2d::UnitX();
  Eigen::Vector2d direction2_in_robot = Eigen::Vector2d::UnitY();
};

struct CircleMarkPercept {
  Eigen::Vector2d centre_in_robot = Eigen::Vector2d::Zero();
  Eigen::Vector2d centre_px = Eigen::Vector2d::Zero();
};

/// Field lines and features of one frame.
struct FieldFeatures {
  std::vector<LinePercept> lines;
  std::vector<IntersectionPercept> intersections;
  std::optional<CircleMarkPercept> centre_circle;
  std::vector<CircleMarkPercept> penalty_marks;
};

}  // namespace colorfree
