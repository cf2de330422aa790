#include "colorfree/perception/orientation/orientation_filter.h"

#include <array>
#include <cmath>
#include <numbers>

namespace colorfree {

RobotOrientation orientationFromLine(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                     RobotSide side, const Eigen::Vector2d& robot_position) {
  const Eigen::Vector2d dir = (b - a).normalized();
  RobotOrientation o;
  if (side == RobotSide::kSide) {
    o.angle_rad = wrapAngle(std::atan2(dir.y(), dir.x()));
    o.facing_known = false;
    return o;
  }
  Eigen::Vector2d normal(-dir.y(), dir.x());
  // The normal that points from the robot towards the observer (the origin).
  if (normal.dot(-robot_position) < 0) normal = -normal;
  if (side == RobotSide::kBack) normal = -normal;
  o.angle_rad = wrapAngle(std::atan2(normal.y(), normal.x()));
  o.facing_known = true;
  return o;
}

RobotOrientation orientationFromSideLine(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                         bool faces_left, const Eigen::Vector2d& robot_position) {
  Eigen::Vector2d dir = (b - a).normalized();
  // The observer's left at the robot: the line of sight turned by +90°.
  const Eigen::Vector2d left(-robot_position.y(), robot_position.x());
  if ((dir.dot(left) > 0) != faces_left) dir = -dir;
  return RobotOrientation{wrapAngle(std::atan2(dir.y(), dir.x())), true};
}

bool classesConsistent(const std::vector<RobotSide>& classes) {
  std::array<int, 3> count{};
  for (RobotSide c : classes) {
    if (++count[static_cast<int>(c)] > 1) return false;
  }
  return true;
}

void keepMostConfidentOfEachClass(std::vector<RobotOrientation>& orientations, std::vector<RobotSide>& classes,
                                  const std::vector<float>& confidences) {
  const std::size_t n = classes.size();
  std::vector<RobotOrientation> kept_orientations;
  std::vector<RobotSide> kept_classes;
  for (std::size_t i = 0; i < n; ++i) {
    bool strongest = true;
    for (std::size_t j = 0; j < n && strongest; ++j) {
      if (j == i || classes[j] != classes[i]) continue;
      strongest = confidences[j] < confidences[i] || (confidences[j] == confidences[i] && i < j);
    }
    if (!strongest) continue;
    kept_orientations.push_back(orientations[i]);
    kept_classes.push_back(classes[i]);
  }
  orientations = std::move(kept_orientations);
  classes = std::move(kept_classes);
}

std::optional<RobotOrientation> combineLineOrientations(
    const std::vector<RobotOrientation>& orientations, const std::vector<RobotSide>& classes) {
  if (orientations.empty() || orientations.size() != classes.size()) return std::nullopt;
  if (!classesConsistent(classes)) return std::nullopt;
  // Every facing-known estimate must agree on the facing; otherwise the estimate is not trusted.
  std::optional<RobotOrientation> facing;
  for (std::size_t i = 0; i < classes.size(); ++i) {
    if (!orientations[i].facing_known) continue;
    if (facing && std::abs(wrapAngle(facing->angle_rad - orientations[i].angle_rad)) > std::numbers::pi / 4) {
      return std::nullopt;
    }
    if (!facing) facing = orientations[i];
  }
  if (!facing) return orientations.front();
  // The first line (the best voted) gives the most precise direction: when it is a side line, its
  // axis with the facing the front or back line gives.
  if (classes.front() == RobotSide::kSide) {
    const double axis = orientations.front().angle_rad;
    for (double a : {axis, wrapAngle(axis + std::numbers::pi)}) {
      if (std::abs(wrapAngle(a - facing->angle_rad)) <= std::numbers::pi / 4) return RobotOrientation{a, true};
    }
  }
  return facing;
}

std::optional<RobotOrientation> updateOrientationTrack(OrientationTrack& track,
                                                       const std::optional<RobotOrientation>& sample,
                                                       double time_s,
                                                       const OrientationFilterParams& params) {
  while (!track.samples.empty() && time_s - track.samples.front().time_s > params.expiry_s) {
    track.samples.pop_front();
  }
  if (sample) track.samples.push_back({time_s, *sample});
  while (static_cast<int>(track.samples.size()) > params.buffer_size) track.samples.pop_front();
  if (track.samples.empty()) return std::nullopt;

  std::vector<double> facing, all;
  for (const auto& s : track.samples) {
    all.push_back(s.orientation.angle_rad);
    if (s.orientation.facing_known) facing.push_back(s.orientation.angle_rad);
  }
  RobotOrientation out;
  if (2 * facing.size() >= all.size()) {
    out.angle_rad = *circularMedian(facing);
    out.facing_known = true;
  } else {
    out.angle_rad = *circularMedian(all, /*axial=*/true);
    out.facing_known = false;
  }
  return out;
}

}  // namespace colorfree
