// The truth projected by groundtruth/ against what MuJoCo renders (label sim).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "colorfree/groundtruth/field_markings.h"
#include "colorfree/groundtruth/truth_in_image.h"
#include "colorfree/sim/world.h"
#include "test_support.h"

namespace colorfree {
namespace {

using sim::NaoCamera;
using sim::NaoState;
using sim::World;

// How far a robot's rendered pixels may poke out of its projected box, and how much box may stay
// empty on each side: the box model is an upright cuboid while the NAO swings its arms and legs.
constexpr double kRobotBoxOutsidePx = 3.0;
constexpr double kRobotBoxSlackFraction = 0.25;  // of the box's width or height

struct Scene {
  WorldState state;
  std::vector<FieldPose> robots;
};

WorldState renderState(World& world, NaoCamera cam, int w, int h, const FieldPose& observer,
                       const std::vector<FieldPose>& robots, const Eigen::Vector3d& ball) {
  WorldState s;
  s.observer = observer;
  s.camera.model = world.cameraModel(cam, w, h);
  s.camera.camera_to_field = world.cameraToField(cam);
  for (std::size_t i = 0; i < robots.size(); ++i) {
    RobotTruth r;
    r.index = static_cast<int>(i);
    r.pose = robots[i];
    s.robots.push_back(r);
  }
  s.ball.present = true;
  s.ball.position_m = ball;
  s.ball.radius_m = FieldDimensions{}.ballRadius();
  s.object_map = world.render(cam, w, h, true).object_map;
  return s;
}

void dump(const std::string& name, const GrayImage& gray, const FrameTruth& t) {
  cv::Mat g(gray.height(), gray.width(), CV_8UC1, const_cast<std::uint8_t*>(gray.data()));
  cv::Mat bgr;
  cv::cvtColor(g, bgr, cv::COLOR_GRAY2BGR);
  cv::resize(bgr, bgr, cv::Size(), 2, 2, cv::INTER_NEAREST);
  auto pt = [](const Eigen::Vector2d& p) { return cv::Point(int(p.x() * 2), int(p.y() * 2)); };
  for (const auto& l : t.field.lines) cv::line(bgr, pt(l.start_px), pt(l.end_px), {255, 128, 0}, 1);
  for (const auto& l : t.field.circle_pieces) cv::line(bgr, pt(l.start_px), pt(l.end_px), {255, 128, 0}, 1);
  for (const auto& i : t.field.intersections) cv::drawMarker(bgr, pt(i.position_px), {0, 0, 255}, cv::MARKER_CROSS, 10);
  for (const auto& r : t.robots) {
    if (!r.in_view) continue;
    cv::rectangle(bgr, pt({r.box.x0, r.box.y0}), pt({r.box.x1, r.box.y1}), {0, 255, 0}, 1);
    cv::rectangle(bgr, pt({r.feet_box.x0, r.feet_box.y0}), pt({r.feet_box.x1, r.feet_box.y1}), {0, 200, 255}, 1);
    cv::circle(bgr, pt(r.left_foot_px), 3, {255, 0, 255}, -1);
    cv::circle(bgr, pt(r.right_foot_px), 3, {255, 0, 255}, -1);
  }
  if (t.ball.in_view) cv::circle(bgr, pt(t.ball.centre_px), int(t.ball.radius_px * 2), {0, 255, 0}, 1);
  cv::imwrite(::testing::TempDir() + "/" + name + ".png", bgr);
}

class TruthVsRender : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    sim::SceneSpec spec;
    spec.field = FieldDimensions::loadDefault();
    spec.robot_count = 3;
    spec.jersey_gray = {0.2, 0.8, 0.5};
    spec.shadows = false;
    spec.multisamples = 0;
    spec.max_width_px = 320;
    spec.max_height_px = 240;
    spec.seed = 5;
    world_ = new World(spec);
  }
  static void TearDownTestSuite() {
    delete world_;
    world_ = nullptr;
  }
  static World* world_;
};
World* TruthVsRender::world_ = nullptr;

