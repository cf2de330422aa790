#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <utility>

#include "colorfree/perception/orientation/geometry.h"
#include "colorfree/perception/orientation/orientation_filter.h"

namespace colorfree {
namespace {

constexpr double kPi = std::numbers::pi;
double deg(double d) { return d * kPi / 180; }

TEST(ConvexHull, SquareWithInteriorAndCollinearPoints) {
  std::vector<Eigen::Vector2d> pts = {{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.5, 0.5},
                                      {0.5, 0}, {0.2, 0.7}, {1, 0.5}, {0, 0}};
  const auto hull = convexHull(pts);
  ASSERT_EQ(hull.size(), 4u);
  EXPECT_EQ(hull[0], Eigen::Vector2d(0, 0));
  EXPECT_EQ(hull[1], Eigen::Vector2d(1, 0));
  EXPECT_EQ(hull[2], Eigen::Vector2d(1, 1));
  EXPECT_EQ(hull[3], Eigen::Vector2d(0, 1));
}

TEST(ConvexHull, DegenerateInputs) {
  EXPECT_TRUE(convexHull({}).empty());
  EXPECT_EQ(convexHull({{1, 2}, {1, 2}}).size(), 1u);
  // All collinear: the two ends.
  const auto line = convexHull({{0, 0}, {1, 1}, {2, 2}, {3, 3}});
  ASSERT_EQ(line.size(), 2u);
  EXPECT_EQ(line[0], Eigen::Vector2d(0, 0));
  EXPECT_EQ(line[1], Eigen::Vector2d(3, 3));
}

TEST(LineVotes, CountsPointsNearTheSegmentOnly) {
  std::vector<Eigen::Vector2d> pts;
  for (int i = 0; i <= 10; ++i) pts.push_back({i * 0.1, 0.004 * (i % 2)});  // on the line
  pts.push_back({0.5, 0.05});   // too far across
  pts.push_back({1.5, 0.0});    // beyond the end
  EXPECT_EQ(countLineVotes({0, 0}, {1, 0}, pts, 0.005), 11);
  EXPECT_EQ(countLineVotes({0, 0}, {1, 0}, pts, 0.06), 12);
  EXPECT_EQ(countLineVotes({0, 0}, {1, 0}, pts, 0.005, 0.6), 12);
}

TEST(SilhouetteLines, FindsTheLongEdgeThenTheOrthogonalShortOne) {
  // An L of silhouette points: a long edge of 0.25 m along x, a short one of 0.09 m along y.
  std::vector<Eigen::Vector2d> pts;
  for (int i = 0; i <= 25; ++i) pts.push_back({i * 0.01, 0});
  for (int i = 1; i <= 9; ++i) pts.push_back({0.25, i * 0.01});
  SilhouetteLineBounds bounds;
  bounds.vote_distance = 0.003;
  const auto lines = findSilhouetteLines(pts, bounds);
  ASSERT_TRUE(lines.first);
  EXPECT_NEAR(std::abs(lines.first->direction().x()), 1.0, 1e-9);
  EXPECT_EQ(lines.first->votes, 26);
  ASSERT_TRUE(lines.second);
  EXPECT_NEAR(std::abs(lines.second->direction().y()), 1.0, 1e-9);
  EXPECT_NEAR(lines.second->length(), 0.09, 1e-9);
}

TEST(SilhouetteLines, NoSecondLineWhenNothingIsOrthogonal) {
  std::vector<Eigen::Vector2d> pts;
  for (int i = 0; i <= 20; ++i) pts.push_back({i * 0.01, 0.001 * (i % 3)});
  const auto lines = findSilhouetteLines(pts, {});
  ASSERT_TRUE(lines.first);
  EXPECT_FALSE(lines.second);
}

TEST(SilhouetteLines, WithAViewpointOnlyTheNearEdgesCount) {
  // A turned foot seen from the origin: two near edges from the corner (1, 0), 0.16 m at +40°
  // and 0.10 m at -50°, and a few points far behind them (the heel's top, seen through). The
  // hull edges behind the silhouette must not be candidates.
  std::vector<Eigen::Vector2d> pts;
  const Eigen::Vector2d corner(1.0, 0.0), u(std::cos(deg(40)), std::sin(deg(40))),
      v(std::cos(deg(-50)), std::sin(deg(-50)));
  for (int i = 0; i <= 32; ++i) pts.push_back(corner + i * 0.005 * u);
  for (int i = 1; i <= 20; ++i) pts.push_back(corner + i * 0.005 * v);
  for (int i = 0; i <= 12; ++i) pts.push_back(corner + 0.16 * u + 0.10 * v + Eigen::Vector2d(0.0, -0.005 * i));
  SilhouetteLineBounds bounds;
  bounds.vote_distance = 0.003;
  bounds.min_length = 0.04;
  bounds.vote_margin = 1.0;  // the whole line votes (the hull splits a noisy edge into pieces)
  bounds.viewpoint = Eigen::Vector2d::Zero();
  const auto lines = findSilhouetteLines(pts, bounds);
  ASSERT_TRUE(lines.first);
  EXPECT_NEAR(std::abs(lines.first->direction().dot(u)), 1.0, 1e-9);
  EXPECT_EQ(lines.first->votes, 33);
  EXPECT_NEAR(lines.first->length(), 0.16, 1e-9);
  ASSERT_TRUE(lines.second);
  EXPECT_NEAR(std::abs(lines.second->direction().dot(v)), 1.0, 1e-9);
  EXPECT_NEAR(lines.second->length(), 0.10, 1e-9);
  // Seen from behind, the far points' edge is the near one.
  bounds.viewpoint = Eigen::Vector2d(3.0, 0.0);
  const auto behind = findSilhouetteLines(pts, bounds);
  ASSERT_TRUE(behind.first);
  EXPECT_LT(std::abs(behind.first->direction().dot(u)), 0.9);
}

// Two short clusters 0.27 m apart that happen to line up (one foot's heel, the other foot's toe,
// seen at 1.4 m in uneven light) and between them no silhouette at all, beside a real foot edge
// of 0.1 m at 60°: the clusters together out-vote the edge, but no edge of a robot's feet has a
// 0.27 m hole in it.
std::vector<Eigen::Vector2d> twoClustersAndAnEdge() {
  std::vector<Eigen::Vector2d> pts;
  for (int i = 0; i < 7; ++i) pts.push_back({0.005 * i, 0});         // cluster A: 0 .. 0.03 m
  for (int i = 0; i < 7; ++i) pts.push_back({0.30 + 0.005 * i, 0});  // cluster B: 0.30 .. 0.33 m
  const Eigen::Vector2d start(0.34, 0.005), u(std::cos(deg(60)), std::sin(deg(60)));
  for (int i = 0; i < 9; ++i) pts.push_back(start + 0.0125 * i * u);  // the foot's edge: 0.1 m
  return pts;
}

TEST(LineVoters, OnlyTheLongestContiguousRunWithAGapLimit) {
  const auto pts = twoClustersAndAnEdge();
  // Without a gap limit every point near the line votes, ordered along it.
  const auto all = lineVoters({0.33, 0}, {0, 0}, pts, 0.003, 0.0, 0.0);
  ASSERT_EQ(all.size(), 14u);
  EXPECT_NEAR(all.front().x(), 0.33, 1e-12);
  EXPECT_NEAR(all.back().x(), 0.0, 1e-12);
  // With one, the runs of 7 are two pieces: the first along the line (from 0.33 m down) stays.
  const auto run = lineVoters({0.33, 0}, {0, 0}, pts, 0.003, 0.0, 0.1);
  ASSERT_EQ(run.size(), 7u);
  for (const auto& p : run) EXPECT_GE(p.x(), 0.30 - 1e-12);
  // A longer run wins whatever its place.
  auto more = pts;
  more.push_back({0.035, 0});
  const auto longer = lineVoters({0.33, 0}, {0, 0}, more, 0.003, 0.0, 0.1);
  ASSERT_EQ(longer.size(), 8u);
  for (const auto& p : longer) EXPECT_LE(p.x(), 0.035 + 1e-12);
  EXPECT_TRUE(lineVoters({0, 0}, {0, 0}, pts, 0.003, 0.0, 0.1).empty());
}

TEST(SilhouetteLines, AGapLimitKeepsTwoDistantClustersFromOutvotingAnEdge) {
  const auto pts = twoClustersAndAnEdge();
  SilhouetteLineBounds bounds;
  bounds.vote_distance = 0.003;
  bounds.vote_margin =
      0.1;  // the hull may split the edge into pieces: each gets the whole edge's votes
  // The paper's voting: the line through both clusters (14 votes, 0°) beats the edge (9, 60°).
  const auto joined = findSilhouetteLines(pts, bounds);
  ASSERT_TRUE(joined.first);
  EXPECT_EQ(joined.first->votes, 14);
  EXPECT_NEAR(std::abs(joined.first->direction().x()), 1.0, 1e-9);
  // With the gap limit the clusters are 7 votes each and the edge is the first line.
  bounds.max_voter_gap = 0.1;
  const auto lines = findSilhouetteLines(pts, bounds);
  ASSERT_TRUE(lines.first);
  EXPECT_EQ(lines.first->votes, 9);
  EXPECT_NEAR(
      std::abs(lines.first->direction().dot(Eigen::Vector2d(std::cos(deg(60)), std::sin(deg(60))))),
      1.0, 1e-9);
  EXPECT_NEAR(lines.first->length(), 0.1, 1e-9);
}

TEST(CircularMedian, WrapsAroundPlusMinusPi) {
  // Samples around 180°: a linear median would give about 0.
  const std::vector<double> a = {deg(170), deg(-175), deg(178), deg(-170), deg(175)};
  const double m = *circularMedian(a);
  EXPECT_NEAR(std::abs(m), deg(178), 1e-12);
  EXPECT_FALSE(circularMedian({}));
}

TEST(CircularMedian, RejectsAnOutlier) {
  const std::vector<double> a = {deg(10), deg(12), deg(-150), deg(11), deg(9)};
  EXPECT_NEAR(*circularMedian(a), deg(10), 1e-12);
}

TEST(CircularMedian, AxialTreatsOppositeAnglesAsOne) {
  const std::vector<double> a = {deg(88), deg(-91), deg(92), deg(-89), deg(90)};
  const double m = *circularMedian(a, /*axial=*/true);
  EXPECT_NEAR(std::abs(wrapAngle(2 * (m - deg(90)))) / 2, 0, deg(1.01));
  EXPECT_GT(m, -kPi / 2);
  EXPECT_LE(m, kPi / 2);
}

TEST(WrapAngle, HalfOpenInterval) {
  EXPECT_NEAR(wrapAngle(3 * kPi), kPi, 1e-12);
  EXPECT_NEAR(wrapAngle(-kPi), kPi, 1e-12);
  EXPECT_NEAR(wrapAngle(deg(370)), deg(10), 1e-12);
}

TEST(OrientationFromLine, FrontFacesTheObserverBackFacesAway) {
  // A robot 1.2 m ahead; its toe line runs along y.
  const Eigen::Vector2d pos(1.2, 0);
  const auto front = orientationFromLine({1.1, -0.1}, {1.1, 0.1}, RobotSide::kFront, pos);
  EXPECT_TRUE(front.facing_known);
  EXPECT_NEAR(std::abs(front.angle_rad), kPi, 1e-12);  // facing the observer: towards −x
  const auto back = orientationFromLine({1.1, -0.1}, {1.1, 0.1}, RobotSide::kBack, pos);
  EXPECT_NEAR(back.angle_rad, 0, 1e-12);
  const auto side = orientationFromLine({1.1, -0.1}, {1.1, 0.1}, RobotSide::kSide, pos);
  EXPECT_FALSE(side.facing_known);
  EXPECT_NEAR(std::abs(side.angle_rad), kPi / 2, 1e-12);
}

TEST(OrientationFromSideLine, FacesTheObserversLeftOrRight) {
  // A robot 1.2 m ahead, its foot's long side along y: the observer's left is +y.
  const Eigen::Vector2d pos(1.2, 0);
  for (const auto& [a, b] : {std::pair<Eigen::Vector2d, Eigen::Vector2d>{{1.1, -0.1}, {1.1, 0.1}},
                             {{1.1, 0.1}, {1.1, -0.1}}}) {
    const auto left = orientationFromSideLine(a, b, true, pos);
    EXPECT_TRUE(left.facing_known);
    EXPECT_NEAR(left.angle_rad, kPi / 2, 1e-12);
    const auto right = orientationFromSideLine(a, b, false, pos);
    EXPECT_TRUE(right.facing_known);
    EXPECT_NEAR(right.angle_rad, -kPi / 2, 1e-12);
  }
  // Seen at a bearing of 45°: the observer's left there points to (-1, 1); a line along it.
  const Eigen::Vector2d diag(1, 1);
  const auto l = orientationFromSideLine({1.05, 0.95}, {0.95, 1.05}, true, diag);
  EXPECT_NEAR(l.angle_rad, 3 * kPi / 4, 1e-9);
  const auto r = orientationFromSideLine({1.05, 0.95}, {0.95, 1.05}, false, diag);
  EXPECT_NEAR(r.angle_rad, -kPi / 4, 1e-9);
  // A side line slightly off the lateral direction keeps its own direction.
  const auto tilted = orientationFromSideLine({1.2, 0}, {1.2 + 0.1 * std::sin(0.2), 0.1 * std::cos(0.2)}, true, pos);
  EXPECT_NEAR(tilted.angle_rad, kPi / 2 - 0.2, 1e-9);
}

TEST(ConsistencyCheck, SideLinesWithAFacing) {
  // A side line alone whose facing OriNet saw: its estimate, facing known.
  const auto alone = combineLineOrientations({{1.0, true}}, {RobotSide::kSide});
  ASSERT_TRUE(alone);
  EXPECT_TRUE(alone->facing_known);
  EXPECT_DOUBLE_EQ(alone->angle_rad, 1.0);
  // Its facing disagrees with the front line's: not trusted.
  EXPECT_FALSE(combineLineOrientations({{1.0, true}, {1.0 - kPi + 0.1, true}},
                                       {RobotSide::kSide, RobotSide::kFront}));
  // It agrees: the side line (first, best voted) gives the angle.
  const auto agree = combineLineOrientations({{1.0, true}, {0.8, true}}, {RobotSide::kSide, RobotSide::kFront});
  ASSERT_TRUE(agree);
  EXPECT_DOUBLE_EQ(agree->angle_rad, 1.0);
  // A front line first and a side line with a facing second: the front line's estimate.
  const auto front_first = combineLineOrientations({{0.5, true}, {0.6, true}}, {RobotSide::kFront, RobotSide::kSide});
  ASSERT_TRUE(front_first);
  EXPECT_DOUBLE_EQ(front_first->angle_rad, 0.5);
  // Two side lines stay inconsistent whatever their facings.
  EXPECT_FALSE(combineLineOrientations({{1.0, true}, {1.0, false}}, {RobotSide::kSide, RobotSide::kSide}));
}

TEST(ConsistencyCheck, KeepsTheMostConfidentRegionOfAClass) {
  // Two side regions (the paper's check drops both): the surer one stays, wherever it is.
  std::vector<RobotOrientation> o = {{1.0, true}, {2.5, true}};
  std::vector<RobotSide> c = {RobotSide::kSide, RobotSide::kSide};
  keepMostConfidentOfEachClass(o, c, {0.63f, 0.99f});
  ASSERT_EQ(o.size(), 1u);
  EXPECT_DOUBLE_EQ(o[0].angle_rad, 2.5);
  const auto kept = combineLineOrientations(o, c);
  ASSERT_TRUE(kept);
  EXPECT_DOUBLE_EQ(kept->angle_rad, 2.5);
  // Regions of different classes are all kept, in order; of equals the first.
  o = {{0.5, true}, {1.0, false}, {0.6, true}};
  c = {RobotSide::kFront, RobotSide::kSide, RobotSide::kFront};
  keepMostConfidentOfEachClass(o, c, {0.8f, 0.7f, 0.8f});
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0], RobotSide::kFront);
  EXPECT_DOUBLE_EQ(o[0].angle_rad, 0.5);
  EXPECT_EQ(c[1], RobotSide::kSide);
  // Nothing shared: unchanged.
  o = {{0.5, true}, {2.0, false}};
  c = {RobotSide::kFront, RobotSide::kSide};
  keepMostConfidentOfEachClass(o, c, {0.1f, 0.9f});
  EXPECT_EQ(o.size(), 2u);
}

