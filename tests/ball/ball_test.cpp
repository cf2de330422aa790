// Ball proposals and the ball detector on synthetic frames: a drawn ball at a known place on
// textured carpet, with a line through it, next to a drawn foot; nothing on blank carpet or a lone
// line crossing. Parameter files: strict, defaults equal the shipped files.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>

#include "colorfree/perception/ball_detector.h"
#include "colorfree/perception/ball_proposer.h"
#include "colorfree/perception/error.h"
#include "colorfree/perception/noise.h"
#include "colorfree/perception/param_file.h"
#include "colorfree/perception/pipeline.h"
#include "synthetic_ball.h"
#include "synthetic_field.h"

namespace colorfree {
namespace {

test::SyntheticScene carpetOnly(std::uint64_t seed) {
  test::SyntheticScene s;
  s.texture = 10;
  s.seed = seed;
  return s;
}

struct Found {
  std::vector<BallProposal> proposals;
  std::vector<BallPercept> balls;
};

Found runPipeline(const GrayImage& image, const CameraModel& cam) {
  static const Pipeline pipeline(PipelineConfig::loadDefault());
  Frame frame(image.view(), cam);
  pipeline.process(frame);
  return {*frame.ball_proposals, *frame.ball_percepts};
}

std::string describe(const std::vector<BallProposal>& props) {
  std::ostringstream out;
  out << "\nproposals:";
  for (const auto& p : props) out << "\n  (" << p.centre_px.transpose() << ") r=" << p.radius_px << " response " << p.response;
  return out.str();
}

// Index of the first proposal within the scorer's match rule (half the radius, at least 2 px).
int matchIndex(const std::vector<BallProposal>& props, const test::DrawnBall& b) {
  for (std::size_t i = 0; i < props.size(); ++i) {
    if ((props[i].centre_px - b.centre_px).norm() <= std::max(2.0, 0.5 * b.radius_px)) return static_cast<int>(i);
  }
  return -1;
}

bool detected(const std::vector<BallPercept>& balls, const test::DrawnBall& b) {
  for (const auto& p : balls) {
    if ((p.centre_px - b.centre_px).norm() <= std::max(2.0, 0.5 * b.radius_px)) return true;
  }
  return false;
}

class DrawnBallAt : public ::testing::TestWithParam<double> {};

TEST_P(DrawnBallAt, TexturedCarpetFoundWhereItIs) {
  const CameraModel cam = test::testCamera(22);
  GrayImage image = test::renderScene(cam, carpetOnly(3));
  const test::DrawnBall b = test::drawBall(image, cam, {GetParam(), 0.15});
  if (std::getenv("BALL_TEST_DUMP")) writeGrayPng(std::string(std::getenv("BALL_TEST_DUMP")) + ".png", image.view());
  const Found f = runPipeline(image, cam);
  const int i = matchIndex(f.proposals, b);
  ASSERT_GE(i, 0) << "no proposal at the ball (" << b.centre_px.transpose() << "), r=" << b.radius_px
                  << describe(f.proposals);
  EXPECT_NEAR(f.proposals[i].radius_px, b.radius_px, 0.25 * b.radius_px + 0.5);
  ASSERT_EQ(f.balls.size(), 1u);
  EXPECT_TRUE(detected(f.balls, b));
  ASSERT_TRUE(f.balls[0].position_in_robot);
  EXPECT_NEAR(f.balls[0].position_in_robot->x(), GetParam(), 0.12 * GetParam());
  EXPECT_NEAR(f.balls[0].position_in_robot->y(), 0.15, 0.1);
}

INSTANTIATE_TEST_SUITE_P(Distances, DrawnBallAt, ::testing::Values(0.8, 1.5, 3.0));

// A ball very close to the bottom camera (640x480, 0.47 m high, looking down 40-65 degrees): an
// expected radius of 50-70 px, more than the 16-px high-contrast windows (from 66 px the scan step
// is wider than a window), and partly cut by the lower and side borders. Only the proposal is
// checked: the nets (trained on 320x240 bottom-camera frames, radii up to ~35 px) miss most of
// these drawn balls (2026-12-01: 7 of 16 detected), which the proposer cannot change. The radius
// is not compared with the drawn ball's (the on-axis value; off the axis the ball projects larger,
// which the proposer's expected radius models).
struct CloseBall {
  double pitch_deg, x_m, y_m;
};

class CloseBallAt : public ::testing::TestWithParam<CloseBall> {};

TEST_P(CloseBallAt, Proposed) {
  const CloseBall c = GetParam();
  const CameraModel cam = test::testCamera(c.pitch_deg, 640, 480, 0.47);
  GrayImage image = test::renderScene(cam, carpetOnly(11));
  const test::DrawnBall b = test::drawBall(image, cam, {c.x_m, c.y_m});
  if (std::getenv("BALL_TEST_DUMP")) {
    writeGrayPng(std::string(std::getenv("BALL_TEST_DUMP")) + ".png", image.view());
  }
  const Found f = runPipeline(image, cam);
  EXPECT_GE(matchIndex(f.proposals, b), 0) << "no proposal at the ball (" << b.centre_px.transpose()
                                           << "), r=" << b.radius_px << describe(f.proposals);
  EXPECT_LE(f.balls.size(), 1u);
}

// The last five: the ball beside and at the image's lower border and lower-left corner (its
// centre outside the image), where the expected radius is 66 px or more (before every window got
// an evaluation, the one at the corner had no proposal). Not covered: at (0.26, -0.24), the
// lower-right corner, the proposal lands 26 px from the drawn centre, just outside the match rule.
INSTANTIATE_TEST_SUITE_P(BottomCamera, CloseBallAt,
                         ::testing::Values(CloseBall{40, 0.30, 0.0}, CloseBall{40, 0.25, 0.08},
                                           CloseBall{40, 0.40, 0.0}, CloseBall{55, 0.30, 0.0},
                                           CloseBall{55, 0.35, 0.1}, CloseBall{55, 0.45, 0.0},
                                           CloseBall{65, 0.25, 0.0}, CloseBall{40, 0.33, 0.22},
                                           CloseBall{55, 0.30, -0.2}, CloseBall{40, 0.45, -0.3},
                                           CloseBall{55, 0.20, 0.15}, CloseBall{40, 0.25, 0.0},
                                           CloseBall{40, 0.28, 0.2}, CloseBall{40, 0.25, 0.25},
                                           CloseBall{40, 0.24, 0.12}));

// A ball lying on a line straight ahead, a crossing line behind it: the line lights the ball's
// surround, so the print's edges (the texture term) must carry it.
TEST(BallDetection, LineThroughTheBall) {
  const CameraModel cam = test::testCamera(22);
  test::SyntheticScene scene = carpetOnly(4);
  scene.segments.push_back({{0.5, 0.0}, {4.0, 0.0}});   // a line along x ...
  scene.segments.push_back({{1.6, -2.0}, {1.6, 2.0}});  // ... and one crossing it
  GrayImage image = test::renderScene(cam, scene);
  const test::DrawnBall b = test::drawBall(image, cam, {1.3, 0.0});
  const Found f = runPipeline(image, cam);
  EXPECT_GE(matchIndex(f.proposals, b), 0) << b.centre_px.transpose() << " r=" << b.radius_px << describe(f.proposals);
  EXPECT_TRUE(detected(f.balls, b));
  EXPECT_LE(f.balls.size(), 1u);
}

TEST(BallDetection, NextToAFoot) {
  const CameraModel cam = test::testCamera(22);
  GrayImage image = test::renderScene(cam, carpetOnly(5));
  test::drawFoot(image, cam, {1.2, 0.05});
  const test::DrawnBall b = test::drawBall(image, cam, {1.1, -0.12});
  const Found f = runPipeline(image, cam);
  EXPECT_GE(matchIndex(f.proposals, b), 0);
  EXPECT_TRUE(detected(f.balls, b));
}

TEST(BallDetection, NothingOnBlankCarpet) {
  const CameraModel cam = test::testCamera(22);
  for (std::uint64_t seed : {6u, 7u}) {
    const GrayImage image = test::renderScene(cam, carpetOnly(seed));
    const Found f = runPipeline(image, cam);
    EXPECT_TRUE(f.balls.empty()) << f.balls[0].centre_px.transpose() << describe(f.proposals);
  }
}

TEST(BallDetection, NothingOnALoneLineCrossing) {
  const CameraModel cam = test::testCamera(22);
  test::SyntheticScene scene = carpetOnly(8);
  scene.segments.push_back({{0.5, 0.0}, {4.0, 0.0}});
  scene.segments.push_back({{1.4, -2.0}, {1.4, 2.0}});
  const GrayImage image = test::renderScene(cam, scene);
  const Found f = runPipeline(image, cam);
  EXPECT_FALSE(f.proposals.empty());  // the crossing is high contrast: the cascade must reject it
  EXPECT_TRUE(f.balls.empty());
}

// A ball whose black patches the light lifts to the carpet's gray (as in the real dark-hall NAO
// frame) is a bright blob with nothing darker inside: the field lines alone take it for a penalty
// mark; once the ball is detected the pipeline drops that mark.
TEST(BallDetection, ABallWithGrayPatchesIsNoPenaltyMark) {
  const CameraModel cam = test::testCamera(22);
  const test::SyntheticScene scene = carpetOnly(4);
  static const Pipeline pipeline(PipelineConfig::loadDefault());
  PipelineConfig keep_config = PipelineConfig::loadDefault();
  keep_config.field_lines.penalty_mark_ball_radii = 0;
  const Pipeline keep(keep_config);
  for (const double d : {1.1, 1.3}) {
    GrayImage image = test::renderScene(cam, scene);
    const test::DrawnBall b = test::drawBall(image, cam, {d, 0.1}, 130, scene.carpet);
    const auto on_ball = [&](const std::vector<CircleMarkPercept>& marks) {
      return std::count_if(marks.begin(), marks.end(), [&](const CircleMarkPercept& m) {
        return (m.centre_px - b.centre_px).norm() < b.radius_px;
      });
    };
    const FieldLineResult lines =
        FieldLineDetector().run(image.view(), cam, IgnoreMask::all(640, 480));
    ASSERT_EQ(on_ball(lines.features.penalty_marks), 1)
        << d << ": the field lines alone find no mark on the ball";
    Frame frame(image.view(), cam);
    pipeline.process(frame);
    ASSERT_TRUE(detected(*frame.ball_percepts, b)) << d << describe(*frame.ball_proposals);
    EXPECT_EQ(on_ball(frame.field_lines->features.penalty_marks), 0) << d;
    Frame kept(image.view(), cam);
    keep.process(kept);
    EXPECT_EQ(on_ball(kept.field_lines->features.penalty_marks), 1) << d;
  }
}

// Less than about half a ball in view: a proposal centred outside the image by more than
// max_centre_outside_radii is not passed on to BallNet, whatever BoostBallNet says of it.
TEST(BallDetector, ProposalsCentredOutsideTheImageAreNotPassedOn) {
  EXPECT_DOUBLE_EQ(centreOutsideRadii({100, 100}, 10, 320, 240), 0);
  EXPECT_DOUBLE_EQ(centreOutsideRadii({150, -2}, 10, 320, 240), 0.2);
  EXPECT_DOUBLE_EQ(centreOutsideRadii({326, 100}, 10, 320, 240), 0.6);
  EXPECT_DOUBLE_EQ(centreOutsideRadii({-3, 244}, 10, 320, 240), 0.5);
  const CameraModel cam = test::testCamera(22);
  const GrayImage image = test::renderScene(cam, carpetOnly(9));
  ASSERT_EQ(image.width(), 640);
  ASSERT_EQ(image.height(), 480);
  const std::vector<BallProposal> props = {
      {{100, 100}, 10, 1}, {{150, -2}, 10, 1}, {{646, 100}, 10, 1}, {{-3, 484}, 10, 1}};
  BallDetectorParams p;
  p.boost_min_confidence = 0;  // every proposal BoostBallNet ranks may pass: only the image rule decides
  p.boost_keep_count = 10;
  std::vector<BallDecision> d;
  BallDetector::load(p).run(image.view(), cam, props, &d);
  ASSERT_EQ(d.size(), props.size());
  EXPECT_TRUE(d[0].passed_boost);
  EXPECT_TRUE(d[1].passed_boost);  // 0.2 radii out: within the 0.25 allowed
  EXPECT_FALSE(d[2].passed_boost);
  EXPECT_FALSE(d[2].detected);
  EXPECT_EQ(d[2].ball_confidence, -1);
  EXPECT_FALSE(d[3].passed_boost);
  p.max_centre_outside_radii = 1;
  BallDetector::load(p).run(image.view(), cam, props, &d);
  for (const BallDecision& x : d) EXPECT_TRUE(x.passed_boost) << x.proposal;
}

TEST(BallProposer, WorksWithoutAndWithRobotsAndIsCapped) {
  const CameraModel cam = test::testCamera(22);
  test::SyntheticScene scene = carpetOnly(9);
  for (int i = 0; i < 12; ++i) scene.segments.push_back({{0.6 + 0.3 * i, -2.0}, {0.6 + 0.3 * i, 2.0}});
  GrayImage image = test::renderScene(cam, scene);
  test::drawFoot(image, cam, {1.5, 0.3});
  const test::DrawnBall b = test::drawBall(image, cam, {1.45, 0.14});
  const PipelineConfig config = PipelineConfig::loadDefault();
  const HighContrastDetector hc(config.high_contrast);
  const IgnoreMask ignore = IgnoreMask::all(image.width(), image.height());
  const ContrastRegions regions = hc.run(image.view(), ignore);
  const BallProposer proposer(config.ball_proposer);
  const auto without = proposer.run(image.view(), cam, ignore, regions, nullptr);
  EXPECT_LE(static_cast<int>(without.size()), config.ball_proposer.max_count);
  RobotPercept robot;
  robot.feet_px = *cam.robotToPixel({1.5, 0.3, 0});
  const std::vector<RobotPercept> robots{robot};
  const auto with = proposer.run(image.view(), cam, ignore, regions, &robots);
  EXPECT_LE(static_cast<int>(with.size()), config.ball_proposer.max_count);
  EXPECT_GE(matchIndex(with, b), 0);
  for (std::size_t i = 1; i < with.size(); ++i) EXPECT_GE(with[i - 1].response, with[i].response);
  // Same input, same output.
  const auto again = proposer.run(image.view(), cam, ignore, regions, &robots);
  ASSERT_EQ(again.size(), with.size());
  for (std::size_t i = 0; i < with.size(); ++i) EXPECT_EQ(again[i].centre_px, with[i].centre_px);
  // A mask of another size is an error.
  EXPECT_THROW(proposer.run(image.view(), cam, IgnoreMask::all(320, 240), regions, nullptr), Error);
}

// A detected robot's body damps the responses above its feet region (its white parts), but only
// the middle of its box across (robot_body_width_fraction): a ball behind the robot seen beside
// its body, in the box's margin, keeps its full response. Two balls 3 m away, a robot's box
// (feet 1.2 m away) around both: the one at the box's middle counts robot_body_factor of its
// response, the one near the box's edge all of it.
TEST(BallProposer, ARobotsBodyDampsOnlyTheMiddleOfItsBox) {
  const CameraModel cam = test::testCamera(22);
  GrayImage image = test::renderScene(cam, carpetOnly(31));
  const test::DrawnBall middle = test::drawBall(image, cam, {3.0, 0.0});
  const test::DrawnBall beside = test::drawBall(image, cam, {3.0, -0.35});
  const BallProposerParams p = BallProposerParams::loadDefault();
  ASSERT_GT(p.robot_body_factor, 0);
  ASSERT_LT(p.robot_body_factor, 1);
  ASSERT_LT(p.robot_body_width_fraction, 1);
  // The box: centred on the middle ball, its right edge just beyond the other ball, so that the
  // other lies in the box's margin (outside the middle fraction, inside the box).
  RobotPercept robot;
  robot.feet_px = *cam.robotToPixel({1.2, 0.0, 0});
  const double half = (beside.centre_px.x() - middle.centre_px.x()) / 0.95;
  robot.box = {middle.centre_px.x() - half, middle.centre_px.y() - 200,
               middle.centre_px.x() + half, robot.feet_px.y() + 10};
  ASSERT_GT(std::abs(beside.centre_px.x() - middle.centre_px.x()), p.robot_body_width_fraction * half);
  // Both balls lie above the feet region (feet_region_diameters ball radii above the feet point).
  const double feet_radius = *cam.ballRadiusPx(robot.feet_px, p.ball_radius_m);
  ASSERT_LT(std::max(middle.centre_px.y(), beside.centre_px.y()),
            robot.feet_px.y() - p.feet_region_diameters * feet_radius * 1.5);
  PipelineConfig config = PipelineConfig::loadDefault();
  const IgnoreMask ignore = IgnoreMask::all(image.width(), image.height());
  const ContrastRegions regions = HighContrastDetector(config.high_contrast).run(image.view(), ignore);
  const BallProposer proposer(p);
  const std::vector<RobotPercept> robots{robot};
  const auto without = proposer.run(image.view(), cam, ignore, regions, nullptr);
  const auto with = proposer.run(image.view(), cam, ignore, regions, &robots);
  const int mid0 = matchIndex(without, middle), mid1 = matchIndex(with, middle);
  const int side0 = matchIndex(without, beside), side1 = matchIndex(with, beside);
  ASSERT_GE(mid0, 0) << describe(without);
  ASSERT_GE(side0, 0) << describe(without);
  ASSERT_GE(mid1, 0) << describe(with);
  ASSERT_GE(side1, 0) << describe(with);
  EXPECT_FLOAT_EQ(with[mid1].response, static_cast<float>(p.robot_body_factor) * without[mid0].response);
  EXPECT_FLOAT_EQ(with[side1].response, without[side0].response);
  // The whole box as the body (the rule before): the ball beside the body is damped too.
  BallProposerParams whole = p;
  whole.robot_body_width_fraction = 1.0;
  const auto damped = BallProposer(whole).run(image.view(), cam, ignore, regions, &robots);
  const int side2 = matchIndex(damped, beside);
  ASSERT_GE(side2, 0) << describe(damped);
  EXPECT_FLOAT_EQ(damped[side2].response, static_cast<float>(p.robot_body_factor) * without[side0].response);
}

// A dark hall seen through a soft lens: carpet at 30 grey levels, the ball's white at 72, the
// frame blurred (two 3×3 box passes). The high-contrast stage's absolute threshold (22 grey levels)
// leaves the ball's windows unmarked; the proposer's threshold that follows the frame's light scans
// them, and so does the high-contrast stage's own (its light_contrast_fraction). With both off the
// ball is not proposed; blank dark carpet gives no proposal either way.
GrayImage softened(const GrayImage& in) {
  GrayImage a = in, b = in;
  for (int pass = 0; pass < 2; ++pass) {
    const GrayImage& src = pass == 0 ? in : a;
    GrayImage& dst = pass == 0 ? b : a;
    GrayImage tmp = src;
    for (int y = 0; y < src.height(); ++y) {
      for (int x = 0; x < src.width(); ++x) {
        int sum = 0, n = 0;
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            if (!src.view().contains(x + dx, y + dy)) continue;
            sum += src.view().at(x + dx, y + dy);
            ++n;
          }
        }
        tmp.at(x, y) = static_cast<std::uint8_t>((sum + n / 2) / n);
      }
    }
    dst = tmp;
    if (pass == 0) a = b;
  }
  return a;
}