FrameTruth renderAndProject(World& world, NaoCamera cam, const FieldPose& observer, double head_pitch,
                            double head_yaw, const std::vector<FieldPose>& robots,
                            const std::vector<double>& speeds, const Eigen::Vector3d& ball,
                            const std::string& dump_name, WorldState* out_state = nullptr) {
  NaoState obs;
  obs.pose = observer;
  obs.posture.head_pitch = head_pitch;
  obs.posture.head_yaw = head_yaw;
  world.setObserver(obs);
  for (std::size_t i = 0; i < robots.size(); ++i) {
    NaoState r;
    r.pose = robots[i];
    r.posture = sim::walkPosture(0.25, speeds[i]);
    world.setRobot(static_cast<int>(i), r);
  }
  world.setBall(ball, Eigen::Quaterniond::Identity());
  WorldState s = renderState(world, cam, 320, 240, observer, robots, ball);
  const FieldDimensions dims = FieldDimensions::loadDefault();
  const FrameTruth t = computeFrameTruth(s, FieldMarkings::fromDimensions(dims), dims, ScoringParams::loadDefault());
  dump(dump_name, world.render(cam, 320, 240, false).gray, t);
  if (out_state) *out_state = s;
  return t;
}

void expectBallCovered(const WorldState& s, const FrameTruth& t) {
  ASSERT_TRUE(t.ball.in_view);
  int n = 0;
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (int y = 0; y < s.object_map.height; ++y) {
    for (int x = 0; x < s.object_map.width; ++x) {
      if (s.object_map.at(x, y) != kObjectBall) continue;
      const Eigen::Vector2d c(x + 0.5, y + 0.5);
      EXPECT_LE((c - t.ball.centre_px).norm(), t.ball.radius_px + 0.75) << "ball pixel " << x << "," << y;
      sum += c;
      ++n;
    }
  }
  ASSERT_GT(n, 10);
  EXPECT_LT((sum / n - t.ball.centre_px).norm(), 0.5);
  EXPECT_NEAR(t.ball.visible_fraction, 1.0, 0.12);
}

void expectRobotBounded(const WorldState& s, const RobotInImage& r) {
  const std::uint16_t label = static_cast<std::uint16_t>(kObjectRobotBase + r.index);
  PixelBox b{1e9, 1e9, -1e9, -1e9};
  int n = 0;
  for (int y = 0; y < s.object_map.height; ++y) {
    for (int x = 0; x < s.object_map.width; ++x) {
      if (s.object_map.at(x, y) != label) continue;
      b.x0 = std::min<double>(b.x0, x);
      b.y0 = std::min<double>(b.y0, y);
      b.x1 = std::max<double>(b.x1, x + 1);
      b.y1 = std::max<double>(b.y1, y + 1);
      ++n;
    }
  }
  ASSERT_GT(n, 50) << "robot " << r.index;
  // Only a robot seen whole shows its whole outline.
  const bool whole = r.visible_fraction > 0.9 && r.box.y0 > 0 && r.box.x0 > 0 &&
                     r.box.x1 < s.object_map.width && r.box.y1 < s.object_map.height;
  std::printf("robot %d: pixels [%.0f %.0f %.0f %.0f], box [%.1f %.1f %.1f %.1f], visible %.2f\n", r.index,
              b.x0, b.y0, b.x1, b.y1, r.box.x0, r.box.y0, r.box.x1, r.box.y1, r.visible_fraction);
  // The box bounds the robot's pixels...
  EXPECT_GE(b.x0, r.box.x0 - kRobotBoxOutsidePx) << r.index;
  EXPECT_GE(b.y0, r.box.y0 - kRobotBoxOutsidePx) << r.index;
  EXPECT_LE(b.x1, r.box.x1 + kRobotBoxOutsidePx) << r.index;
  EXPECT_LE(b.y1, r.box.y1 + kRobotBoxOutsidePx) << r.index;
  // ... and is not much larger than they are.
  if (!whole) return;
  EXPECT_LE(b.x0 - r.box.x0, kRobotBoxSlackFraction * r.box.width()) << r.index;
  EXPECT_LE(r.box.x1 - b.x1, kRobotBoxSlackFraction * r.box.width()) << r.index;
  EXPECT_LE(b.y0 - r.box.y0, kRobotBoxSlackFraction * r.box.height()) << r.index;
  EXPECT_LE(r.box.y1 - b.y1, kRobotBoxSlackFraction * r.box.height()) << r.index;
}

