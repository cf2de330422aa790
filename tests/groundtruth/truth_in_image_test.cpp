#include "colorfree/groundtruth/truth_in_image.h"

#include <gtest/gtest.h>

#include <cmath>

#include "colorfree/groundtruth/field_markings.h"
#include "test_support.h"

namespace colorfree {
namespace {

constexpr double kPi = 3.14159265358979323846;

// An observer at `pose` with a camera `height_m` above its ground point looking along its heading,
// pitched down by `pitch_rad`.
WorldState makeWorld(FieldPose observer, double height_m, double pitch_rad, int w = 320, int h = 240) {
  WorldState s;
  s.observer = observer;
  CameraPose cp;
  cp.height_m = height_m;
  cp.pitch_rad = pitch_rad;
  s.camera.model = CameraModel(CameraIntrinsics::fromHorizontalFov(w, h, 60.9 * kPi / 180), cp);
  s.camera.camera_to_field = robotToField(observer) * s.camera.model.cameraToRobot();
  return s;
}

void fillDisc(ObjectMap& map, const Eigen::Vector2d& c, double r, std::uint16_t label) {
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      if ((Eigen::Vector2d(x + 0.5, y + 0.5) - c).norm() <= r) map.labels[y * map.width + x] = label;
    }
  }
}

ObjectMap emptyMap(int w, int h) {
  ObjectMap m;
  m.width = w;
  m.height = h;
  m.labels.assign(static_cast<std::size_t>(w) * h, kObjectCarpet);
  return m;
}

TEST(FieldMarkings, HasTheSplMarkings) {
  const FieldMarkings m = FieldMarkings::fromDimensions(FieldDimensions{});
  EXPECT_EQ(m.lines.size(), 17u);
  int l = 0, t = 0, x = 0;
  for (const auto& i : m.intersections) {
    l += i.type == IntersectionType::kL;
    t += i.type == IntersectionType::kT;
    x += i.type == IntersectionType::kX;
  }
  EXPECT_EQ(l, 12);
  EXPECT_EQ(t, 10);
  EXPECT_EQ(x, 2);
  ASSERT_EQ(m.penalty_marks.size(), 2u);
  EXPECT_NEAR(std::abs(m.penalty_marks[0].x()), 3.2, 1e-12);
  EXPECT_NEAR(m.centre_circle_radius_m, 0.75, 1e-12);
  // Every intersection lies on at least two lines (or on a line and the circle for X).
  for (const auto& i : m.intersections) {
    int on = 0;
    for (const auto& s : m.lines) on += pointSegmentDistance(i.position, s.start, s.end) < 1e-9;
    EXPECT_GE(on + (i.type == IntersectionType::kX ? 1 : 0), 2) << i.position.transpose();
  }
}

TEST(TruthInImage, BallOnTheOpticalAxisHasTheConeRadius) {
  // Level camera at the ball's centre height: the ball sits on the optical axis.
  WorldState s = makeWorld({0, 0, 0}, 0.05, 0);
  s.ball.present = true;
  s.ball.position_m = {2.0, 0, 0.05};
  const auto t = computeFrameTruth(s, FieldMarkings::fromDimensions({}), {}, ScoringParams{});
  ASSERT_TRUE(t.ball.in_view);
  const auto& k = s.camera.model.intrinsics();
  EXPECT_NEAR(t.ball.centre_px.x(), k.center_x_px, 1e-6);
  EXPECT_NEAR(t.ball.centre_px.y(), k.center_y_px, 1e-6);
  EXPECT_NEAR(t.ball.radius_px, k.focal_x_px * std::tan(std::asin(0.05 / 2.0)), 1e-3);
  EXPECT_NEAR(t.ball.distance_m, 2.0, 1e-12);
  EXPECT_NEAR(t.ball.visible_fraction, 1.0, 1e-2);  // no object map: only the border counts
  EXPECT_TRUE(t.ball.should_detect);
}