test::SyntheticScene darkCarpet(std::uint64_t seed) {
  test::SyntheticScene s;
  s.carpet = 30;
  s.background = 45;
  s.texture = 3;
  s.pixel_noise = 2;
  s.seed = seed;
  return s;
}

// `noise`: the frame's pixel noise as a caller (the pipeline) hands it over; absent: the proposer's
// own estimate. `light_contrast`: the high-contrast stage's light-relative threshold on (shipped)
// or off.
std::vector<BallProposal> proposeOnly(const GrayImage& image, const CameraModel& cam,
                                      const BallProposerParams& p,
                                      std::optional<double> noise = std::nullopt,
                                      bool light_contrast = true) {
  PipelineConfig config = PipelineConfig::loadDefault();
  if (!light_contrast) {
    // (The absolute threshold alone: no light-relative bar, nor the sparse frame's lower one.)
    config.high_contrast.light_contrast_fraction = 0;
    config.high_contrast.sparse_max_seed_fraction = 0;
  }
  const IgnoreMask ignore = IgnoreMask::all(image.width(), image.height());
  const ContrastRegions regions = HighContrastDetector(config.high_contrast).run(image.view(), ignore);
  return BallProposer(p).run(image.view(), cam, ignore, regions, nullptr, noise);
}

TEST(BallProposer, LowContrastSoftBallInADarkHall) {
  const CameraModel cam = test::testCamera(22);
  for (const double d : {1.2, 1.8}) {
    GrayImage image = test::renderScene(cam, darkCarpet(4));
    const test::DrawnBall b = test::drawBall(image, cam, {d, 0.1}, 72, 14);
    image = softened(image);
    const BallProposerParams shipped = BallProposerParams::loadDefault();
    const auto props = proposeOnly(image, cam, shipped);
    EXPECT_GE(matchIndex(props, b), 0) << "ball at " << d << " m (" << b.centre_px.transpose()
                                       << "), r=" << b.radius_px << describe(props);
    BallProposerParams absolute = shipped;
    absolute.light_contrast_fraction = 0;
    EXPECT_LT(matchIndex(proposeOnly(image, cam, absolute, std::nullopt, false), b), 0)
        << "the absolute thresholds find it too at " << d << " m";
    // The high-contrast stage's own light-relative threshold marks its windows too.
    EXPECT_GE(matchIndex(proposeOnly(image, cam, absolute), b), 0) << d << " m";
  }
}

