#include "colorfree/groundtruth/matching.h"

#include <algorithm>

namespace colorfree {

Matching matchOneToOne(int truth_count, int percept_count, std::vector<MatchCandidate> candidates) {
  Matching m;
  m.truth_to_percept.assign(truth_count, -1);
  m.percept_to_truth.assign(percept_count, -1);
  std::sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) {
    if (a.cost != b.cost) return a.cost < b.cost;
    if (a.truth != b.truth) return a.truth < b.truth;
    return a.percept < b.percept;
  });
  for (const auto& c : candidates) {
    if (m.truth_to_percept[c.truth] >= 0 || m.percept_to_truth[c.percept] >= 0) continue;
    m.truth_to_percept[c.truth] = c.percept;
    m.percept_to_truth[c.percept] = c.truth;
  }
  return m;
}

std::optional<double> ballMatchCost(const BallInImage& truth, const Eigen::Vector2d& centre_px,
                                    const ScoringParams& params) {
  if (!truth.in_view) return std::nullopt;
  const double allowed =
      std::max(params.ball_match_radius_fraction * truth.radius_px, params.ball_match_min_px);
  const double d = (centre_px - truth.centre_px).norm();
  if (d > allowed) return std::nullopt;
  return d / allowed;
}

std::optional<double> robotMatchCost(const RobotInImage& truth, const PixelBox& box,
                                     const std::optional<Eigen::Vector2d>& feet_in_field,
                                     const ScoringParams& params) {
  if (!truth.in_view) return std::nullopt;
  const double iou = boxIou(truth.box, box);
  if (iou >= params.robot_match_min_iou) return 1 - iou;
  if (feet_in_field && params.robot_match_max_feet_distance_m > 0) {
    const double d = (*feet_in_field - truth.position_in_field).norm();
    if (d <= params.robot_match_max_feet_distance_m) {
      return 1 + d / params.robot_match_max_feet_distance_m;
    }
  }
  return std::nullopt;
}

}  // namespace colorfree