TEST(TruthInImage, BallCutByTheBorderAndOccludedInTheObjectMap) {
  WorldState s = makeWorld({0, 0, 0}, 0.5, 0.3);
  s.ball.present = true;
  s.ball.position_m = {1.5, 0.2, 0.05};
  auto t = computeFrameTruth(s, FieldMarkings::fromDimensions({}), {}, ScoringParams{});
  ASSERT_TRUE(t.ball.in_view);
  // A map with the ball's disc drawn: almost all of it visible.
  s.object_map = emptyMap(320, 240);
  fillDisc(s.object_map, t.ball.centre_px, t.ball.radius_px - 0.5, kObjectBall);
  t = computeFrameTruth(s, FieldMarkings::fromDimensions({}), {}, ScoringParams{});
  EXPECT_GT(t.ball.visible_fraction, 0.85);
  EXPECT_TRUE(t.ball.should_detect);
  // A robot in front of its right 70 %: not visible enough any more.
  for (int y = 0; y < 240; ++y) {
    for (int x = 0; x < 320; ++x) {
      if (x + 0.5 > t.ball.centre_px.x() - 0.4 * t.ball.radius_px) s.object_map.labels[y * 320 + x] = kObjectRobotBase;
    }
  }
  t = computeFrameTruth(s, FieldMarkings::fromDimensions({}), {}, ScoringParams{});
  EXPECT_LT(t.ball.visible_fraction, 0.4);
  EXPECT_FALSE(t.ball.should_detect);

  // Without a map, a ball whose centre is on the image's left edge is about half visible.
  WorldState e = makeWorld({0, 0, 0}, 0.05, 0);
  e.ball.present = true;
  const double half_fov = e.camera.model.intrinsics().horizontalFov() / 2;
  e.ball.position_m = {2.0 * std::cos(half_fov), 2.0 * std::sin(half_fov), 0.05};
  t = computeFrameTruth(e, FieldMarkings::fromDimensions({}), {}, ScoringParams{});
  ASSERT_TRUE(t.ball.in_view);
  EXPECT_NEAR(t.ball.centre_px.x(), 0.0, 0.5);
  EXPECT_NEAR(t.ball.visible_fraction, 0.5, 0.03);
}

TEST(TruthInImage, BallBehindTheCameraIsNotInView) {
  WorldState s = makeWorld({0, 0, 0}, 0.5, 0.3);
  s.ball.present = true;
  s.ball.position_m = {-1.0, 0, 0.05};
  const auto t = computeFrameTruth(s, FieldMarkings::fromDimensions({}), {}, ScoringParams{});
  EXPECT_FALSE(t.ball.in_view);
  EXPECT_FALSE(t.ball.should_detect);
}

TEST(TruthInImage, RobotHeadingRelativeToTheLineOfSight) {
  WorldState s = makeWorld({0, 0, 0}, 0.5, 0.2);
  const FieldMarkings field = FieldMarkings::fromDimensions({});
  auto relFor = [&](double heading) {
    s.robots = {RobotTruth{}};
    s.robots[0].pose = {2.0, 0.0, heading};
    return computeFrameTruth(s, field, {}, ScoringParams{}).robots[0];
  };
  auto r = relFor(kPi);  // facing the observer
  EXPECT_NEAR(r.heading_rel_rad, 0, 1e-9);
  EXPECT_EQ(r.side_seen, RobotSide::kFront);
  EXPECT_NEAR(std::abs(r.heading_in_observer_rad), kPi, 1e-9);
  r = relFor(0);  // walking away
  EXPECT_NEAR(std::abs(r.heading_rel_rad), kPi, 1e-9);
  EXPECT_EQ(r.side_seen, RobotSide::kBack);
  r = relFor(kPi / 2);
  EXPECT_EQ(r.side_seen, RobotSide::kSide);
  EXPECT_NEAR(r.heading_rel_rad, -kPi / 2, 1e-9);
  // Off-axis: a robot at 45° to the left facing the camera's position.
  s.robots[0].pose = {2.0, 2.0, std::atan2(-2.0, -2.0)};
  r = computeFrameTruth(s, field, {}, ScoringParams{}).robots[0];
  EXPECT_NEAR(r.heading_rel_rad, 0, 1e-2);  // camera is ~5 cm ahead of the ground point
}

