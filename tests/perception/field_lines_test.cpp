#include "colorfree/perception/field_lines.h"

#include <gtest/gtest.h>

#include <cmath>
#include <tuple>

#include "colorfree/perception/error.h"
#include "colorfree/perception/ignore_regions.h"
#include "colorfree/perception/pose_fit.h"
#include "synthetic_field.h"

namespace colorfree {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Where a detected feature may be, around the truth: a fixed part and a part growing with
// distance (a pixel covers more ground farther away).
double allowedError(const Eigen::Vector2d& in_robot) { return 0.06 + 0.03 * in_robot.norm(); }

struct Truth {
  std::vector<FieldModel::Segment> lines;
  std::vector<FieldModel::Intersection> intersections;
  Eigen::Vector2d circle_centre;
  std::vector<Eigen::Vector2d> penalty_marks;
};

Truth truthInRobot(const FieldPose& pose) {
  const FieldModel model(FieldDimensions{});
  const double c = std::cos(pose.heading_rad), s = std::sin(pose.heading_rad);
  const auto toRobot = [&](const Eigen::Vector2d& p) {
    const Eigen::Vector2d d = p - Eigen::Vector2d(pose.x_m, pose.y_m);
    return Eigen::Vector2d(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
  };
  Truth t;
  for (const auto& l : model.lines) t.lines.push_back({toRobot(l.a), toRobot(l.b)});
  for (const auto& x : model.intersections) t.intersections.push_back({x.type, toRobot(x.position)});
  t.circle_centre = toRobot(model.centre_circle_centre);
  for (const auto& m : model.penalty_marks) t.penalty_marks.push_back(toRobot(m));
  return t;
}

bool onSomeTrueLine(const LinePercept& l, const Truth& truth) {
  const Eigen::Vector2d d = (l.end_in_robot - l.start_in_robot).normalized();
  for (const auto& seg : truth.lines) {
    const Eigen::Vector2d u = (seg.b - seg.a).normalized();
    if (std::abs(u.dot(d)) < std::cos(6 * kPi / 180)) continue;
    const Eigen::Vector2d n(-u.y(), u.x());
    const double len = (seg.b - seg.a).norm();
    bool ok = true;
    for (const auto& p : {l.start_in_robot, l.end_in_robot}) {
      const double t = (p - seg.a).dot(u);
      ok = ok && std::abs((p - seg.a).dot(n)) <= allowedError(p) && t > -0.3 && t < len + 0.3;
    }
    if (ok) return true;
  }
  return false;
}

const char* typeName(IntersectionType t) {
  return t == IntersectionType::kL ? "L" : t == IntersectionType::kT ? "T" : "X";
}

bool matchesTrueIntersection(const IntersectionPercept& x, const Truth& truth) {
  for (const auto& t : truth.intersections) {
    if (t.type == x.type && (t.position - x.position_in_robot).norm() <= allowedError(t.position)) return true;
  }
  return false;
}

struct Detected {
  FieldLineResult result;
  Truth truth;
};

Detected detect(const FieldPose& pose, double pitch_deg, double gradient, std::uint64_t seed,
                double pixel_noise = 5) {
  const CameraModel cam = test::testCamera(pitch_deg);
  test::SyntheticScene scene = test::sceneFromField(FieldDimensions{}, pose);
  scene.gradient = gradient;
  scene.seed = seed;
  scene.pixel_noise = pixel_noise;
  const GrayImage image = test::renderScene(cam, scene);
  const IgnoreMask mask = IgnoreMask::combine(FieldBoundaryDetector().run(image.view(), cam),
                                              BodyContourProvider().run(cam), 640, 480);
  return {FieldLineDetector().run(image.view(), cam, mask, true), truthInRobot(pose)};
}

// Scenes: robot pose on the field and camera pitch; lighting: gradient; noise seed.
using SceneParam = std::tuple<int, double, std::uint64_t>;
struct SceneSpec {
  FieldPose pose;
  double pitch_deg;
};
const SceneSpec kScenes[] = {
    {{-2.0, 0.0, 0.0}, 22},                  // centre circle and halfway line ahead
    {{1.6, 0.4, -10 * kPi / 180}, 25},       // penalty mark, penalty area corners
    {{2.3, 1.0, 20 * kPi / 180}, 25},        // goal area corner, T on the goal line
    {{-3.5, 2.0, 150 * kPi / 180}, 22},      // towards the own corner and touch line
    {{0.0, -1.5, 90 * kPi / 180}, 20},       // across the halfway line and circle
};

class FieldLinesOnSyntheticField : public ::testing::TestWithParam<SceneParam> {};

TEST_P(FieldLinesOnSyntheticField, EverythingFoundIsWhereItWasDrawn) {
  const auto [scene, gradient, seed] = GetParam();
  const Detected d = detect(kScenes[scene].pose, kScenes[scene].pitch_deg, gradient, seed);
  const FieldFeatures& f = d.result.features;
  EXPECT_FALSE(f.lines.empty());
  for (const auto& l : f.lines) {
    EXPECT_TRUE(onSomeTrueLine(l, d.truth))
        << "line (" << l.start_in_robot.transpose() << ")-(" << l.end_in_robot.transpose() << ")";
  }
  for (const auto& x : f.intersections) {
    EXPECT_TRUE(matchesTrueIntersection(x, d.truth))
        << typeName(x.type) << " at " << x.position_in_robot.transpose();
  }
  if (f.centre_circle) {
    EXPECT_LE((f.centre_circle->centre_in_robot - d.truth.circle_centre).norm(),
              allowedError(d.truth.circle_centre));
  }
  for (const auto& m : f.penalty_marks) {
    bool near = false;
    for (const auto& t : d.truth.penalty_marks) near = near || (t - m.centre_in_robot).norm() <= allowedError(t);
    EXPECT_TRUE(near) << "penalty mark at " << m.centre_in_robot.transpose();
  }
}

INSTANTIATE_TEST_SUITE_P(Scenes, FieldLinesOnSyntheticField,
                         ::testing::Values(SceneParam{0, 0.0, 1}, SceneParam{0, 0.5, 2}, SceneParam{1, 0.0, 3},
                                           SceneParam{1, 0.5, 4}, SceneParam{2, 0.0, 5}, SceneParam{2, 0.5, 6},
                                           SceneParam{3, 0.0, 7}, SceneParam{3, 0.5, 8}, SceneParam{4, 0.0, 9},
                                           SceneParam{4, 0.5, 10}));

// Camera noise of sigma 10 (real NAO frames are about as noisy): the lines are still found, and
// only where drawn.
class FieldLinesUnderNoise : public ::testing::TestWithParam<std::tuple<int, double>> {};

TEST_P(FieldLinesUnderNoise, LinesFoundWhereDrawn) {
  const auto [scene, noise] = GetParam();
  const Detected clean = detect(kScenes[scene].pose, kScenes[scene].pitch_deg, 0.0, 40 + scene, 0);
  const Detected noisy = detect(kScenes[scene].pose, kScenes[scene].pitch_deg, 0.0, 40 + scene, noise);
  for (const auto& l : noisy.result.features.lines) {
    EXPECT_TRUE(onSomeTrueLine(l, noisy.truth))
        << "line (" << l.start_in_robot.transpose() << ")-(" << l.end_in_robot.transpose() << ")";
  }
  for (const auto& x : noisy.result.features.intersections) {
    EXPECT_TRUE(matchesTrueIntersection(x, noisy.truth)) << typeName(x.type) << " at " << x.position_in_robot.transpose();
  }
  // The painted lines seen without noise are still seen, but for at most one (a thin far one).
  const auto seen = [](const Detected& d) {
    int n = 0;
    for (const auto& seg : d.truth.lines) {
      Truth one;
      one.lines = {seg};
      bool found = false;
      for (const auto& l : d.result.features.lines) found = found || onSomeTrueLine(l, one);
      n += found;
    }
    return n;
  };
  ASSERT_GE(seen(clean), 2);
  EXPECT_GE(seen(noisy), seen(clean) - 1) << "painted lines seen without noise " << seen(clean);
}

INSTANTIATE_TEST_SUITE_P(Noise, FieldLinesUnderNoise,
                         ::testing::Combine(::testing::Values(0, 1, 2, 3, 4), ::testing::Values(10.0)));

TEST(FieldLines, NothingOnStrongNoise) {
  const CameraModel cam = test::testCamera(22);
  const FieldLineDetector detector;
  const IgnoreMask all = IgnoreMask::all(640, 480);
  for (double sigma : {10.0, 25.0, 40.0}) {
    for (std::uint64_t seed : {5u, 6u}) {
      const GrayImage noise = test::noiseImage(640, 480, 90, sigma, seed);
      const FieldLineResult r = detector.run(noise.view(), cam, all);
      EXPECT_TRUE(r.features.lines.empty()) << sigma << " " << r.features.lines.size() << " lines";
      EXPECT_TRUE(r.features.intersections.empty()) << sigma;
      EXPECT_FALSE(r.features.centre_circle) << sigma;
      EXPECT_TRUE(r.features.penalty_marks.empty()) << sigma;
    }
  }
}

class FieldLinesLighting : public ::testing::TestWithParam<double> {};

TEST_P(FieldLinesLighting, CentreCircleHalfwayLineAndItsCrossings) {
  const Detected d = detect(kScenes[0].pose, kScenes[0].pitch_deg, GetParam(), 7);
  const FieldFeatures& f = d.result.features;
  ASSERT_TRUE(f.centre_circle);
  EXPECT_NEAR(f.centre_circle->centre_in_robot.x(), 2.0, 0.08);
  EXPECT_NEAR(f.centre_circle->centre_in_robot.y(), 0.0, 0.08);
  EXPECT_FALSE(d.result.circle_points_in_robot.empty());
  // The halfway line, 2 m ahead, across the whole image.
  bool halfway = false;
  for (const auto& l : f.lines) {
    halfway = halfway || (std::abs(l.start_in_robot.x() - 2.0) < 0.05 && std::abs(l.end_in_robot.x() - 2.0) < 0.05 &&
                          std::abs(l.end_in_robot.y() - l.start_in_robot.y()) > 1.5);
  }
  EXPECT_TRUE(halfway);
  int crossings = 0;
  for (const auto& x : f.intersections) {
    if (x.type == IntersectionType::kX && std::abs(x.position_in_robot.x() - 2.0) < 0.1 &&
        std::abs(std::abs(x.position_in_robot.y()) - 0.75) < 0.1) {
      ++crossings;
    }
  }
  EXPECT_EQ(crossings, 2);
  // Spots lie on painted ground and their image and ground positions agree.
  const CameraModel cam = test::testCamera(kScenes[0].pitch_deg);
  ASSERT_GT(d.result.spots.size(), 100u);
  for (const auto& s : d.result.spots) {
    const auto px = cam.robotToPixel({s.position_in_robot.x(), s.position_in_robot.y(), 0});
    ASSERT_TRUE(px);
    EXPECT_NEAR((*px - s.position_px).norm(), 0, 1e-6);
  }
}

TEST_P(FieldLinesLighting, PenaltyMarkAndPenaltyAreaCorners) {
  const Detected d = detect(kScenes[1].pose, kScenes[1].pitch_deg, GetParam(), 8);
  const FieldFeatures& f = d.result.features;
  ASSERT_EQ(f.penalty_marks.size(), 1u);
  EXPECT_LE((f.penalty_marks[0].centre_in_robot - d.truth.penalty_marks[1]).norm(), 0.08);
  // Goal line T's with the penalty area and the penalty area's front corners (L).
  int ts = 0, ls = 0;
  for (const auto& x : f.intersections) {
    ts += x.type == IntersectionType::kT;
    ls += x.type == IntersectionType::kL;
  }
  EXPECT_EQ(ts, 2);
  EXPECT_EQ(ls, 2);
  EXPECT_FALSE(f.centre_circle);
}

TEST_P(FieldLinesLighting, GoalAreaCorner) {
  const Detected d = detect(kScenes[2].pose, kScenes[2].pitch_deg, GetParam(), 9);
  const FieldFeatures& f = d.result.features;
  // The goal area's corner at (3.9, 1.1) on the field, 1.5 m ahead: the only L within 2 m.
  bool found = false;
  for (const auto& t : d.truth.intersections) {
    if (t.type != IntersectionType::kL) continue;
    for (const auto& x : f.intersections) {
      if (x.type == IntersectionType::kL && (x.position_in_robot - t.position).norm() < 0.1 &&
          t.position.norm() < 2.0) {
        found = true;
      }
    }
  }
  EXPECT_TRUE(found);
}

INSTANTIATE_TEST_SUITE_P(Gradients, FieldLinesLighting, ::testing::Values(0.0, 0.5));

TEST(FieldLines, NothingOnNoiseOrBlankFrames) {
  const CameraModel cam = test::testCamera(22);
  const FieldLineDetector detector;
  const IgnoreMask all = IgnoreMask::all(640, 480);
  const auto expectEmpty = [](const FieldLineResult& r) {
    EXPECT_TRUE(r.features.lines.empty());
    EXPECT_TRUE(r.features.intersections.empty());
    EXPECT_FALSE(r.features.centre_circle);
    EXPECT_TRUE(r.features.penalty_marks.empty()) << r.spots.size() << " spots";
  };
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const GrayImage noise = test::noiseImage(640, 480, 80, 8, seed);
    expectEmpty(detector.run(noise.view(), cam, all));
    test::SyntheticScene empty;
    empty.seed = seed;
    empty.gradient = 0.5;
    const GrayImage carpet = test::renderScene(cam, empty);
    const FieldLineResult r = detector.run(carpet.view(), cam, all);
    expectEmpty(r);
    EXPECT_TRUE(r.spots.empty());
  }
  for (std::uint8_t v : {std::uint8_t{0}, std::uint8_t{255}}) {
    const GrayImage flat(640, 480, v);
    const FieldLineResult r = detector.run(flat.view(), cam, all);
    expectEmpty(r);
    EXPECT_TRUE(r.spots.empty());
  }
}

TEST(FieldLines, WrongImageSizeIsAnError) {
  const CameraModel cam = test::testCamera(22);
  const GrayImage small(320, 240, 80);
  EXPECT_THROW(FieldLineDetector().run(small.view(), cam, IgnoreMask::all(320, 240)), Error);
  const GrayImage right(640, 480, 80);
  EXPECT_THROW(FieldLineDetector().run(right.view(), cam, IgnoreMask::all(320, 240)), Error);
}

TEST(FieldLines, UprightWhitePartIsNotALine) {
  // A robot's white leg: a bar of constant pixel width standing up from the ground.
  const CameraModel cam = test::testCamera(22);
  test::SyntheticScene scene;
  GrayImage image = test::renderScene(cam, scene);
  for (int y = 120; y < 330; ++y) {
    for (int x = 300; x < 324; ++x) image.at(x, y) = 200;
  }
  const FieldLineResult r = FieldLineDetector().run(image.view(), cam, IgnoreMask::all(640, 480), true);
  EXPECT_TRUE(r.features.lines.empty());
  bool not_on_ground = false;
  for (const auto& rej : r.rejected) not_on_ground = not_on_ground || rej.reason == LineRejectReason::kNotOnGround;
  EXPECT_TRUE(not_on_ground);
}

// A robot standing on a line across the view: its two feet (white blocks with dark soles over the
// line) join the line as a few spots, some scanned the other way with widths nothing like a painted
// line's there. The line is still on the ground: the width trend leaves out a few spots scanned the
// other way than most of the line's (width_trend_minority_fraction); with none left out the feet's spots
// made the line "not on the ground" (the penalty area's front line under a robot in
// scenes/orientation_static_lines.yaml).
TEST(FieldLines, ALineWithARobotStandingOnItIsOnTheGround) {
  const CameraModel cam = test::testCamera(22);
  test::SyntheticScene scene;
  scene.segments.push_back({{1.2, -1.5}, {1.2, 1.5}});
  const GrayImage clean = test::renderScene(cam, scene);
  GrayImage image = clean;
  const Eigen::Vector2d on_line = *cam.robotToPixel({1.2, 0, 0});
  for (const int cx : {static_cast<int>(on_line.x()) - 26, static_cast<int>(on_line.x()) + 26}) {
    const int bottom = static_cast<int>(on_line.y()) + 6;
    for (int y = bottom - 40; y <= bottom; ++y) {
      for (int x = cx - 20; x <= cx + 20; ++x) image.at(x, y) = y > bottom - 6 ? 30 : 220;
    }
  }
  const auto penaltyLine = [](const FieldLineResult& r) {
    return std::any_of(r.features.lines.begin(), r.features.lines.end(), [](const LinePercept& l) {
      return std::abs(l.start_in_robot.x() - 1.2) < 0.05 && std::abs(l.end_in_robot.x() - 1.2) < 0.05 &&
             (l.end_in_robot - l.start_in_robot).norm() > 1.0;
    });
  };
  FieldLineParams none_left_out = FieldLineParams::loadDefault();
  ASSERT_GT(none_left_out.width_trend_minority_fraction, 0);
  EXPECT_TRUE(penaltyLine(FieldLineDetector().run(clean.view(), cam, IgnoreMask::all(640, 480))));
  EXPECT_TRUE(penaltyLine(FieldLineDetector().run(image.view(), cam, IgnoreMask::all(640, 480))));
  none_left_out.width_trend_minority_fraction = 0;
  EXPECT_FALSE(penaltyLine(FieldLineDetector(none_left_out).run(image.view(), cam, IgnoreMask::all(640, 480))));
}

TEST(FieldLines, BallIsNotAPenaltyMark) {
  // The penalty mark scene, with a ball-like blob 0.6 m left of the mark.
  const FieldPose pose = kScenes[1].pose;
  const CameraModel cam = test::testCamera(kScenes[1].pitch_deg);
  test::SyntheticScene scene = test::sceneFromField(FieldDimensions{}, pose);
  scene.seed = 12;
  GrayImage image = test::renderScene(cam, scene);
  const Eigen::Vector2d mark = truthInRobot(pose).penalty_marks[1];
  const Eigen::Vector2d ball = mark + Eigen::Vector2d(0, 0.6);
  // Drawn flat on the ground (as the bottom camera sees a ball from above): a 10 cm white disc
  // with two black patches, so that only its dark patches tell it from a painted cross.
  const Eigen::Vector2d c = *cam.robotToPixel({ball.x(), ball.y(), 0});
  for (int y = static_cast<int>(c.y()) - 40; y <= static_cast<int>(c.y()) + 40; ++y) {
    for (int x = static_cast<int>(c.x()) - 40; x <= static_cast<int>(c.x()) + 40; ++x) {
      const auto g = cam.pixelToGround({x + 0.5, y + 0.5});
      if (!g || (*g - ball).norm() > 0.05) continue;
      const Eigen::Vector2d d = *g - ball;
      const bool patch = (d - Eigen::Vector2d(0.02, 0.015)).norm() < 0.018 ||
                         (d - Eigen::Vector2d(-0.02, -0.02)).norm() < 0.018;
      image.at(x, y) = patch ? 25 : 210;
    }
  }
  const IgnoreMask mask = IgnoreMask::all(640, 480);
  const FieldLineResult res = FieldLineDetector().run(image.view(), cam, mask);
  ASSERT_EQ(res.features.penalty_marks.size(), 1u);
  EXPECT_LE((res.features.penalty_marks[0].centre_in_robot - mark).norm(), 0.08);
  // Without the dark-patch test the ball is taken for a second mark: the test is what rejects it.
  FieldLineParams p;
  p.penalty_mark_max_dark_fraction = 1.0;
  EXPECT_EQ(FieldLineDetector(p).run(image.view(), cam, mask).features.penalty_marks.size(), 2u);
}

TEST(FieldLines, SameInputSameOutput) {
  const Detected a = detect(kScenes[0].pose, 22, 0.3, 5);
  const Detected b = detect(kScenes[0].pose, 22, 0.3, 5);
  ASSERT_EQ(a.result.spots.size(), b.result.spots.size());
  ASSERT_EQ(a.result.features.lines.size(), b.result.features.lines.size());
  for (std::size_t i = 0; i < a.result.features.lines.size(); ++i) {
    EXPECT_EQ(a.result.features.lines[i].start_in_robot, b.result.features.lines[i].start_in_robot);
    EXPECT_EQ(a.result.features.lines[i].end_in_robot, b.result.features.lines[i].end_in_robot);
  }
}

}  // namespace
}  // namespace colorfree
