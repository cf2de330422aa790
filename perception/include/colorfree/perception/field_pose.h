#pragma once

#include <Eigen/Core>
#include <cmath>

namespace colorfree {

/// A robot's pose on the field: its ground point (between the feet, under the torso) and the
/// direction it faces, field coordinates (see FieldDimensions). The one definition shared by the
/// pose fit, the simulator and the ground truth.
struct FieldPose {
  double x_m = 0;
  double y_m = 0;
  double heading_rad = 0;

  /// A robot-frame point in the field frame.
  Eigen::Vector2d toField(const Eigen::Vector2d& point_in_robot) const {
    const double c = std::cos(heading_rad), s = std::sin(heading_rad);
    return {x_m + c * point_in_robot.x() - s * point_in_robot.y(),
            y_m + s * point_in_robot.x() + c * point_in_robot.y()};
  }
};

}  // namespace colorfree