TEST(BallProposer, NothingOnBlankDarkCarpet) {
  const CameraModel cam = test::testCamera(22);
  for (std::uint64_t seed : {6u, 7u}) {
    const GrayImage image = softened(test::renderScene(cam, darkCarpet(seed)));
    const auto props = proposeOnly(image, cam, BallProposerParams::loadDefault());
    EXPECT_TRUE(props.empty()) << "seed " << seed << describe(props);
  }
}

BallProposerParams withoutNoiseTerms(BallProposerParams p) {
  p.texture_noise_factor = 0;
  p.response_noise_factor = 0;
  return p;
}

// A dark hall's high gain (noise sigma 25 gray levels, as the camera-noise sweep's): every pixel's
// edges are some 56 gray levels strong, so without the noise terms the texture term makes the
// largest, nearest boxes of noisy carpet the strongest responses and the ball gets no proposal;
// with them it is proposed where it is, and the detector finds it.
TEST(BallProposer, BallInHeavySensorNoise) {
  const CameraModel cam = test::testCamera(22);
  for (const double d : {1.0, 2.0}) {
    test::SyntheticScene scene = carpetOnly(8);
    scene.pixel_noise = 0;
    scene.segments.push_back({{0.5, -0.6}, {4.0, -0.6}});
    GrayImage image = test::renderScene(cam, scene);
    const test::DrawnBall b = test::drawBall(image, cam, {d, 0.1});
    test::addNoise(image, 25, 12);
    const BallProposerParams shipped = BallProposerParams::loadDefault();
    const auto props = proposeOnly(image, cam, shipped);
    EXPECT_GE(matchIndex(props, b), 0) << "ball at " << d << " m (" << b.centre_px.transpose()
                                       << "), r=" << b.radius_px << describe(props);
    EXPECT_LT(matchIndex(proposeOnly(image, cam, withoutNoiseTerms(shipped)), b), 0)
        << "found without the noise terms too at " << d << " m";
    // The noise handed over is the one used: the frame's own estimate proposes the same, a
    // noise-free claim fails as the terms switched off do.
    const double sigma = pixelNoiseGray(image.view(), IgnoreMask::all(image.width(), image.height()));
    EXPECT_EQ(describe(proposeOnly(image, cam, shipped, sigma)), describe(props));
    EXPECT_LT(matchIndex(proposeOnly(image, cam, shipped, 0.0), b), 0) << "found with a noise of 0 at " << d << " m";
    const Found f = runPipeline(image, cam);
    EXPECT_TRUE(detected(f.balls, b)) << "ball at " << d << " m" << describe(f.proposals);
    EXPECT_LE(f.balls.size(), 1u);
  }
}

