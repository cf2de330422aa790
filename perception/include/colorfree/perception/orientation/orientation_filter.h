#pragma once

#include <deque>
#include <optional>
#include <string>
#include <vector>

#include "colorfree/perception/orientation/geometry.h"
#include "colorfree/perception/percepts.h"

namespace colorfree {

/// The orientation a line and its class give: front — the robot faces across the line, towards
/// the observer's side; back — across the line, away from it; side — along the line, facing
/// unknown (semi-perceived). `line_*` and `robot_position` in the observer's robot frame.
RobotOrientation orientationFromLine(const Eigen::Vector2d& line_a, const Eigen::Vector2d& line_b,
                                     RobotSide side, const Eigen::Vector2d& robot_position);

/// The orientation a side line gives when OriNet also saw which way the robot faces along it:
/// towards the observer's left (`faces_left`, image left) or right. Facing known. `line_*` and
/// `robot_position` in the observer's robot frame.
RobotOrientation orientationFromSideLine(const Eigen::Vector2d& line_a, const Eigen::Vector2d& line_b,
                                         bool faces_left, const Eigen::Vector2d& robot_position);

/// The paper's consistency check: at most one region of each class.
bool classesConsistent(const std::vector<RobotSide>& classes);

/// A softer consistency check: of the regions that share a class, keeps only the one with the
/// highest `confidences` entry (the first of equals), in the given order; regions of different
/// classes are kept. Two orthogonal feet lines cannot both be a side, so one class of two is wrong:
/// the paper's check drops both, this keeps the region OriNet is surer of.
void keepMostConfidentOfEachClass(std::vector<RobotOrientation>& orientations, std::vector<RobotSide>& classes,
                                  const std::vector<float>& confidences);

/// Combines the orientations of one robot's classified line regions (the first line, the best
/// voted, first) into one estimate: every facing-known estimate (front, back, or a side line whose
/// facing OriNet saw) must agree within 45°, else the estimate is not trusted (empty); the first
/// facing-known one decides the facing; when the first line is a side line within 45° of that
/// facing, the estimate is its axis turned to the facing (the best-voted line is the most
/// precise); side lines without a facing give only the axis. Empty when the classes are
/// inconsistent or there is nothing.
std::optional<RobotOrientation> combineLineOrientations(
    const std::vector<RobotOrientation>& orientations, const std::vector<RobotSide>& classes);

/// Parameters of the per-robot orientation filter.
struct OrientationFilterParams {
  int buffer_size = 11;     ///< estimates kept (the paper's 11)
  double expiry_s = 1.0;    ///< the filtered value is dropped after this long without samples
};

/// The explicit state of one tracked robot's filter: the last estimates and when they came.
struct OrientationTrack {
  struct Sample {
    double time_s = 0;
    RobotOrientation orientation;
  };
  std::deque<Sample> samples;
};

/// Adds `sample` (if any) at `time_s` and returns the filtered orientation: the circular median
/// over the buffer. Facing-known samples decide when they are at least half of the buffer;
/// otherwise the axial median of all samples, facing unknown. Samples older than the expiry are
/// dropped first, so a track without new samples goes empty.
std::optional<RobotOrientation> updateOrientationTrack(OrientationTrack& track,
                                                       const std::optional<RobotOrientation>& sample,
                                                       double time_s,
                                                       const OrientationFilterParams& params);

}  // namespace colorfree
