#pragma once

#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/field_pose.h"

namespace colorfree {

/// What each pixel of the object map shows. Robots are kObjectRobotBase + index into
/// WorldState::robots; the observer's own body has its own label.
enum ObjectLabel : std::uint16_t {
  kObjectNone = 0,       ///< hall, walls, anything off the carpet
  kObjectCarpet = 1,
  kObjectLine = 2,       ///< field lines, circle, penalty marks
  kObjectGoal = 3,       ///< posts, crossbar, net
  kObjectBall = 4,
  kObjectOwnBody = 5,    ///< the observer's own body
  kObjectRobotBase = 16, ///< kObjectRobotBase + i is robot i
};

/// Per-pixel labels of one rendered frame, rows top-down, same size as the image.
struct ObjectMap {
  int width = 0;
  int height = 0;
  std::vector<std::uint16_t> labels;

  std::uint16_t at(int x, int y) const { return labels[static_cast<std::size_t>(y) * width + x]; }
};

/// The truth about one robot other than the observer.
struct RobotTruth {
  int index = 0;                 ///< stable id within the scenario
  FieldPose pose;                ///< ground point and facing on the field
  double speed_mps = 0;          ///< walking speed over the ground
  double walk_direction_rad = 0; ///< direction of travel on the field
  double turn_rate_radps = 0;
  std::string posture = "standing";  ///< standing | walking | turning
  double jersey_gray = 0.5;      ///< 0 black .. 1 white
};

/// The truth about the ball.
struct BallTruth {
  bool present = false;
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();  ///< centre, field frame
  Eigen::Vector3d velocity_mps = Eigen::Vector3d::Zero();
  double radius_m = 0.05;
};

/// The camera that took the frame: model relative to the observer's ground frame, and pose on
/// the field.
struct CameraTruth {
  std::string name;                      ///< "top" or "bottom"
  CameraModel model;                     ///< intrinsics + camera_to_robot (robot = observer)
  Eigen::Isometry3d camera_to_field = Eigen::Isometry3d::Identity();
};

/// Everything true about one rendered frame. Filled by sim/, read by groundtruth/. Never seen by
/// perception/.
struct WorldState {
  int frame_index = 0;
  double time_s = 0;
  FieldPose observer;              ///< observer's ground point on the field
  double observer_head_yaw_rad = 0;
  double observer_head_pitch_rad = 0;
  CameraTruth camera;
  std::vector<RobotTruth> robots;  ///< the other robots
  BallTruth ball;
  ObjectMap object_map;
};

/// Field frame ← observer's robot frame, from the observer's pose.
Eigen::Isometry3d robotToField(const FieldPose& observer);

}  // namespace colorfree