TEST(TruthInImage, RobotBoxBoundsItsProjectedBody) {
  WorldState s = makeWorld({0, 0, 0}, 0.5, 0.25);
  s.robots = {RobotTruth{}};
  s.robots[0].pose = {1.5, 0.1, 1.0};
  const FieldDimensions dims;
  const ScoringParams p;
  const auto r = computeFrameTruth(s, FieldMarkings::fromDimensions(dims), dims, p).robots[0];
  ASSERT_TRUE(r.in_view);
  EXPECT_TRUE(r.should_detect);
  // The ground point and the head's centre lie inside the box; the feet box is its lower part.
  const auto head = s.camera.model.robotToPixel({1.5, 0.1, dims.robot_height_m - 0.05});
  ASSERT_TRUE(head);
  for (const Eigen::Vector2d& q : {r.ground_px, *head}) {
    EXPECT_GE(q.x(), r.box.x0);
    EXPECT_LE(q.x(), r.box.x1);
    EXPECT_GE(q.y(), r.box.y0);
    EXPECT_LE(q.y(), r.box.y1);
  }
  EXPECT_NEAR(r.feet_box.y1, r.box.y1, 1e-9);
  EXPECT_GT(r.feet_box.y0, r.box.y0 + 0.5 * r.box.height());
  EXPECT_NEAR(r.distance_m, std::hypot(1.5, 0.1), 1e-12);
  // Feet straddle the ground point.
  EXPECT_NEAR(((r.left_foot_px + r.right_foot_px) / 2 - r.ground_px).norm(), 0, 0.5);
}

TEST(TruthInImage, RobotVisibleFractionCountsNearerOccluders) {
  WorldState s = makeWorld({0, 0, 0}, 0.5, 0.25);
  s.robots = {RobotTruth{}, RobotTruth{}};
  s.robots[0].pose = {2.0, 0.0, 0};
  s.robots[1].pose = {1.0, 0.0, 0};  // nearer, in front of robot 0
  s.robots[1].index = 1;
  const FieldDimensions dims;
  const FieldMarkings field = FieldMarkings::fromDimensions(dims);
  auto t = computeFrameTruth(s, field, dims, ScoringParams{});
  s.object_map = emptyMap(320, 240);
  // Paint robot 0's box, then robot 1's over it (nearer hides farther).
  for (int i : {0, 1}) {
    const auto& b = t.robots[i].box;
    for (int y = static_cast<int>(b.y0); y < static_cast<int>(b.y1); ++y)
      for (int x = static_cast<int>(b.x0); x < static_cast<int>(b.x1); ++x)
        s.object_map.labels[y * 320 + x] = static_cast<std::uint16_t>(kObjectRobotBase + i);
  }
  t = computeFrameTruth(s, field, dims, ScoringParams{});
  EXPECT_GT(t.robots[1].visible_fraction, 0.95);
  EXPECT_LT(t.robots[0].visible_fraction, 0.2);
  EXPECT_FALSE(t.robots[0].should_detect);
  EXPECT_TRUE(t.robots[1].should_detect);
}