// A camera pose that is off: the ball drawn with the camera pitched 22° down, detected with one the
// robot believes pitched 16° or 17° (the expected radius some 0.6 times the ball's) or 28° (some 1.4
// times). BallNet rejects the ball framed that tightly or loosely; the look at rescale_up /
// rescale_down times the radius finds it, with about its radius. (These drawn balls are the ones
// of 1.0 to 3.0 m the shipped detector misses without that look; it finds every one it found
// without it.)
TEST(BallDetection, CameraPitchOffByFiveDegreesStillFindsTheBall) {
  const CameraModel drawn_with = test::testCamera(22);
  PipelineConfig off = PipelineConfig::loadDefault();
  off.ball_detector.rescale_up = 0;
  off.ball_detector.rescale_down = 0;
  const Pipeline without(off);
  const std::pair<double, double> cases[] = {{16, 1.2}, {17, 2.5}, {28, 2.5}};  // believed pitch, distance
  for (const auto& [believed_deg, d] : cases) {
    const CameraModel believed = test::testCamera(believed_deg);
    GrayImage image = test::renderScene(drawn_with, carpetOnly(8));
    const test::DrawnBall b = test::drawBall(image, drawn_with, {d, 0.1});
    const Found f = runPipeline(image, believed);
    ASSERT_TRUE(detected(f.balls, b)) << "ball at " << d << " m, believed pitch " << believed_deg << describe(f.proposals);
    EXPECT_NEAR(f.balls[0].radius_px / b.radius_px, 1.0, 0.3) << "ball at " << d << " m, believed pitch " << believed_deg;
    Frame frame(image.view(), believed);
    without.process(frame);
    EXPECT_FALSE(detected(*frame.ball_percepts, b)) << "found without the rescaled look too: ball at " << d
                                                    << " m, believed pitch " << believed_deg;
  }
}

// The rescaled look is gated by the proposal's radius: the ball 2.5 m away that the camera's
// believed pitch (28° where it is 22°) frames too small is found through it from a bar under the
// proposal's radius, not from one above it.
TEST(BallDetector, NoRescaledLookUnderItsMinimumRadius) {
  const CameraModel drawn_with = test::testCamera(22), believed = test::testCamera(28);
  GrayImage image = test::renderScene(drawn_with, carpetOnly(8));
  const test::DrawnBall b = test::drawBall(image, drawn_with, {2.5, 0.1});
  const Found f = runPipeline(image, believed);
  const int i = matchIndex(f.proposals, b);
  ASSERT_GE(i, 0) << describe(f.proposals);
  const double r = f.proposals[static_cast<std::size_t>(i)].radius_px;
  ASSERT_GE(r, BallDetectorParams::loadDefault().rescale_min_radius_px);
  for (const double bar : {r - 0.5, r + 0.5}) {
    BallDetectorParams p = BallDetectorParams::loadDefault();
    p.rescale_min_radius_px = bar;
    const auto balls = BallDetector::load(p).run(image.view(), believed, f.proposals);
    EXPECT_EQ(detected(balls, b), bar < r) << "bar " << bar << ", proposal radius " << r;
  }
}

// The same noise on blank carpet: no ball.
TEST(BallDetection, NothingOnNoisyBlankCarpet) {
  const CameraModel cam = test::testCamera(22);
  for (std::uint64_t seed : {13u, 14u}) {
    test::SyntheticScene scene = carpetOnly(seed);
    scene.pixel_noise = 0;
    GrayImage image = test::renderScene(cam, scene);
    test::addNoise(image, 25, seed);
    const Found f = runPipeline(image, cam);
    EXPECT_TRUE(f.balls.empty()) << "seed " << seed << describe(f.proposals);
  }
}

// The frame smeared sideways by a head turn during the exposure: every pixel the mean of the
// pixels up to length_px / 2 left and right of it (clamped at the border).
GrayImage smearedSideways(const GrayImage& in, int length_px) {
  GrayImage out = in;
  const int h = length_px / 2;
  for (int y = 0; y < in.height(); ++y) {
    for (int x = 0; x < in.width(); ++x) {
      int sum = 0;
      for (int d = -h; d <= h; ++d) sum += in.view().at(std::clamp(x + d, 0, in.width() - 1), y);
      out.at(x, y) = static_cast<std::uint8_t>((sum + h) / (2 * h + 1));
    }
  }
  return out;
}

// The nearest proposal's distance to the drawn ball's centre (infinity without proposals).
double nearestDistance(const std::vector<BallProposal>& props, const test::DrawnBall& b) {
  double best = std::numeric_limits<double>::infinity();
  for (const auto& p : props) best = std::min(best, (p.centre_px - b.centre_px).norm());
  return best;
}

// A ball smeared sideways by one and by one and a half radii (a 20 ms exposure while the head
// turns at some 100 deg/s smears a ball 1.5-2 m away by 20-25 px): its gradients vote for centres
// along a ridge as long as the smear; the proposal must sit at the ridge's middle, within a quarter
// of the radius of the ball's centre. The best cell alone (centre_ridge_fraction 0) lands 6.8-7.6 px
// off at 1.5 radii, outside that (2026-12-02). Not covered: smeared by 2 radii at 1.5 m, the
// high-contrast stage marks no window near the drawn ball, so nothing is proposed at all.
TEST(BallProposer, SmearedBallProposedAtItsCentre) {
  const CameraModel cam = test::testCamera(22);
  const BallProposerParams shipped = BallProposerParams::loadDefault();
  for (const double d : {1.0, 1.5, 2.2}) {
    for (const double smear_radii : {1.0, 1.5}) {
      GrayImage image = test::renderScene(cam, carpetOnly(5));
      const test::DrawnBall b = test::drawBall(image, cam, {d, -0.1});
      image = smearedSideways(image, static_cast<int>(std::lround(smear_radii * b.radius_px)));
      if (std::getenv("BALL_TEST_DUMP")) writeGrayPng(std::string(std::getenv("BALL_TEST_DUMP")) + ".png", image.view());
      const auto props = proposeOnly(image, cam, shipped);
      BallProposerParams best_cell = shipped;
      best_cell.centre_ridge_fraction = 0;
      EXPECT_LE(nearestDistance(props, b), 0.25 * b.radius_px)
          << "ball at " << d << " m (" << b.centre_px.transpose() << "), r=" << b.radius_px << ", smeared by "
          << smear_radii << " radii; the best cell alone: "
          << nearestDistance(proposeOnly(image, cam, best_cell), b) << " px off" << describe(props);
    }
  }
}

