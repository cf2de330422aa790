#pragma once

#include <Eigen/Core>
#include <cmath>
#include <optional>
#include <vector>

namespace colorfree {

/// Convex hull by Andrew's monotone chain. Returns the hull's vertices in counter-clockwise order
/// (in a frame with y up; clockwise on screen), starting from the lowest-x (then lowest-y) point,
/// without repeating the first; collinear points on the hull's edges are dropped. Fewer than three
/// distinct points come back as they are (sorted, deduplicated).
std::vector<Eigen::Vector2d> convexHull(std::vector<Eigen::Vector2d> points);

/// A straight line through two points, used as a hypothesis for the lower silhouette.
struct LineHypothesis {
  Eigen::Vector2d a = Eigen::Vector2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  int votes = 0;
  double length() const { return (b - a).norm(); }
  Eigen::Vector2d direction() const { return (b - a).normalized(); }
};

/// Whether `p` lies within `max_distance` of the line through `a` along the unit direction `u` and
/// projects within [-margin, length + margin] along it (the segment a .. a + length·u, extended).
inline bool nearSegment(const Eigen::Vector2d& a, const Eigen::Vector2d& u, double length,
                        const Eigen::Vector2d& p, double max_distance, double margin) {
  const Eigen::Vector2d ap = p - a;
  const double along = ap.dot(u);
  const double across = std::abs(ap.x() * u.y() - ap.y() * u.x());
  return across <= max_distance && along >= -margin && along <= length + margin;
}

/// Votes for the line through `a` and `b`: the number of `points` within `max_distance` of the
/// segment's infinite line whose projection falls within the segment extended by `margin` at
/// both ends.
int countLineVotes(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                   const std::vector<Eigen::Vector2d>& points, double max_distance,
                   double margin = 0);

/// The points voting for the line through `a` and `b` (within `max_distance` of it, projecting
/// within the segment extended by `margin`), ordered along a -> b, and with `max_gap` > 0 only
/// the longest contiguous run of them (no two consecutive voters more than `max_gap` apart along
/// the line; of runs with as many voters, the first).
std::vector<Eigen::Vector2d> lineVoters(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                        const std::vector<Eigen::Vector2d>& points,
                                        double max_distance, double margin, double max_gap);

/// Bounds for choosing the silhouette lines (units those of the points, e.g. metres on the
/// ground).
struct SilhouetteLineBounds {
  double vote_distance = 0.01;     ///< a point votes when this close to the line
  double min_length = 0.05;        ///< second line: shortest accepted
  double max_length = 0.30;        ///< second line: longest accepted
  double max_orthogonality_cos = 0.35;  ///< second line: |cos| of its angle to the first, at most
  double vote_margin = 0;          ///< a point votes when its projection is within this of the edge's ends
  /// Voters further apart than this along the line are two pieces, and only the piece with the
  /// most voters votes (a line through two separate objects, e.g. one foot's heel and the other's
  /// toe, is no edge); 0: no limit.
  double max_voter_gap = 0;
  /// Where the silhouette is seen from (the camera's ground point, e.g. the robot frame's
  /// origin). When set, only the hull edges facing it are candidates: the lower silhouette is
  /// the near side of the hull, the edge closing the hull behind it is no edge of the robot.
  std::optional<Eigen::Vector2d> viewpoint;
};

/// The paper's lines generator on silhouette points: every pair of consecutive hull vertices is a
/// candidate, validated by voting over all points (its ends are moved to its outermost voters;
/// with `max_voter_gap`, of its voters' longest contiguous run);
/// the best is the first line; the second is the
/// best-voted remaining candidate that meets the length bounds and is roughly orthogonal to it.
/// With a viewpoint only edges facing it count. Empty when there are fewer than two hull vertices
/// (or no edge faces the viewpoint).
struct SilhouetteLines {
  std::optional<LineHypothesis> first;
  std::optional<LineHypothesis> second;
};
SilhouetteLines findSilhouetteLines(const std::vector<Eigen::Vector2d>& points,
                                    const SilhouetteLineBounds& bounds);

/// Wraps an angle to (-π, π].
double wrapAngle(double angle_rad);

/// Circular median of angles: the sample minimising the sum of absolute angular distances to all
/// samples (ties: the earliest). Empty for no samples. With `axial` true, angles are axes (θ and
/// θ + π are the same), and the result is in (-π/2, π/2].
std::optional<double> circularMedian(const std::vector<double>& angles_rad, bool axial = false);

}  // namespace colorfree