TEST(TruthInImage, LinesAreClippedToTheViewAndBehindTheCamera) {
  // 1.5 m from the left touch line, looking along +x: that line runs from behind the camera to
  // far ahead.
  WorldState s = makeWorld({0, 1.5, 0}, 0.5, 0.3);
  const FieldMarkings field = FieldMarkings::fromDimensions({});
  auto t = computeFrameTruth(s, field, {}, ScoringParams{});
  ASSERT_FALSE(t.field.lines.empty());
  const double w = 320, h = 240;
  for (const auto& l : t.field.lines) {
    for (const auto& p : {l.start_px, l.end_px}) {
      EXPECT_GE(p.x(), -1e-9);
      EXPECT_LE(p.x(), w + 1e-9);
      EXPECT_GE(p.y(), -1e-9);
      EXPECT_LE(p.y(), h + 1e-9);
    }
    // The clipped segment maps back onto the model line on the ground.
    for (const auto& q : {l.start_px, l.end_px}) {
      const auto g = s.camera.model.pixelToGround(q);
      ASSERT_TRUE(g) << l.name;
      const Eigen::Vector2d gf = *g + Eigen::Vector2d(0, 1.5);
      double best = 1e9;
      for (const auto& m : field.lines) {
        if (m.name == l.name) best = pointSegmentDistance(gf, m.start, m.end);
      }
      EXPECT_LT(best, 1e-6) << l.name;
    }
  }
  // The left touch line is on the left of the image and never wraps to the right; the goal line
  // behind is not in view.
  bool seen_left = false;
  for (const auto& l : t.field.lines) {
    if (l.name == "touch line left") {
      seen_left = true;
      EXPECT_LT(std::max(l.start_px.x(), l.end_px.x()), w / 2);
    }
    EXPECT_NE(l.name, "goal line own");
  }
  EXPECT_TRUE(seen_left);
  // From the centre spot the circle is in view ahead; every X in view lies inside the image.
  s = makeWorld({0, 0, 0}, 0.5, 0.3);
  t = computeFrameTruth(s, field, {}, ScoringParams{});
  EXPECT_TRUE(t.field.centre_circle_in_view);
  for (const auto& i : t.field.intersections) {
    EXPECT_GE(i.position_px.x(), 0);
    EXPECT_LE(i.position_px.x(), w);
  }
}

TEST(TruthInImage, IntersectionsAndMarksInViewNeedLinePixels) {
  // Look at the opponent penalty area from its front, 2 m away.
  WorldState s = makeWorld({0.85, 0, 0}, 0.5, 0.15);
  const FieldMarkings field = FieldMarkings::fromDimensions({});
  auto t = computeFrameTruth(s, field, {}, ScoringParams{});
  ASSERT_FALSE(t.field.penalty_marks.empty());
  ASSERT_FALSE(t.field.intersections.empty());
  // With an object map that shows no line at all, nothing is in view.
  s.object_map = emptyMap(320, 240);
  t = computeFrameTruth(s, field, {}, ScoringParams{});
  EXPECT_TRUE(t.field.penalty_marks.empty());
  EXPECT_TRUE(t.field.intersections.empty());
  EXPECT_TRUE(t.field.lines.empty());
}

TEST(Geometry, PolygonClipHullIou) {
  const std::vector<Eigen::Vector2d> square = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  EXPECT_NEAR(polygonArea(square), 4, 1e-12);
  EXPECT_NEAR(polygonArea(clipPolygonToRect(square, 10, 10)), 1, 1e-12);
  const auto hull = convexHull({{0, 0}, {2, 0}, {1, 1}, {2, 2}, {0, 2}});
  EXPECT_EQ(hull.size(), 4u);
  EXPECT_TRUE(insideConvex(hull, {1, 1.5}));
  EXPECT_FALSE(insideConvex(hull, {3, 1}));
  EXPECT_NEAR(boxIou({0, 0, 2, 2}, {1, 0, 3, 2}), 2.0 / 6.0, 1e-12);
  EXPECT_NEAR(boxIou({0, 0, 1, 1}, {2, 2, 3, 3}), 0, 1e-12);
  EXPECT_NEAR(wrapAngle(3 * kPi / 2), -kPi / 2, 1e-12);
  EXPECT_NEAR(wrapAngle(-kPi), kPi, 1e-12);
}

}  // namespace
}  // namespace colorfree