// The smear lights the square surround's left and right cells: with the camera's smear known, the
// surround widens along it and the ball smeared by 1.5 radii responds more strongly than in a
// square surround (71.0 against 65.7 at 1 m, 64.5 against 60.6 at 1.5 m) or in one widened across
// the smear (66.1, 62.1: x and y swapped); without a smear in the camera model nothing changes.
TEST(BallProposer, SurroundWidensAlongTheCamerasSmear) {
  const BallProposerParams shipped = BallProposerParams::loadDefault();
  ASSERT_GT(shipped.smear_surround_fraction, 0);
  BallProposerParams square = shipped;
  square.smear_surround_fraction = 0;
  for (const double d : {1.0, 1.5}) {
    const CameraModel sharp_cam = test::testCamera(22);
    GrayImage image = test::renderScene(sharp_cam, carpetOnly(5));
    const test::DrawnBall b = test::drawBall(image, sharp_cam, {d, -0.1});
    const double smear_px = std::round(1.5 * b.radius_px);
    image = smearedSideways(image, static_cast<int>(smear_px));
    const auto responseAtBall = [&](const CameraModel& cam, const BallProposerParams& p) {
      const auto props = proposeOnly(image, cam, p);
      const int i = matchIndex(props, b);
      return i < 0 ? -1.0 : props[i].response;
    };
    CameraModel along = sharp_cam, across = sharp_cam;
    along.setExposureSmearPx({smear_px, 0});
    across.setExposureSmearPx({0, smear_px});
    const double widened = responseAtBall(along, shipped);
    SCOPED_TRACE("ball at " + std::to_string(d) + " m, r " + std::to_string(b.radius_px) + " px");
    EXPECT_GT(widened, 1.05 * responseAtBall(along, square));
    EXPECT_GT(widened, responseAtBall(across, shipped));
    EXPECT_EQ(responseAtBall(sharp_cam, shipped), responseAtBall(sharp_cam, square));
  }
}

TEST(BallProposer, NothingOnBlankSmearedCarpet) {
  const CameraModel cam = test::testCamera(22);
  for (std::uint64_t seed : {6u, 7u}) {
    const GrayImage image = smearedSideways(test::renderScene(cam, carpetOnly(seed)), 20);
    const auto props = proposeOnly(image, cam, BallProposerParams::loadDefault());
    EXPECT_TRUE(props.empty()) << "seed " << seed << describe(props);
  }
}

// patchSmear on the patch the nets see: a drawn ball, sharp, is round (its outline and patches
// turn every way); smeared sideways by 1.5 radii (a head turn during a long exposure) it is
// elongated past the routing bound measured with (0.5, README ball12); a patch reaching beyond the
// image is not measured.
constexpr double kSmearedMinCoherence = 0.5;

TEST(BallDetector, PatchSmearTellsASmearedBallFromASharpOne) {
  const CameraModel cam = test::testCamera(22);
  const double bound = kSmearedMinCoherence;
  for (const double d : {1.0, 1.5, 2.2}) {
    GrayImage image = test::renderScene(cam, carpetOnly(5));
    const test::DrawnBall b = test::drawBall(image, cam, {d, -0.1});
    const cnn::PatchBox box = ballPatchBox(b.centre_px, b.radius_px, 1.25);
    const double sharp = patchSmear(image.view(), box);
    const double smeared =
        patchSmear(smearedSideways(image, static_cast<int>(std::lround(1.5 * b.radius_px))).view(), box);
    EXPECT_GE(sharp, 0) << d;
    EXPECT_LT(sharp, 0.3) << d;
    EXPECT_GT(smeared, bound) << d;
  }
  const GrayImage image = test::renderScene(cam, carpetOnly(5));
  EXPECT_EQ(patchSmear(image.view(), {-1, 100, 40, 40}), -1);
  EXPECT_EQ(patchSmear(image.view(), {620, 100, 40, 40}), -1);
  EXPECT_GE(patchSmear(image.view(), {600, 440, 40, 40}), 0);
  GrayImage edge(640, 480);
  for (int y = 0; y < 480; ++y) {
    for (int x = 0; x < 640; ++x) edge.at(x, y) = x < 320 ? 60 : 200;
  }
  EXPECT_GT(patchSmear(edge.view(), {300, 200, 40, 40}), 0.99);
}

// A ball smeared sideways by 2 radii, proposed 0.6 radii off its centre along the smear: the middle
// of its smear is the ball's centre, within a quarter radius; patchSmear's direction is the
// smear's. A line running through the whole profile, and bare carpet, give none.
TEST(BallDetector, SmearedBallCentreIsTheMiddleOfTheSmear) {
  const CameraModel cam = test::testCamera(22);
  const BallDetectorParams p = BallDetectorParams::loadDefault();
  for (const double d : {1.0, 1.5}) {
    GrayImage image = test::renderScene(cam, carpetOnly(5));
    const test::DrawnBall b = test::drawBall(image, cam, {d, -0.1});
    image = smearedSideways(image, static_cast<int>(std::lround(2 * b.radius_px)));
    Eigen::Vector2d along;
    patchSmear(image.view(), ballPatchBox(b.centre_px, b.radius_px, 1.25), &along);
    EXPECT_GT(std::abs(along.x()), 0.95) << d;
    for (const double off : {-0.6, 0.6}) {
      const Eigen::Vector2d proposed = b.centre_px + Eigen::Vector2d(off * b.radius_px, 0);
      const auto c = smearedBallCentre(image.view(), proposed, b.radius_px, along, p.smeared_centre_reach_radii,
                                       p.smeared_centre_min_contrast_gray);
      ASSERT_TRUE(c.has_value()) << d << " " << off;
      EXPECT_LT((*c - b.centre_px).norm(), 0.25 * b.radius_px)
          << d << " " << off << ": " << c->transpose() << " vs " << b.centre_px.transpose();
    }
  }
  GrayImage line = test::renderScene(cam, carpetOnly(5));
  for (int y = 200; y < 212; ++y) {
    for (int x = 0; x < line.width(); ++x) line.at(x, y) = 220;
  }
  EXPECT_FALSE(smearedBallCentre(line.view(), {320, 206}, 15, {1, 0}, 3, 8).has_value());
  const GrayImage carpet = test::renderScene(cam, carpetOnly(5));
  EXPECT_FALSE(smearedBallCentre(carpet.view(), {320, 206}, 15, {1, 0}, 3, 8).has_value());
}

