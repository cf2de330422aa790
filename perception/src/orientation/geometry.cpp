#include "colorfree/perception/orientation/geometry.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace colorfree {

namespace {
constexpr double kPi = 3.14159265358979323846;

double cross(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}
}  // namespace

std::vector<Eigen::Vector2d> convexHull(std::vector<Eigen::Vector2d> points) {
  std::sort(points.begin(), points.end(), [](const auto& p, const auto& q) {
    return p.x() < q.x() || (p.x() == q.x() && p.y() < q.y());
  });
  points.erase(std::unique(points.begin(), points.end()), points.end());
  const std::size_t n = points.size();
  if (n < 3) return points;
  std::vector<Eigen::Vector2d> hull(2 * n);
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {  // lower hull
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
    hull[k++] = points[i];
  }
  for (std::size_t i = n - 1, t = k + 1; i-- > 0;) {  // upper hull
    while (k >= t && cross(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
    hull[k++] = points[i];
  }
  hull.resize(k - 1);
  return hull;
}

int countLineVotes(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                   const std::vector<Eigen::Vector2d>& points, double max_distance,
                   double margin) {
  const Eigen::Vector2d d = b - a;
  const double length = d.norm();
  if (length <= 0) return 0;
  const Eigen::Vector2d u = d / length;
  int votes = 0;
  for (const auto& p : points) votes += nearSegment(a, u, length, p, max_distance, margin);
  return votes;
}

namespace {
// lineVoters' work: the voters along the line into `voters` (reused, so the hull edges' votes
// allocate once), their longest run is [begin, end).
void voterRun(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
              const std::vector<Eigen::Vector2d>& points, double max_distance, double margin,
              double max_gap, std::vector<std::pair<double, Eigen::Vector2d>>& voters,
              std::size_t& best_begin, std::size_t& best_end) {
  voters.clear();
  best_begin = best_end = 0;
  const Eigen::Vector2d d = b - a;
  const double length = d.norm();
  if (length <= 0) return;
  const Eigen::Vector2d u = d / length;
  for (const auto& p : points) {
    const Eigen::Vector2d ap = p - a;
    const double along = ap.dot(u);
    const double across = std::abs(ap.x() * u.y() - ap.y() * u.x());
    if (across <= max_distance && along >= -margin && along <= length + margin)
      voters.emplace_back(along, p);
  }
  // Along the line, ties in the points' order (as std::stable_sort): an insertion sort, the
  // points come nearly in order (scan line by scan line) and the sort allocates nothing.
  for (std::size_t i = 1; i < voters.size(); ++i) {
    const auto v = voters[i];
    std::size_t j = i;
    for (; j > 0 && v.first < voters[j - 1].first; --j) voters[j] = voters[j - 1];
    voters[j] = v;
  }
  best_end = voters.size();
  if (max_gap > 0 && !voters.empty()) {
    best_end = 0;
    for (std::size_t begin = 0, i = 1; i <= voters.size(); ++i) {
      if (i < voters.size() && voters[i].first - voters[i - 1].first <= max_gap) continue;
      if (i - begin > best_end - best_begin) {
        best_begin = begin;
        best_end = i;
      }
      begin = i;
    }
  }
}
}  // namespace

std::vector<Eigen::Vector2d> lineVoters(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                        const std::vector<Eigen::Vector2d>& points,
                                        double max_distance, double margin, double max_gap) {
  std::vector<std::pair<double, Eigen::Vector2d>> voters;
  std::size_t best_begin = 0, best_end = 0;
  voterRun(a, b, points, max_distance, margin, max_gap, voters, best_begin, best_end);
  std::vector<Eigen::Vector2d> out;
  out.reserve(best_end - best_begin);
  for (std::size_t i = best_begin; i < best_end; ++i) out.push_back(voters[i].second);
  return out;
}

SilhouetteLines findSilhouetteLines(const std::vector<Eigen::Vector2d>& points,
                                    const SilhouetteLineBounds& bounds) {
  SilhouetteLines out;
  const std::vector<Eigen::Vector2d> hull = convexHull(points);
  if (hull.size() < 2) return out;
  std::vector<LineHypothesis> candidates;
  candidates.reserve(hull.size());
  std::vector<std::pair<double, Eigen::Vector2d>> voters;
  voters.reserve(points.size());
  const std::size_t edges = hull.size() == 2 ? 1 : hull.size();
  for (std::size_t i = 0; i < edges; ++i) {
    LineHypothesis h;
    h.a = hull[i];
    h.b = hull[(i + 1) % hull.size()];
    if (bounds.viewpoint && hull.size() > 2) {
      // Counter-clockwise hull: the outward normal of a -> b is (dy, -dx).
      const Eigen::Vector2d d = h.b - h.a;
      const Eigen::Vector2d outward(d.y(), -d.x());
      if (outward.dot(*bounds.viewpoint - 0.5 * (h.a + h.b)) <= 0) continue;
    }
    const Eigen::Vector2d d = h.b - h.a;
    const double length = d.norm();
    if (bounds.max_voter_gap > 0) {
      // The extent and votes of the voters' longest contiguous run.
      std::size_t begin = 0, end = 0;
      voterRun(h.a, h.b, points, bounds.vote_distance, bounds.vote_margin, bounds.max_voter_gap,
               voters, begin, end);
      if (end - begin < 2) continue;  // no line: the edge joins two lone points
      h.votes = static_cast<int>(end - begin);
      const Eigen::Vector2d u = d / length, a = h.a;
      h.a = a + (voters[begin].second - a).dot(u) * u;
      h.b = a + (voters[end - 1].second - a).dot(u) * u;
      candidates.push_back(h);
      continue;
    }
    h.votes = countLineVotes(h.a, h.b, points, bounds.vote_distance, bounds.vote_margin);
    // The line's extent is that of its voters (a noisy edge's hull splits it into short pieces).
    if (length > 0) {
      const Eigen::Vector2d u = d / length;
      double t0 = 0, t1 = length;
      for (const auto& p : points) {
        const Eigen::Vector2d ap = p - h.a;
        const double along = ap.dot(u);
        if (std::abs(ap.x() * u.y() - ap.y() * u.x()) <= bounds.vote_distance && along >= -bounds.vote_margin &&
            along <= length + bounds.vote_margin) {
          t0 = std::min(t0, along);
          t1 = std::max(t1, along);
        }
      }
      const Eigen::Vector2d a = h.a;
      h.a = a + t0 * u;
      h.b = a + t1 * u;
    }
    candidates.push_back(h);
  }
  if (candidates.empty()) return out;
  // Most votes first; ties go to the longer line, then to hull order (stable).
  std::stable_sort(candidates.begin(), candidates.end(), [](const auto& p, const auto& q) {
    return p.votes > q.votes || (p.votes == q.votes && p.length() > q.length());
  });
  out.first = candidates.front();
  const Eigen::Vector2d first_dir = out.first->direction();
  for (std::size_t i = 1; i < candidates.size(); ++i) {
    const auto& c = candidates[i];
    const double len = c.length();
    if (len < bounds.min_length || len > bounds.max_length) continue;
    if (std::abs(c.direction().dot(first_dir)) > bounds.max_orthogonality_cos) continue;
    out.second = c;
    break;
  }
  return out;
}

double wrapAngle(double a) {
  a = std::fmod(a, 2 * kPi);
  if (a <= -kPi) a += 2 * kPi;
  if (a > kPi) a -= 2 * kPi;
  return a;
}

std::optional<double> circularMedian(const std::vector<double>& angles, bool axial) {
  if (angles.empty()) return std::nullopt;
  // Axial data: double the angles, take the directional median, halve back.
  const double scale = axial ? 2.0 : 1.0;
  double best = 0;
  double best_cost = std::numeric_limits<double>::infinity();
  for (double candidate : angles) {
    double cost = 0;
    for (double a : angles) cost += std::abs(wrapAngle(scale * (a - candidate)));
    if (cost < best_cost - 1e-12) {
      best_cost = cost;
      best = candidate;
    }
  }
  if (!axial) return wrapAngle(best);
  double r = wrapAngle(2 * best) / 2;  // in (-π/2, π/2]
  return r;
}

}  // namespace colorfree
