#include "colorfree/groundtruth/world_state.h"

namespace colorfree {

Eigen::Isometry3d robotToField(const FieldPose& observer) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(observer.x_m, observer.y_m, 0);
  t.linear() = Eigen::AngleAxisd(observer.heading_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return t;
}

}  // namespace colorfree