// Kept patches BallNet rejects that are at least smeared_min_coherence elongated go to
// SmearedBallNet; the sharp ball's patch does not, nor one BallNet accepts. Without the bound
// nothing is measured, and a bound without the net is refused.
TEST(BallDetector, SmearedPatchesGoToSmearedBallNet) {
  CameraModel cam = test::testCamera(22);
  GrayImage image = test::renderScene(cam, carpetOnly(5));
  const test::DrawnBall b = test::drawBall(image, cam, {1.5, -0.1});
  const GrayImage smeared = smearedSideways(image, static_cast<int>(std::lround(1.5 * b.radius_px)));
  cam.setExposureSmearPx({1.5 * b.radius_px, 0});  // the camera turned sideways by that much
  const std::vector<BallProposal> props = {{b.centre_px, b.radius_px, 1}};
  BallDetectorParams p = BallDetectorParams::loadDefault();
  p.smeared_min_coherence = kSmearedMinCoherence;  // the bound the routing was measured with
  p.boost_min_confidence = 0;  // BoostBallNet's view of the drawn ball is not what is tested here
  p.ball_min_confidence = 1.1;  // BallNet rejects everything, so every patch is measured
  p.sharpen_sigma_radii = 0;    // no sharpened look, nor a deblurred one: only SmearedBallNet may
  p.deblur_iterations = 0;      // take a rejected patch
  std::vector<BallDecision> d;
  const BallDetector detector = BallDetector::load(p);
  detector.run(image.view(), cam, props, &d);
  ASSERT_EQ(d.size(), 1u);
  EXPECT_GE(d[0].smear, 0);
  EXPECT_LT(d[0].smear, p.smeared_min_coherence);
  EXPECT_GE(d[0].ball_confidence, 0);
  EXPECT_EQ(d[0].smeared_confidence, -1);
  detector.run(smeared.view(), cam, props, &d);
  EXPECT_GE(d[0].smear, p.smeared_min_coherence);
  EXPECT_GE(d[0].ball_confidence, 0);
  EXPECT_GE(d[0].smeared_confidence, 0);
  EXPECT_FALSE(d[0].detected && d[0].smeared_confidence < p.smeared_ball_min_confidence);
  p.smeared_min_coherence = 2;
  BallDetector::load(p).run(smeared.view(), cam, props, &d);
  EXPECT_EQ(d[0].smear, -1);
  EXPECT_EQ(d[0].smeared_confidence, -1);
  EXPECT_FALSE(d[0].detected);
  p.smeared_min_coherence = kSmearedMinCoherence;
  p.ball_min_confidence = 0;  // BallNet accepts: no second look
  BallDetector::load(p).run(smeared.view(), cam, props, &d);
  EXPECT_EQ(d[0].smear, -1);
  EXPECT_EQ(d[0].smeared_confidence, -1);
  EXPECT_TRUE(d[0].detected);
  const std::string dir = cnn::defaultModelDir();
  const auto net = [&](const std::string& stem) {
    return cnn::Classifier::load(dir + "/" + stem + ".cfg", dir + "/" + stem + ".weights");
  };
  p.smeared_min_coherence = 0.5;
  EXPECT_THROW(BallDetector(p, net("boost_ball_net"), net("ball_net")), Error);
  EXPECT_NO_THROW(BallDetector(p, net("boost_ball_net"), net("ball_net"), net("smeared_ball_net")));
}

// With the camera's own smear required (smeared_min_camera_smear_radii), a smeared patch goes to
// SmearedBallNet only when the camera file says the camera turned that far during the exposure,
// along the patch's smear (smeared_max_direction_deg): a still camera, a smear too short and one
// across the patch's all keep it from the net.
TEST(BallDetector, SmearedBallNetOnlyWhereTheCameraTurnedAlongTheSmear) {
  CameraModel cam = test::testCamera(22);
  GrayImage image = test::renderScene(cam, carpetOnly(5));
  const test::DrawnBall b = test::drawBall(image, cam, {1.5, -0.1});
  const double r = b.radius_px;
  const GrayImage smeared = smearedSideways(image, static_cast<int>(std::lround(1.5 * r)));
  const std::vector<BallProposal> props = {{b.centre_px, r, 1}};
  BallDetectorParams p = BallDetectorParams::loadDefault();
  p.smeared_min_coherence = kSmearedMinCoherence;
  p.smeared_min_camera_smear_radii = 0.5;
  p.smeared_max_direction_deg = 20;
  p.boost_min_confidence = 0;
  p.ball_min_confidence = 1.1;  // BallNet rejects everything, so every patch is measured
  p.sharpen_sigma_radii = 0;
  const BallDetector detector = BallDetector::load(p);
  std::vector<BallDecision> d;
  const auto routed = [&](const Eigen::Vector2d& camera_smear_px) {
    cam.setExposureSmearPx(camera_smear_px);
    detector.run(smeared.view(), cam, props, &d);
    return d.at(0).smeared_confidence >= 0;
  };
  EXPECT_FALSE(routed({0, 0}));              // a still camera
  EXPECT_FALSE(routed({0.4 * r, 0}));        // turned less than half a radius
  EXPECT_TRUE(routed({1.5 * r, 0}));         // along the smear (sideways)
  EXPECT_TRUE(routed({-1.5 * r, 0.3 * r}));  // either way, 11 degrees off
  EXPECT_FALSE(routed({0, 1.5 * r}));        // across it
  EXPECT_FALSE(routed({1.5 * r, 0.7 * r}));  // 25 degrees off
  p.smeared_max_direction_deg = 90;          // any direction
  cam.setExposureSmearPx({0, 1.5 * r});
  BallDetector::load(p).run(smeared.view(), cam, props, &d);
  EXPECT_GE(d.at(0).smeared_confidence, 0);
  EXPECT_THROW(cam.setExposureSmearPx({std::nan(""), 0}), Error);
}

// A rolling shutter read the ball's row before or after the frame's time while the camera turned:
// the percept is put where the ball was at the frame's time (CameraModel::atFrameTime), its ground
// position from there; without a shift it stays where the image shows it.
TEST(BallDetector, BallIsPlacedAtTheFramesTimeUnderARollingShutter) {
  CameraModel cam = test::testCamera(22);
  GrayImage image = test::renderScene(cam, carpetOnly(5));
  const test::DrawnBall b = test::drawBall(image, cam, {1.5, -0.1});
  const std::vector<BallProposal> props = {{b.centre_px, b.radius_px, 1}};
  const BallDetector detector = BallDetector::load(BallDetectorParams::loadDefault());
  const std::vector<BallPercept> still = detector.run(image.view(), cam, props);
  ASSERT_EQ(still.size(), 1u);
  EXPECT_EQ(still[0].centre_px, b.centre_px);
  cam.setRollingShutterShiftPx({24, -6});
  const std::vector<BallPercept> shifted = detector.run(image.view(), cam, props);
  ASSERT_EQ(shifted.size(), 1u);
  const double share = b.centre_px.y() / cam.height() - 0.5;
  ASSERT_GT(std::abs(share), 0.05);  // the drawn ball's row is not the middle one
  EXPECT_TRUE(shifted[0].centre_px.isApprox(b.centre_px - share * Eigen::Vector2d(24, -6), 1e-9));
  ASSERT_TRUE(shifted[0].position_in_robot.has_value());
  EXPECT_TRUE(
      shifted[0].position_in_robot->isApprox(*cam.pixelToGround(shifted[0].centre_px, 0.05), 1e-9));
  EXPECT_GT((*shifted[0].position_in_robot - *still[0].position_in_robot).norm(), 0.005);
}

// A soft lens: the frame blurred by a Gaussian of `sigma` pixels (the border repeated).
GrayImage defocused(const GrayImage& in, double sigma) {
  const int reach = static_cast<int>(std::ceil(3 * sigma));
  std::vector<double> k(2 * reach + 1);
  double total = 0;
  for (int i = -reach; i <= reach; ++i) {
    total += k[i + reach] = std::exp(-0.5 * i * i / (sigma * sigma));
  }
  const int w = in.width(), h = in.height();
  std::vector<double> rows(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      double s = 0;
      for (int i = -reach; i <= reach; ++i) {
        s += k[i + reach] * in.view().at(std::clamp(x + i, 0, w - 1), y);
      }
      rows[y * w + x] = s / total;
    }
  }
  GrayImage out(w, h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      double s = 0;
      for (int i = -reach; i <= reach; ++i) {
        s += k[i + reach] * rows[std::clamp(y + i, 0, h - 1) * w + x];
      }
      out.at(x, y) = static_cast<std::uint8_t>(std::clamp(std::lround(s / total), 0L, 255L));
    }
  }
  return out;
}

