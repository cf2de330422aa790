#include "colorfree/perception/pose_fit.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "colorfree/perception/field_lines.h"
#include "colorfree/perception/ignore_regions.h"
#include "synthetic_field.h"

namespace colorfree {
namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Vector2d fieldToRobot(const FieldPose& pose, const Eigen::Vector2d& p) {
  const double c = std::cos(pose.heading_rad), s = std::sin(pose.heading_rad);
  const Eigen::Vector2d d = p - Eigen::Vector2d(pose.x_m, pose.y_m);
  return {c * d.x() + s * d.y(), -s * d.x() + c * d.y()};
}

// Features a robot at `pose` would see: pieces of the model lines near it, the intersections and
// the circle within `range`, each perturbed by `noise_m` (seeded).
FieldFeatures featuresFromModel(const FieldPose& pose, double range, double noise_m, std::uint64_t seed) {
  const FieldModel model(FieldDimensions{});
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n(0, noise_m);
  const auto jitter = [&](Eigen::Vector2d p) {
    if (noise_m > 0) p += Eigen::Vector2d(n(rng), n(rng));
    return p;
  };
  FieldFeatures f;
  const Eigen::Vector2d at(pose.x_m, pose.y_m);
  for (const auto& l : model.lines) {
    // The part of the segment within range.
    const Eigen::Vector2d u = (l.b - l.a).normalized();
    const double len = (l.b - l.a).norm();
    const double t0 = std::clamp((at - l.a).dot(u) - range, 0.0, len);
    const double t1 = std::clamp((at - l.a).dot(u) + range, 0.0, len);
    const Eigen::Vector2d a = l.a + t0 * u, b = l.a + t1 * u;
    if (t1 - t0 < 0.3 || ((a + b) / 2 - at).norm() > range) continue;
    LinePercept p;
    p.start_in_robot = jitter(fieldToRobot(pose, a));
    p.end_in_robot = jitter(fieldToRobot(pose, b));
    f.lines.push_back(p);
  }
  for (const auto& x : model.intersections) {
    if ((x.position - at).norm() > range) continue;
    IntersectionPercept p;
    p.type = x.type;
    p.position_in_robot = jitter(fieldToRobot(pose, x.position));
    f.intersections.push_back(p);
  }
  if ((model.centre_circle_centre - at).norm() < range) {
    f.centre_circle = CircleMarkPercept{jitter(fieldToRobot(pose, model.centre_circle_centre)), {}};
  }
  return f;
}

double positionError(const FieldPose& a, const FieldPose& b) {
  return std::hypot(a.x_m - b.x_m, a.y_m - b.y_m);
}

TEST(FieldModel, HasTheSplFieldsMarkings) {
  const FieldModel m(FieldDimensions{});
  EXPECT_EQ(m.lines.size(), 17u);
  EXPECT_EQ(m.penalty_marks.size(), 2u);
  int l = 0, t = 0, x = 0;
  for (const auto& i : m.intersections) {
    l += i.type == IntersectionType::kL;
    t += i.type == IntersectionType::kT;
    x += i.type == IntersectionType::kX;
  }
  EXPECT_EQ(l, 12);
  EXPECT_EQ(t, 10);
  EXPECT_EQ(x, 2);
  EXPECT_DOUBLE_EQ(m.penalty_marks[1].x(), 4.5 - 1.3);
}

TEST(PoseFit, RecoversThePoseFromExactFeatures) {
  const PoseFitter fitter;
  for (const FieldPose truth : {FieldPose{-1.2, 0.4, 0.3}, FieldPose{3.0, -1.0, -2.0}, FieldPose{-3.9, 2.5, 2.8}}) {
    const FieldFeatures f = featuresFromModel(truth, 2.5, 0, 1);
    ASSERT_GE(f.lines.size(), 2u);
    const FieldPose guess{truth.x_m + 0.25, truth.y_m - 0.2, truth.heading_rad + 0.1};
    const PoseFitResult r = fitter.fit(f, guess);
    EXPECT_TRUE(r.ok);
    EXPECT_LT(positionError(r.pose, truth), 1e-6) << r.pose.x_m << " " << r.pose.y_m;
    EXPECT_NEAR(std::remainder(r.pose.heading_rad - truth.heading_rad, 2 * kPi), 0, 1e-6);
    EXPECT_LT(r.rms_residual_m, 1e-6);
    // The guess was wrong: the fit moved.
    EXPECT_GT(positionError(guess, truth), 0.3);
  }
}

TEST(PoseFit, NoisyFeaturesGiveACentimetreError) {
  const PoseFitter fitter;
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> ux(-4.0, 4.0), uy(-2.5, 2.5), ut(-kPi, kPi), off(-0.2, 0.2);
  double sum = 0;
  int n = 0;
  for (int i = 0; i < 40; ++i) {
    const FieldPose truth{ux(rng), uy(rng), ut(rng)};
    const FieldFeatures f = featuresFromModel(truth, 3.0, 0.02, 100 + i);
    const PoseFitResult r = fitter.fit(f, {truth.x_m + off(rng), truth.y_m + off(rng), truth.heading_rad + off(rng) / 2});
    if (!r.ok) continue;
    sum += positionError(r.pose, truth);
    ++n;
  }
  ASSERT_GE(n, 30);
  EXPECT_LT(sum / n, 0.03);
}

TEST(PoseFit, AHeadingErrorDoesNotSlideTheFitOntoTheNextPattern) {
  // What the field-line stage found on a rendered top-camera frame from the centre spot looking at
  // the far goal (robot frame, metres): the penalty area's front line, the goal line in two
  // pieces, the goal area's lines and side lines, two L intersections. A guess 5 degrees off moves
  // them 0.35 m sideways and the goal area's side lines (y = 1.1) then lie nearer the penalty
  // area's (y = 2.0): the fit must take the heading from the lines' directions first.
  FieldFeatures f;
  const double lines[][4] = {{2.856, -1.645, 2.856, 1.640}, {4.476, -1.920, 4.476, -0.881},
                             {4.459, 2.011, 4.484, 1.198},  {3.811, 1.975, 4.491, 2.190},
                             {3.909, 1.119, 4.482, 1.060},  {3.907, 1.103, 3.907, 0.536},
                             {3.907, -0.543, 3.907, -1.110}};
  for (const auto& l : lines) {
    LinePercept p;
    p.start_in_robot = {l[0], l[1]};
    p.end_in_robot = {l[2], l[3]};
    f.lines.push_back(p);
  }
  for (const Eigen::Vector2d& x : {Eigen::Vector2d(4.488, 1.059), Eigen::Vector2d(3.907, 1.119)}) {
    IntersectionPercept p;
    p.type = IntersectionType::kL;
    p.position_in_robot = x;
    f.intersections.push_back(p);
  }
  const FieldPose truth{0, 0, 0};
  const PoseFitter fitter;
  for (const double sign : {1.0, -1.0}) {
    const FieldPose guess{0.14, 0.14 * sign, sign * 5 * kPi / 180};
    const PoseFitResult r = fitter.fit(f, guess);
    ASSERT_TRUE(r.ok);
    EXPECT_LT(positionError(r.pose, truth), 0.08) << r.pose.x_m << " " << r.pose.y_m;
  }
}

TEST(PoseFit, ParallelLinesAloneDoNotFixThePose) {
  FieldFeatures f;
  LinePercept l;
  l.start_in_robot = {1.0, -1.0};
  l.end_in_robot = {1.0, 1.0};
  f.lines.push_back(l);
  const PoseFitResult r = PoseFitter().fit(f, {-1.0, 0.1, 0});
  EXPECT_FALSE(r.ok);
  EXPECT_FALSE(PoseFitter().fit(FieldFeatures{}, {0, 0, 0}).ok);
}

TEST(PoseFit, FromDetectedFeaturesOfASyntheticFrame) {
  // The paper's measure: the pose from the features the detector found vs the true pose.
  const FieldPose truth{-2.0, 0.3, 0.1};
  const CameraModel cam = test::testCamera(22);
  test::SyntheticScene scene = test::sceneFromField(FieldDimensions{}, truth);
  scene.seed = 11;
  const GrayImage image = test::renderScene(cam, scene);
  const IgnoreMask mask = IgnoreMask::combine(FieldBoundaryDetector().run(image.view(), cam),
                                              BodyContourProvider().run(cam), 640, 480);
  const FieldLineResult detected = FieldLineDetector().run(image.view(), cam, mask);
  const PoseFitResult r = PoseFitter().fit(detected.features, {truth.x_m + 0.2, truth.y_m - 0.15, truth.heading_rad + 0.05});
  ASSERT_TRUE(r.ok);
  EXPECT_LT(positionError(r.pose, truth), 0.04);
  EXPECT_NEAR(r.pose.heading_rad, truth.heading_rad, 0.02);
}

}  // namespace
}  // namespace colorfree
