#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>
#include <vector>

#include "colorfree/groundtruth/field_markings.h"
#include "colorfree/groundtruth/scoring_params.h"
#include "colorfree/groundtruth/world_state.h"
#include "colorfree/perception/percepts.h"

namespace colorfree {

/// Projects field points into the frame's image through CameraTruth::camera_to_field (optical
/// frame: x right, y down, z forward, as CameraModel) and the model's intrinsics.
class FrameProjector {
 public:
  explicit FrameProjector(const CameraTruth& camera);
  Eigen::Vector3d toCamera(const Eigen::Vector3d& point_in_field) const;
  /// Pixel of a point; empty when it is behind the near plane.
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& point_in_field) const;
  /// The visible part of a straight 3-D segment: clipped at the near plane, projected, clipped
  /// to the image rectangle. Empty when no part is in view.
  std::optional<std::pair<Eigen::Vector2d, Eigen::Vector2d>> segment(
      const Eigen::Vector3d& a_in_field, const Eigen::Vector3d& b_in_field) const;
  /// Like segment(), without the clipping to the image (only at the near plane).
  std::optional<std::pair<Eigen::Vector2d, Eigen::Vector2d>> segmentUnclipped(
      const Eigen::Vector3d& a_in_field, const Eigen::Vector3d& b_in_field) const;
  Eigen::Vector3d cameraPosition() const { return camera_to_field_.translation(); }
  int width() const { return intrinsics_.width_px; }
  int height() const { return intrinsics_.height_px; }
  bool inImage(const Eigen::Vector2d& p) const {
    return p.x() >= 0 && p.y() >= 0 && p.x() <= width() && p.y() <= height();
  }

 private:
  Eigen::Vector2d toPixel(const Eigen::Vector3d& c) const;
  CameraIntrinsics intrinsics_;
  Eigen::Isometry3d camera_to_field_;
  Eigen::Isometry3d field_to_camera_;
};

/// The true ball as the camera sees it.
struct BallInImage {
  bool in_view = false;  ///< in front of the camera and part of it inside the image
  Eigen::Vector2d centre_px = Eigen::Vector2d::Zero();  ///< centre of the projected outline
  double radius_px = 0;          ///< smallest circle about centre_px covering the outline
  double projected_area_px = 0;  ///< area of the whole projected outline (also outside the image)
  int visible_px = 0;            ///< ball pixels in the object map
  double visible_fraction = 0;   ///< visible_px / projected_area_px, at most 1
  double distance_m = 0;         ///< on the ground, from the observer
  Eigen::Vector2d position_in_field = Eigen::Vector2d::Zero();
  std::vector<Eigen::Vector2d> outline_px;
  bool should_detect = false;
};

/// One other robot as the camera sees it.
struct RobotInImage {
  int index = 0;
  bool in_view = false;
  PixelBox box;       ///< whole body, projected body box, clipped to the image
  PixelBox feet_box;  ///< ground up to the feet-region height, clipped to the image
  Eigen::Vector2d ground_px = Eigen::Vector2d::Zero();  ///< ground point (between the feet)
  Eigen::Vector2d left_foot_px = Eigen::Vector2d::Zero(), right_foot_px = Eigen::Vector2d::Zero();
  double projected_area_px = 0;  ///< area of the projected body's hull (also outside the image)
  int visible_px = 0;            ///< this robot's pixels in the object map
  int occluded_px = 0;           ///< hull pixels showing a nearer object
  double visible_fraction = 0;
  double distance_m = 0;       ///< on the ground, from the observer
  double heading_rel_rad = 0;  ///< facing relative to the line of sight; 0 = facing the camera
  RobotSide side_seen = RobotSide::kFront;
  double heading_in_observer_rad = 0;  ///< facing in the observer's robot frame
  Eigen::Vector2d position_in_field = Eigen::Vector2d::Zero();
  double speed_mps = 0;
  bool should_detect = false;
};

struct LineInImage {
  std::string name;
  bool circle = false;  ///< a piece of the centre circle
  Eigen::Vector2d start_px = Eigen::Vector2d::Zero(), end_px = Eigen::Vector2d::Zero();
  double visible_length_px = 0;  ///< length not hidden in the object map
};

struct PointFeatureInImage {
  IntersectionType type = IntersectionType::kL;  ///< for intersections
  Eigen::Vector2d position_px = Eigen::Vector2d::Zero();
  Eigen::Vector2d position_in_field = Eigen::Vector2d::Zero();
};

/// Field markings in view.
struct FieldInImage {
  std::vector<LineInImage> lines;          ///< straight lines in view (visible long enough)
  std::vector<LineInImage> circle_pieces;  ///< centre-circle chords in the image
  bool centre_circle_in_view = false;
  std::optional<Eigen::Vector2d> circle_centre_px;  ///< when in front of the camera
  std::vector<PointFeatureInImage> intersections;
  std::vector<PointFeatureInImage> penalty_marks;
};

/// Everything true about one frame, in the image.
struct FrameTruth {
  int frame_index = 0;
  BallInImage ball;
  bool ball_present = false;
  std::vector<RobotInImage> robots;  ///< every robot, in view or not (see in_view)
  FieldInImage field;
  FieldPose observer;
};

/// Computes the truth in the image from a world state. The object map may be empty: then
/// visibility counts only the image border (and the visible fractions assume no occlusion).
FrameTruth computeFrameTruth(const WorldState& world, const FieldMarkings& field,
                             const FieldDimensions& dims, const ScoringParams& params);

/// Angle wrapped into (-π, π].
double wrapAngle(double a);
/// Side of a robot a camera sees from its heading relative to the line of sight.
RobotSide sideSeen(double heading_rel_rad);
const char* robotSideName(RobotSide side);

/// Area of a simple polygon (absolute), and the part of it inside [0,w]×[0,h].
double polygonArea(const std::vector<Eigen::Vector2d>& polygon);
std::vector<Eigen::Vector2d> clipPolygonToRect(const std::vector<Eigen::Vector2d>& polygon,
                                               double w, double h);
/// Convex hull (Andrew's monotone chain), counter-clockwise in a y-down image.
std::vector<Eigen::Vector2d> convexHull(std::vector<Eigen::Vector2d> points);
bool insideConvex(const std::vector<Eigen::Vector2d>& hull, const Eigen::Vector2d& p);
double pointSegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                            const Eigen::Vector2d& b);
// boxIou: colorfree/perception/percepts.h.

}  // namespace colorfree