TEST(ConsistencyCheck, AtMostOneOfEachClass) {
  EXPECT_TRUE(classesConsistent({RobotSide::kFront, RobotSide::kSide}));
  EXPECT_FALSE(classesConsistent({RobotSide::kSide, RobotSide::kSide}));
  EXPECT_FALSE(combineLineOrientations({{0, true}, {0.1, true}},
                                       {RobotSide::kFront, RobotSide::kFront}));
  // Front and back that disagree on the facing are rejected.
  EXPECT_FALSE(combineLineOrientations({{0, true}, {kPi, true}},
                                       {RobotSide::kFront, RobotSide::kBack}));
  // A side line first (best voted): its axis, turned to the facing the front line gives.
  const auto both = combineLineOrientations({{1.0 - kPi, false}, {0.5, true}},
                                            {RobotSide::kSide, RobotSide::kFront});
  ASSERT_TRUE(both);
  EXPECT_TRUE(both->facing_known);
  EXPECT_DOUBLE_EQ(both->angle_rad, 1.0);
  // The front line first: its own estimate.
  const auto front_first = combineLineOrientations({{0.5, true}, {1.0, false}},
                                                   {RobotSide::kFront, RobotSide::kSide});
  ASSERT_TRUE(front_first);
  EXPECT_DOUBLE_EQ(front_first->angle_rad, 0.5);
  // A side axis far from the front line's facing (no orthogonal pair): the facing line's estimate.
  const auto far = combineLineOrientations({{0.5 + kPi / 2, false}, {0.5, true}},
                                           {RobotSide::kSide, RobotSide::kFront});
  ASSERT_TRUE(far);
  EXPECT_DOUBLE_EQ(far->angle_rad, 0.5);
}