// A drawn ball behind a soft lens, blurred by 0.28 of its radius (BallNet reads the drawn ball up
// to some 0.22; the real dark-hall NAO frame's ball of 21 px is as soft): BallNet rejects its
// patch, the sharpened look accepts it; without the look it stays rejected. The sharp ball is
// BallNet's alone (no look).
TEST(BallDetector, SharpenedLookFindsABallASoftLensBlurred) {
  const CameraModel cam = test::testCamera(22);
  const BallDetectorParams shipped = BallDetectorParams::loadDefault();
  ASSERT_GT(shipped.sharpen_sigma_radii, 0);
  BallDetectorParams off = shipped;
  off.sharpen_sigma_radii = 0;
  for (const double d : {0.8, 1.2, 1.6, 2.0}) {
    GrayImage sharp = test::renderScene(cam, carpetOnly(5));
    const test::DrawnBall b = test::drawBall(sharp, cam, {d, -0.1});
    ASSERT_GE(b.radius_px, shipped.sharpen_min_radius_px) << d;
    const std::vector<BallProposal> props = {{b.centre_px, b.radius_px, 1}};
    std::vector<BallDecision> with, without;
    BallDetector::load(shipped).run(sharp.view(), cam, props, &with);
    EXPECT_TRUE(with[0].detected) << d;
    EXPECT_EQ(with[0].sharpened_confidence, -1) << d;
    const GrayImage soft = defocused(sharp, 0.28 * b.radius_px);
    const auto balls = BallDetector::load(shipped).run(soft.view(), cam, props, &with);
    BallDetector::load(off).run(soft.view(), cam, props, &without);
    EXPECT_LT(with[0].ball_confidence, shipped.ball_min_confidence) << d;
    EXPECT_GE(with[0].sharpened_confidence, shipped.sharpen_min_confidence) << d;
    ASSERT_EQ(balls.size(), 1u) << d;
    EXPECT_EQ(balls[0].radius_px, b.radius_px) << d;
    EXPECT_FALSE(without[0].detected) << d;
    EXPECT_EQ(without[0].sharpened_confidence, -1) << d;
  }
}

// The same soft lens over a lone line crossing and a foot: the proposals there are no ball, though
// BoostBallNet lets all through (its bar at 0), so the sharpened look sees every one BallNet
// rejects.
TEST(BallDetector, SharpenedLookFindsNoBallOnASoftLineCrossingOrFoot) {
  const CameraModel cam = test::testCamera(22);
  test::SyntheticScene scene = carpetOnly(8);
  scene.segments.push_back({{0.5, 0.0}, {4.0, 0.0}});
  scene.segments.push_back({{1.4, -2.0}, {1.4, 2.0}});
  GrayImage image = test::renderScene(cam, scene);
  test::drawFoot(image, cam, {1.1, 0.3});
  for (const double sigma : {4.0, 6.0}) {
    const GrayImage soft = defocused(image, sigma);
    const auto props = proposeOnly(soft, cam, BallProposerParams::loadDefault());
    std::vector<BallDecision> d;
    BallDetectorParams p = BallDetectorParams::loadDefault();
    p.boost_min_confidence = 0;
    const auto balls = BallDetector::load(p).run(soft.view(), cam, props, &d);
    EXPECT_TRUE(balls.empty()) << sigma << describe(props);
    EXPECT_TRUE(std::any_of(d.begin(), d.end(),
                            [](const BallDecision& x) { return x.sharpened_confidence >= 0; }))
        << sigma << describe(props);
  }
}

// Draws a ball on the row of a ball `d` m ahead, its centre `in_radii` of its radius inside the
// image's left (or right) border.
test::DrawnBall drawBallAtBorder(GrayImage& image, const CameraModel& cam, double d, double in_radii, bool left) {
  const Eigen::Vector2d ahead = *cam.robotToPixel(Eigen::Vector3d(d, 0, 0.05));
  const double r = *cam.ballRadiusPx(ahead, 0.05);
  const double x = left ? in_radii * r : cam.intrinsics().width_px - in_radii * r;
  return test::drawBall(image, cam, *cam.pixelToGround({x, ahead.y()}, 0.05));
}

// A ball the image's left or right border cuts to some 70 % in view: the patch repeats the border
// pixel over the cut part and BallNet rejects it; mirrored about the border the visible part
// completes a ball, which the shipped detector takes. The same look at a foot and at a line crossing
// the border cuts (every proposal let through BoostBallNet) finds nothing.
TEST(BallDetector, MirroredLookFindsABallTheBorderCuts) {
  const CameraModel cam = test::testCamera(22);
  const BallDetectorParams shipped = BallDetectorParams::loadDefault();
  ASSERT_LE(shipped.border_mirror_min_confidence, 1);
  BallDetectorParams off = shipped;
  off.border_mirror_min_confidence = 2;
  int rejected_without = 0;
  for (const double d : {0.6, 0.7, 0.8, 1.0}) {
    for (const bool left : {true, false}) {
      // The ball's centre 0.3 radii inside the border: some 70 % in view.
      GrayImage image = test::renderScene(cam, carpetOnly(6));
      const test::DrawnBall b = drawBallAtBorder(image, cam, d, 0.3, left);
      const std::vector<BallProposal> props = {{b.centre_px, b.radius_px, 1}};
      std::vector<BallDecision> with, without;
      const auto balls = BallDetector::load(shipped).run(image.view(), cam, props, &with);
      BallDetector::load(off).run(image.view(), cam, props, &without);
      ASSERT_EQ(balls.size(), 1u) << d << (left ? " left" : " right");
      EXPECT_TRUE(with[0].detected);
      rejected_without += !without[0].detected;
      if (with[0].ball_confidence < shipped.ball_min_confidence) {
        EXPECT_GE(with[0].mirrored_confidence, shipped.border_mirror_min_confidence) << d << (left ? " left" : " right");
        EXPECT_FALSE(without[0].detected) << d << (left ? " left" : " right");
      }
    }
  }
  EXPECT_GT(rejected_without, 0) << "BallNet took every cut ball without the mirrored look";
  // A foot and a line crossing at the left border.
  test::SyntheticScene scene = carpetOnly(9);
  const Eigen::Vector2d at_border = *cam.pixelToGround({3, 300}, 0);
  scene.segments.push_back({{at_border.x() - 1, at_border.y()}, {at_border.x() + 1, at_border.y()}});
  scene.segments.push_back({{at_border.x(), at_border.y() - 1}, {at_border.x(), at_border.y() + 1}});
  GrayImage image = test::renderScene(cam, scene);
  test::drawFoot(image, cam, *cam.pixelToGround({5, 400}, 0));
  BallDetectorParams all = shipped;
  all.boost_min_confidence = 0;
  for (const auto& [pixel, what] : {std::pair{Eigen::Vector2d(3, 300), "crossing"}, std::pair{Eigen::Vector2d(5, 400), "foot"}}) {
    const double r = *cam.ballRadiusPx(pixel, 0.05);
    std::vector<BallProposal> props;
    for (const double dx : {-0.5, 0.0, 0.5}) props.push_back({{pixel.x() + dx * r, pixel.y()}, r, 1});
    std::vector<BallDecision> d;
    EXPECT_TRUE(BallDetector::load(all).run(image.view(), cam, props, &d).empty()) << what;
    EXPECT_TRUE(std::any_of(d.begin(), d.end(), [](const BallDecision& x) { return x.mirrored_confidence >= 0; }))
        << what << ": no mirrored look";
  }
}