// Both ways: the projected lines run over line pixels (where the ground is near enough for a 5 cm
// line to be a few pixels wide), and every line pixel lies on a model line within the line's half
// width plus the pixel's footprint on the ground.
void expectLinesAgree(const WorldState& s, const FrameTruth& t) {
  const CameraModel& cam = s.camera.model;
  const Eigen::Isometry3d robot_to_field = robotToField(s.observer);
  int on = 0, all = 0;
  for (const auto& l : t.field.lines) {
    for (int k = 0; k <= 40; ++k) {
      const Eigen::Vector2d p = l.start_px + (l.end_px - l.start_px) * (k / 40.0);
      const auto g = cam.pixelToGround(p);
      if (!g || (*g - cam.position().head<2>()).norm() > 3.0) continue;
      const int x = std::clamp(int(p.x()), 0, 319), y = std::clamp(int(p.y()), 0, 239);
      bool line = false;
      for (int dy = -2; dy <= 2; ++dy)
        for (int dx = -2; dx <= 2; ++dx) {
          const int xx = std::clamp(x + dx, 0, 319), yy = std::clamp(y + dy, 0, 239);
          line = line || s.object_map.at(xx, yy) == kObjectLine;
        }
      // A robot or the ball may stand on the line.
      const std::uint16_t here = s.object_map.at(x, y);
      if (here >= kObjectRobotBase || here == kObjectBall) continue;
      on += line;
      ++all;
    }
  }
  ASSERT_GT(all, 20);
  EXPECT_GT(double(on) / all, 0.95);

  const FieldDimensions dims;
  const FieldMarkings model = FieldMarkings::fromDimensions(dims);
  int checked = 0, off = 0;
  for (int y = 0; y < s.object_map.height; y += 2) {
    for (int x = 0; x < s.object_map.width; x += 2) {
      if (s.object_map.at(x, y) != kObjectLine) continue;
      const Eigen::Vector2d c(x + 0.5, y + 0.5);
      const auto g = cam.pixelToGround(c);
      const auto gx = cam.pixelToGround(c + Eigen::Vector2d(1, 0));
      const auto gy = cam.pixelToGround(c + Eigen::Vector2d(0, 1));
      if (!g || !gx || !gy) continue;
      const double footprint = std::max((*gx - *g).norm(), (*gy - *g).norm());
      const Eigen::Vector2d f = (robot_to_field * Eigen::Vector3d(g->x(), g->y(), 0)).head<2>();
      double best = std::abs((f - model.centre_circle_centre).norm() - model.centre_circle_radius_m);
      for (const auto& m : model.lines) best = std::min(best, pointSegmentDistance(f, m.start, m.end));
      // Penalty marks and the centre mark are crosses of size penalty_mark_size_m.
      for (const auto& m : model.penalty_marks) best = std::min(best, std::max(0.0, (f - m).norm() - dims.penalty_mark_size_m));
      best = std::min(best, std::max(0.0, f.norm() - dims.penalty_mark_size_m));
      ++checked;
      if (best > dims.line_width_m / 2 + footprint + 0.005) ++off;
    }
  }
  ASSERT_GT(checked, 20);
  EXPECT_EQ(off, 0) << "of " << checked << " line pixels";
}

TEST_F(TruthVsRender, TopCameraBallRobotsAndLines) {
  WorldState s;
  const std::vector<FieldPose> robots = {{1.6, 0.35, 2.5}, {2.6, -0.5, 1.0}, {3.4, 0.6, -2.0}};
  const FrameTruth t = renderAndProject(*world_, NaoCamera::kTop, {0, 0, 0}, 0.35, 0, robots,
                                        {0, 0.15, 0}, {1.0, -0.2, 0.05}, "truth_top", &s);
  // The camera on the field agrees with the camera model and the observer's pose.
  const Eigen::Isometry3d via_robot = robotToField(s.observer) * s.camera.model.cameraToRobot();
  EXPECT_LT((via_robot.matrix() - s.camera.camera_to_field.matrix()).norm(), 1e-6);
  expectBallCovered(s, t);
  ASSERT_EQ(t.robots.size(), 3u);
  for (const auto& r : t.robots) {
    ASSERT_TRUE(r.in_view) << r.index;
    expectRobotBounded(s, r);
  }
  expectLinesAgree(s, t);
}

TEST_F(TruthVsRender, BottomCameraTurnedHead) {
  WorldState s;
  const std::vector<FieldPose> robots = {{0.9, 0.5, 3.0}, {5, 5, 0}, {-3, 0, 0}};
  const FrameTruth t = renderAndProject(*world_, NaoCamera::kBottom, {-1.0, 0.5, 0.3}, 0.1, 0.3,
                                        {{-0.3, 0.95, 3.0}, {5, 5, 0}, {-3, 0, 0}}, {0, 0, 0},
                                        {-0.55, 0.75, 0.05}, "truth_bottom", &s);
  (void)robots;
  expectBallCovered(s, t);
  expectLinesAgree(s, t);
  EXPECT_FALSE(t.robots[2].in_view);  // behind the observer
}

}  // namespace
}  // namespace colorfree