TEST(OrientationTrack, MedianOverElevenAndExpiry) {
  OrientationTrack track;
  OrientationFilterParams params;
  std::optional<RobotOrientation> out;
  for (int i = 0; i < 15; ++i) {
    // Every fifth sample is a flipped outlier.
    const double a = i % 5 == 0 ? deg(-178) : deg(2 + 0.1 * i);
    out = updateOrientationTrack(track, RobotOrientation{a, true}, 0.1 * i, params);
  }
  EXPECT_EQ(track.samples.size(), 11u);
  ASSERT_TRUE(out);
  EXPECT_TRUE(out->facing_known);
  EXPECT_NEAR(out->angle_rad, deg(2.9), deg(0.35));
  // Without new samples the estimate expires.
  EXPECT_TRUE(updateOrientationTrack(track, std::nullopt, 1.45, params));
  EXPECT_FALSE(updateOrientationTrack(track, std::nullopt, 3.0, params));
}

TEST(OrientationTrack, MostlyAxialSamplesGiveOnlyTheAxis) {
  OrientationTrack track;
  std::optional<RobotOrientation> out;
  for (int i = 0; i < 6; ++i) {
    out = updateOrientationTrack(track, RobotOrientation{i % 2 ? deg(89) : deg(-91), false},
                                 0.05 * i, {});
  }
  out = updateOrientationTrack(track, RobotOrientation{deg(90), true}, 0.4, {});
  ASSERT_TRUE(out);
  EXPECT_FALSE(out->facing_known);
  EXPECT_NEAR(std::abs(out->angle_rad), deg(89), deg(2.01));
}

}  // namespace
}  // namespace colorfree