// BoostBallNet scores a proposal the border cuts by the better of its look at the patch and at the
// patch mirrored about the border: never lower than the first look alone, higher for cut balls
// whose mirrored patch looks more like a ball; a proposal inside the image keeps its one look.
TEST(BallDetector, BoostBallNetTakesTheBetterOfTheCutAndTheMirroredPatch) {
  const CameraModel cam = test::testCamera(22);
  const BallDetectorParams shipped = BallDetectorParams::loadDefault();
  ASSERT_EQ(shipped.boost_border_mirror, 1);
  BallDetectorParams off = shipped;
  off.boost_border_mirror = 0;
  int raised = 0;
  for (const double d : {0.6, 0.7, 0.8, 1.0}) {
    for (const double in : {0.0, 0.3}) {
      GrayImage image = test::renderScene(cam, carpetOnly(6));
      const test::DrawnBall b = drawBallAtBorder(image, cam, d, in, true);
      const test::DrawnBall inside = test::drawBall(image, cam, {d, 0.0});
      const std::vector<BallProposal> props = {{b.centre_px, b.radius_px, 1}, {inside.centre_px, inside.radius_px, 1}};
      std::vector<BallDecision> with, without;
      BallDetector::load(shipped).run(image.view(), cam, props, &with);
      BallDetector::load(off).run(image.view(), cam, props, &without);
      EXPECT_GE(with[0].boost_confidence, without[0].boost_confidence) << d << " m, " << in;
      EXPECT_EQ(with[1].boost_confidence, without[1].boost_confidence) << d << " m, " << in;
      raised += with[0].boost_confidence > without[0].boost_confidence;
    }
  }
  EXPECT_GT(raised, 0) << "the mirrored look never raised a cut ball's score";
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::string writeTemp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/ball_" + name;
  std::ofstream(path) << text;
  return path;
}

TEST(BallParams, DefaultsEqualTheShippedFilesAndLoadingIsStrict) {
  EXPECT_EQ(BallProposerParams::loadDefault(), BallProposerParams{});
  EXPECT_EQ(BallDetectorParams::loadDefault(), BallDetectorParams{});
  const std::string prop = readFile(defaultParamDir() + "/ball_proposer.yaml");
  EXPECT_THROW(BallProposerParams::load(writeTemp("extra.yaml", prop + "surprise: 1\n")), Error);
  std::string nan = prop;
  nan.replace(nan.find("min_response: "), 14, "min_response: .nan #");
  EXPECT_THROW(BallProposerParams::load(writeTemp("nan.yaml", nan)), Error);
  const std::string det = readFile(defaultParamDir() + "/ball_detector.yaml");
  std::string missing = det.substr(0, det.find("max_balls"));
  EXPECT_THROW(BallDetectorParams::load(writeTemp("missing.yaml", missing)), Error);
  EXPECT_THROW(BallDetector::load(BallDetectorParams{}, "/nonexistent/models"), Error);
}

}  // namespace
// A drawn ball behind a slightly soft lens (0.15 of its radius), smeared sideways by 1.2 radii
// while the camera turned as far: BallNet rejects it (0.3-0.4) and neither the rescaled nor the
// sharpened look takes it; with the camera's smear taken back BallNet scores it higher (measured
// 0.60 and 0.68 at 1.4 and 1.8 m), and at a bar under that the deblurred look detects it. No look
// where the camera stood still, turned less than deblur_min_camera_smear_radii, or for a ball under
// deblur_min_radius_px; none with deblur_iterations 0.
TEST(BallDetector, DeblurredLookTakesTheCamerasSmearBack) {
  CameraModel cam = test::testCamera(22);
  BallDetectorParams p = BallDetectorParams::loadDefault();
  ASSERT_GT(p.deblur_iterations, 0);
  p.boost_min_confidence = 0;
  for (const double d : {1.4, 1.8}) {
    GrayImage image = test::renderScene(cam, carpetOnly(5));
    const test::DrawnBall b = test::drawBall(image, cam, {d, -0.1});
    const double r = b.radius_px;
    ASSERT_GE(r, p.deblur_min_radius_px) << d;
    const int len = static_cast<int>(std::lround(1.2 * r));
    const GrayImage frame = defocused(smearedSideways(image, len), 0.15 * r);
    const std::vector<BallProposal> props = {{b.centre_px, r, 1}};
    std::vector<BallDecision> dd;
    const auto look = [&](const BallDetectorParams& q, const Eigen::Vector2d& camera_smear_px) {
      cam.setExposureSmearPx(camera_smear_px);
      return BallDetector::load(q).run(frame.view(), cam, props, &dd);
    };
    const Eigen::Vector2d turned(len, 0);
    EXPECT_TRUE(look(p, turned).empty()) << d;
    EXPECT_LT(dd[0].ball_confidence, p.ball_min_confidence) << d;
    EXPECT_LT(dd[0].sharpened_confidence, p.sharpen_min_confidence) << d;
    EXPECT_GT(dd[0].deblurred_confidence, dd[0].ball_confidence + 0.15f) << d;
    BallDetectorParams lower = p;
    lower.deblur_min_confidence = 0.5;
    const std::vector<BallPercept> balls = look(lower, turned);
    ASSERT_EQ(balls.size(), 1u) << d;
    EXPECT_EQ(balls[0].centre_px, b.centre_px) << d;
    look(lower, {0, 0});
    EXPECT_EQ(dd[0].deblurred_confidence, -1) << d;
    EXPECT_FALSE(dd[0].detected) << d;
    look(lower, {0.4 * r, 0});
    EXPECT_EQ(dd[0].deblurred_confidence, -1) << d;
    BallDetectorParams off = lower;
    off.deblur_iterations = 0;
    EXPECT_TRUE(look(off, turned).empty()) << d;
    EXPECT_EQ(dd[0].deblurred_confidence, -1) << d;
    BallDetectorParams small = lower;
    small.deblur_min_radius_px = r + 1;
    look(small, turned);
    EXPECT_EQ(dd[0].deblurred_confidence, -1) << d;
  }
}

// A lone line crossing and a foot smeared by a 15 px turn of the camera: the proposals there are no
// ball, though BoostBallNet lets all through, so the deblurred look sees those BallNet rejects.
TEST(BallDetector, DeblurredLookFindsNoBallOnASmearedCrossingOrFoot) {
  CameraModel cam = test::testCamera(22);
  test::SyntheticScene scene = carpetOnly(8);
  scene.segments.push_back({{0.5, 0.0}, {4.0, 0.0}});
  scene.segments.push_back({{1.4, -2.0}, {1.4, 2.0}});
  GrayImage image = test::renderScene(cam, scene);
  test::drawFoot(image, cam, {1.1, 0.3});
  const GrayImage smeared = smearedSideways(image, 15);
  cam.setExposureSmearPx({15, 0});
  const auto props = proposeOnly(smeared, cam, BallProposerParams::loadDefault());
  BallDetectorParams p = BallDetectorParams::loadDefault();
  p.boost_min_confidence = 0;
  std::vector<BallDecision> d;
  const auto balls = BallDetector::load(p).run(smeared.view(), cam, props, &d);
  EXPECT_TRUE(balls.empty()) << describe(props);
  EXPECT_TRUE(std::any_of(d.begin(), d.end(), [](const BallDecision& x) { return x.deblurred_confidence >= 0; }))
      << describe(props);
}

}  // namespace colorfree
