#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "colorfree/groundtruth/scoring_params.h"
#include "colorfree/groundtruth/truth_in_image.h"

namespace colorfree {

/// A candidate pair for one-to-one matching; lower cost is better.
struct MatchCandidate {
  int truth = 0;
  int percept = 0;
  double cost = 0;
};

/// The result of one-to-one matching: -1 where unmatched.
struct Matching {
  std::vector<int> truth_to_percept;
  std::vector<int> percept_to_truth;
};

/// Greedy one-to-one matching, cheapest pair first (ties: lower truth, then lower percept index).
Matching matchOneToOne(int truth_count, int percept_count, std::vector<MatchCandidate> candidates);

/// Cost of pairing a true ball with a detected centre: the centre distance over the allowed
/// distance max(fraction × true radius, min px), in [0, 1]; empty when farther than allowed.
std::optional<double> ballMatchCost(const BallInImage& truth, const Eigen::Vector2d& centre_px,
                                    const ScoringParams& params);

/// Cost of pairing a true robot with a detected box and feet point: 1 − IoU when the IoU passes,
/// else the feet distance on the ground over the allowed distance plus 1; empty when neither
/// passes. `feet_in_field` is the detected feet point on the field, when known.
std::optional<double> robotMatchCost(const RobotInImage& truth, const PixelBox& box,
                                     const std::optional<Eigen::Vector2d>& feet_in_field,
                                     const ScoringParams& params);

}  // namespace colorfree
