#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <opencv2/imgproc.hpp>
#include <random>

#include "colorfree/perception/cnn/net.h"
#include "colorfree/perception/cnn/patch.h"
#include "colorfree/perception/cnn/shipped_nets.h"
#include "colorfree/perception/error.h"
#include "colorfree/perception/high_contrast.h"
#include "colorfree/perception/noise.h"
#include "colorfree/perception/robot_detector.h"
#include "colorfree/perception/robot_orientation.h"
#include "colorfree/perception/robot_proposer.h"
#include "drawn_robots.h"
#include "synthetic_field.h"

namespace colorfree {
namespace {

RobotProposals propose(const GrayImage& img, const CameraModel& cam) {
  const IgnoreMask all = IgnoreMask::all(img.width(), img.height());
  const ContrastRegions regions = HighContrastDetector().run(img.view(), all);
  return RobotProposer(RobotProposerParams::loadDefault(), FieldDimensions::loadDefault())
      .run(img.view(), cam, all, regions, true);
}

TEST(RobotParams, DefaultsEqualShippedFiles) {
  EXPECT_EQ(RobotProposerParams{}, RobotProposerParams::loadDefault());
  EXPECT_EQ(RobotDetectorParams{}, RobotDetectorParams::loadDefault());
  EXPECT_EQ(RobotOrientationParams{}, RobotOrientationParams::loadDefault());
}

TEST(RobotProposer, FindsTheFeetOfADrawnRobot) {
  const CameraModel cam = testCamera();
  GrayImage img = carpet(1);
  const Eigen::Vector2d feet = drawRobot(img, cam, {1.5, 0.2});
  const RobotProposals out = propose(img, cam);
  ASSERT_EQ(out.proposals.size(), 1u);
  const RobotProposal& p = out.proposals[0];
  const double h = robotSizePx(cam, feet).h;
  EXPECT_NEAR(p.feet_px.y(), feet.y(), 2.0);
  EXPECT_NEAR(p.feet_px.x(), feet.x(), 0.15 * h);
  EXPECT_LT(p.box.y0, feet.y() - 0.9 * h);
  EXPECT_GT(p.box.y1, feet.y());
}

TEST(RobotProposer, TwoRobotsSideBySideGiveTwoProposals) {
  const CameraModel cam = testCamera();
  GrayImage img = carpet(2);
  drawRobot(img, cam, {1.5, 0.25});
  drawRobot(img, cam, {1.5, -0.25});
  EXPECT_EQ(propose(img, cam).proposals.size(), 2u);
}

TEST(RobotProposer, NothingOnBlankCarpetLinesOrABall) {
  const CameraModel cam = testCamera();
  GrayImage img = carpet(3);
  EXPECT_TRUE(propose(img, cam).proposals.empty());
  cv::Mat m = wrap(img);
  // A field line across the image and a ball-sized bright disc.
  cv::line(m, cv::Point(0, 300), cv::Point(639, 320), cv::Scalar(220), 6);
  const Eigen::Vector2d ball = *cam.robotToPixel({1.2, 0, 0.05});
  const double r = *cam.ballRadiusPx(ball, 0.05);
  cv::circle(m, cv::Point(int(ball.x()), int(ball.y())), int(r), cv::Scalar(220), cv::FILLED);
  const RobotProposals out = propose(img, cam);
  EXPECT_TRUE(out.proposals.empty());
  EXPECT_FALSE(out.rejected.empty());  // the scan lines saw them and said why
}

// A robot whose legs have the given gray level above white feet `feet_px_tall` pixels high.
Eigen::Vector2d drawShadedRobot(GrayImage& img, const CameraModel& cam, const Eigen::Vector2d& ground,
                                int leg_gray, int feet_px_tall) {
  const Eigen::Vector2d feet = *cam.robotToPixel({ground.x(), ground.y(), 0});
  const auto [h, w] = robotSizePx(cam, feet);
  cv::Mat m = wrap(img);
  for (double side : {-0.3, 0.3}) {
    const double cx = feet.x() + side * w;
    cv::rectangle(m, cv::Point(int(cx - 0.12 * w), int(feet.y() - 0.5 * h)),
                  cv::Point(int(cx + 0.12 * w), int(feet.y()) - 1), cv::Scalar(leg_gray), cv::FILLED);
    cv::rectangle(m, cv::Point(int(cx - 0.14 * w), int(feet.y()) - feet_px_tall),
                  cv::Point(int(cx + 0.14 * w), int(feet.y()) - 1), cv::Scalar(210), cv::FILLED);
  }
  return feet;
}

std::string describe(const RobotProposals& out) {
  std::string s;
  for (const RobotProposal& p : out.proposals) {
    s += " feet (" + std::to_string(p.feet_px.x()) + ", " + std::to_string(p.feet_px.y()) + ")";
  }
  for (const Eigen::Vector2d& f : out.feet_points_px) {
    s += " <" + std::to_string(f.x()) + ", " + std::to_string(f.y()) + ">";
  }
  for (const RejectedRobotCandidate& r : out.rejected) {
    s += " [" + std::string(robotRejectReasonName(r.reason)) + " (" + std::to_string(r.feet_px.x()) +
         ", " + std::to_string(r.feet_px.y()) + ")]";
  }
  return s;
}

bool proposedAt(const RobotProposals& out, const Eigen::Vector2d& feet, double h) {
  for (const RobotProposal& p : out.proposals) {
    if (std::abs(p.feet_px.y() - feet.y()) <= 2.0 && std::abs(p.feet_px.x() - feet.x()) <= 0.15 * h) {
      return true;
    }
  }
  return false;
}

TEST(RobotProposer, FieldLineJustBelowTheFeetDoesNotBecomeTheFeet) {
  // The line's run ends at the carpet between it and the feet; it must not count the robot's
  // legs above that gap (it did: the proposal sat on the line, a robot height too low).
  const CameraModel cam = testCamera();
  GrayImage img = carpet(5);
  const Eigen::Vector2d feet = drawRobot(img, cam, {1.5, 0.0});
  const double h = robotSizePx(cam, feet).h;
  cv::Mat m = wrap(img);
  const int line_y = int(feet.y()) + 14;
  cv::rectangle(m, cv::Point(0, line_y), cv::Point(639, line_y + 5), cv::Scalar(220), cv::FILLED);
  const RobotProposals out = propose(img, cam);
  EXPECT_TRUE(proposedAt(out, feet, h));
  for (const RobotProposal& p : out.proposals) EXPECT_LT(p.feet_px.y(), line_y - 4);
}

// Fills the ground rectangle [x0, x1] × [y0, y1] (robot frame, metres) as the camera sees it.
void fillGround(GrayImage& img, const CameraModel& cam, double x0, double x1, double y0, double y1,
                int gray) {
  std::vector<cv::Point> corners;
  for (const Eigen::Vector2d& g : {Eigen::Vector2d(x0, y0), Eigen::Vector2d(x0, y1),
                                   Eigen::Vector2d(x1, y1), Eigen::Vector2d(x1, y0)}) {
    const Eigen::Vector2d px = *cam.robotToPixel({g.x(), g.y(), 0});
    corners.emplace_back(int(std::lround(px.x())), int(std::lround(px.y())));
  }
  cv::Mat m = wrap(img);
  cv::fillConvexPoly(m, corners, cv::Scalar(gray));
}

TEST(RobotProposer, FieldLineInFrontOfARobotsShadowIsNoFeet) {
  // The run from the line's lower edge takes the shadow for legs in shade and reaches the robot:
  // without the line test the box stood on the line, 0.25 m nearer than the robot.
  const CameraModel cam = testCamera();
  GrayImage img = carpet(11);
  fillGround(img, cam, 1.25, 1.5, -0.12, 0.12, 30);  // the shadow, up to the feet
  fillGround(img, cam, 1.2, 1.25, -3, 3, 220);       // the line across the image
  const Eigen::Vector2d feet = drawRobot(img, cam, {1.5, 0.0});
  const double h = robotSizePx(cam, feet).h;
  const double line_y = cam.robotToPixel({1.2, 0, 0})->y();
  const RobotProposals out = propose(img, cam);
  EXPECT_TRUE(proposedAt(out, feet, h)) << describe(out);
  for (const RobotProposal& p : out.proposals)
    EXPECT_LT(p.feet_px.y(), line_y - 4) << describe(out);
  EXPECT_TRUE(std::any_of(out.rejected.begin(), out.rejected.end(), [](const auto& r) {
    return r.reason == RobotRejectReason::kFieldLine;
  })) << describe(out);

  RobotProposerParams no_test = RobotProposerParams::loadDefault();
  no_test.line_stripe_factor = 0;
  const IgnoreMask all = IgnoreMask::all(img.width(), img.height());
  const RobotProposals old =
      RobotProposer(no_test, FieldDimensions::loadDefault())
          .run(img.view(), cam, all, HighContrastDetector().run(img.view(), all));
  ASSERT_FALSE(old.proposals.empty());
  EXPECT_NEAR(old.proposals[0].feet_px.y(), line_y, 3) << describe(old);
}

TEST(RobotProposer, LegsInShadeDarkerThanTheCarpetStillMakeARobot) {
  // Directional light: white soles, the legs above them darker than the lit carpet.
  const CameraModel cam = testCamera();
  GrayImage img = carpet(6, 90);
  const Eigen::Vector2d feet = drawShadedRobot(img, cam, {2.0, 0.1}, 40, 6);
  const double h = robotSizePx(cam, feet).h;
  EXPECT_TRUE(proposedAt(propose(img, cam), feet, h));
}

TEST(RobotProposer, CarpetAboveADarkPatchAtTheLowerBorderIsNoRobot) {
  // A scan stretch that starts at the lower border starts on whatever is there: here a dark
  // patch (the black patch of a ball cut by the border, a shadow). The carpet above it is
  // brighter than that start, but no brighter than the carpet beside it: no robot stands there.
  const CameraModel cam = testCamera();
  GrayImage img = carpet(9, 90);
  cv::rectangle(wrap(img), cv::Point(280, 450), cv::Point(360, 479), cv::Scalar(25), cv::FILLED);
  const IgnoreMask all = IgnoreMask::all(img.width(), img.height());
  const ContrastRegions regions = HighContrastDetector().run(img.view(), all);
  RobotProposerParams params = RobotProposerParams::loadDefault();
  const RobotProposals out = RobotProposer(params, FieldDimensions::loadDefault())
                                 .run(img.view(), cam, all, regions, true);
  EXPECT_TRUE(out.proposals.empty()) << describe(out);
  // Without the test beside it (and without the lit-carpet test, which takes the carpet above
  // the patch for lit carpet as well): a robot box on the patch.
  params.beside_width_factor = 0;
  params.lit_band_beside_width_factor = 0;
  const RobotProposals unchecked = RobotProposer(params, FieldDimensions::loadDefault())
                                       .run(img.view(), cam, all, regions, true);
  EXPECT_FALSE(unchecked.proposals.empty()) << describe(unchecked);
}

TEST(RobotProposer, NearRobotWhoseFeetTheLowerBorderCutsStandsAtTheBorder) {
  // A robot 0.55 m away: its feet are below the image, its legs reach the lower border. The scan
  // lines through the legs start on them; measured against the carpet beside the robot they are
  // a robot's, and its box stands at the border (game.yaml's near robot, README robot19). Against
  // the lowest pixel alone the legs were the carpet.
  const CameraModel cam = testCamera();
  GrayImage img = carpet(11);
  const Eigen::Vector2d feet = drawRobot(img, cam, {0.55, 0.0});
  ASSERT_GT(feet.y(), 480);  // the feet are cut off
  const auto near_border = [&](const RobotProposals& out) {
    for (const RobotProposal& p : out.proposals) {
      if (p.feet_px.y() >= 470 &&
          std::abs(p.feet_px.x() - feet.x()) <= 0.15 * robotSizePx(cam, feet).h)
        return true;
    }
    return false;
  };
  const IgnoreMask all = IgnoreMask::all(img.width(), img.height());
  const ContrastRegions regions = HighContrastDetector().run(img.view(), all);
  RobotProposerParams params = RobotProposerParams::loadDefault();
  const RobotProposals out = RobotProposer(params, FieldDimensions::loadDefault())
                                 .run(img.view(), cam, all, regions, true);
  EXPECT_TRUE(near_border(out)) << "feet " << feet.transpose() << describe(out);
  params.border_reference_beside = false;
  const RobotProposals lowest = RobotProposer(params, FieldDimensions::loadDefault())
                                    .run(img.view(), cam, all, regions, true);
  EXPECT_FALSE(near_border(lowest)) << describe(lowest);
}

TEST(RobotProposer, RobotWhoseBodyTheLowerBorderCutsIsProposedWithItsFeetBelow) {
  // A robot 0.45 m in front of a camera pitched 5 deg down (a top camera, the head level): the
  // lower border cuts its body above the crotch, and no scan line reaches its legs. The lowest row
  // shows a span brighter than the carpet, wider than any robot standing on that row: it is
  // proposed as a robot as wide as the span, its feet below the image. A field line along the
  // border, as wide but a stripe, is none; without the test the robot has no box that holds it.
  CameraPose pose;
  pose.height_m = 0.5;
  pose.pitch_rad = 5 * std::numbers::pi / 180;
  const CameraModel cam(
      CameraIntrinsics::fromHorizontalFov(640, 480, 60.9 * std::numbers::pi / 180), pose);
  GrayImage img = carpet(41);
  const Eigen::Vector2d feet = drawRobot(img, cam, {0.45, 0.05});
  const auto [h, w] = robotSizePx(cam, feet);
  ASSERT_GT(feet.y() - 0.37 * h, 480);  // the border cuts the body, not the legs
  const double body_x0 = feet.x() - 0.45 * w, body_x1 = feet.x() + 0.45 * w;
  const auto holds_body = [&](const RobotProposals& out) {
    for (const RobotProposal& p : out.proposals) {
      if (p.feet_px.y() > 480 && p.box.x0 <= body_x0 + 0.1 * w && p.box.x1 >= body_x1 - 0.1 * w &&
          p.box.x1 - p.box.x0 <= 1.5 * (body_x1 - body_x0) && p.box.y0 <= feet.y() - 0.8 * h)
        return true;
    }
    return false;
  };
  const IgnoreMask all = IgnoreMask::all(img.width(), img.height());
  RobotProposerParams params = RobotProposerParams::loadDefault();
  ASSERT_GT(params.border_robot_min_width_factor, 0);
  const auto run = [&](const GrayImage& image) {
    return RobotProposer(params, FieldDimensions::loadDefault())
        .run(image.view(), cam, all, HighContrastDetector().run(image.view(), all), true);
  };
  const RobotProposals out = run(img);
  EXPECT_TRUE(holds_body(out)) << "feet " << feet.transpose() << " h " << h << describe(out);
  // A field line along the lower border, as wide as the body: no box with its feet below.
  GrayImage line = carpet(42);
  cv::Mat m = wrap(line);
  cv::rectangle(m, cv::Point(int(body_x0), 466), cv::Point(int(body_x1), 479), cv::Scalar(220),
                cv::FILLED);
  const RobotProposals on_line = run(line);
  for (const RobotProposal& p : on_line.proposals) {
    EXPECT_LE(p.feet_px.y(), 480) << describe(on_line);
  }
  params.border_robot_min_width_factor = 0;
  const RobotProposals without = run(img);
  EXPECT_FALSE(holds_body(without)) << describe(without);
}

TEST(RobotProposer, HandOfARobotBehindANearerOneIsHeldBackBehindIt) {
  // A at 0.9 m; B at 2 m behind A's right side (its feet in A's box, above A's knees: B's box
  // comes after the free-standing ones); B's hand out to the right of A's box, 0.22 of B's height
  // above B's feet. The hand's box is free-standing, so it is kept before B's. Once B's box is
  // kept, the hand lies in its lower part: it is held back behind B (README robot19), as a hand
  // found after its robot's box is.
  const CameraModel cam = testCamera();
  GrayImage img = carpet(12);
  const Eigen::Vector2d b_feet = drawRobot(img, cam, {2.0, -0.05});
  const Eigen::Vector2d a_feet = drawRobot(img, cam, {0.9, 0.15});
  const double b_h = robotSizePx(cam, b_feet).h;
  const int hand_x = static_cast<int>(b_feet.x()) + 44;
  const int hand_y = static_cast<int>(b_feet.y() - 0.22 * b_h);
  cv::rectangle(wrap(img), cv::Point(hand_x - 9, hand_y - 70), cv::Point(hand_x + 9, hand_y - 1),
                cv::Scalar(205), cv::FILLED);
  const RobotProposals out = propose(img, cam);
  const auto near = [&](const RobotProposal& p, const Eigen::Vector2d& f) {
    return std::abs(p.feet_px.y() - f.y()) <= 4 && std::abs(p.feet_px.x() - f.x()) <= 14;
  };
  int a = -1, b = -1;
  for (std::size_t i = 0; i < out.proposals.size(); ++i) {
    if (near(out.proposals[i], a_feet)) a = static_cast<int>(i);
    if (near(out.proposals[i], b_feet)) b = static_cast<int>(i);
    EXPECT_FALSE(near(out.proposals[i], {hand_x, hand_y}))
        << "the hand is a proposal" << describe(out);
  }
  ASSERT_GE(a, 0) << "A at " << a_feet.transpose() << describe(out);
  ASSERT_GE(b, 0) << "B at " << b_feet.transpose() << describe(out);
  bool held = false;
  for (const HeldBackRobotProposal& h : out.held_back) {
    if (near(h.proposal, {hand_x, hand_y})) {
      held = true;
      EXPECT_EQ(h.nearer, std::vector<int>{b});
    }
  }
  EXPECT_TRUE(held) << "hand at " << hand_x << ", " << hand_y << describe(out);
}

TEST(RobotProposer, BallCutByTheLowerBorderHidesNoRobotBehindIt) {
  // A ball at the lower border (white with black patches): the carpet above its patches is no
  // robot, and no box standing on it drops the feet of a far robot in its upper half.
  const CameraModel cam = testCamera();
  GrayImage img = carpet(7);
  const Eigen::Vector2d far_feet = drawRobot(img, cam, {4.0, 0.0});
  const double h = robotSizePx(cam, far_feet).h;
  cv::Mat m = wrap(img);
  const cv::Point c(int(far_feet.x()), 479 + 10);
  cv::circle(m, c, 45, cv::Scalar(215), cv::FILLED);
  for (int dx : {-24, 0, 24}) cv::circle(m, {c.x + dx, c.y - 28}, 9, cv::Scalar(25), cv::FILLED);
  const RobotProposals out = propose(img, cam);
  EXPECT_TRUE(proposedAt(out, far_feet, h)) << "far feet " << far_feet.transpose() << describe(out);
  for (const RobotProposal& p : out.proposals) EXPECT_LT(p.feet_px.y(), 420) << describe(out);
}

TEST(RobotProposer, BoxesOfAWideGroupComeAfterAFarRobotUnderTheCap) {
  // A bright band wider than several robots lower in the image (the wall above a far field line
  // gives such rows of boxes) must not take the only place under the cap from a farther robot.
  const CameraModel cam = testCamera();
  GrayImage img = carpet(12);
  const Eigen::Vector2d far_feet = drawRobot(img, cam, {5.0, -1.0});
  const Eigen::Vector2d band_feet = *cam.robotToPixel({3.5, 0.6, 0});
  const auto [band_h, band_w] = robotSizePx(cam, band_feet);
  ASSERT_GT(band_feet.y(), far_feet.y() + 5);
  ASSERT_GT(far_feet.x(), band_feet.x() + 3 * band_w);  // the band stays clear of the far robot
  cv::Mat m = wrap(img);
  cv::rectangle(m, cv::Point(int(band_feet.x() - 3 * band_w), int(band_feet.y() - 0.6 * band_h)),
                cv::Point(int(band_feet.x() + 2 * band_w), int(band_feet.y()) - 1), cv::Scalar(200),
                cv::FILLED);
  RobotProposerParams params = RobotProposerParams::loadDefault();
  // The band is as bright beside as on each scan line: the lit-carpet test would leave only its
  // two ends. Off here, for the rows of boxes the test does not catch.
  params.lit_band_beside_width_factor = 0;
  const IgnoreMask all = IgnoreMask::all(img.width(), img.height());
  const ContrastRegions regions = HighContrastDetector().run(img.view(), all);
  const RobotProposer proposer(params, FieldDimensions::loadDefault());
  const RobotProposals uncapped = proposer.run(img.view(), cam, all, regions, true);
  ASSERT_GE(uncapped.proposals.size(), 3u) << describe(uncapped);  // the band's boxes and the robot
  // The band's boxes are marked as a wide group's pieces (the detector's higher bar), the robot
  // not.
  const double far_h = robotSizePx(cam, far_feet).h;
  for (const RobotProposal& p : uncapped.proposals) {
    const bool on_band = std::abs(p.feet_px.y() - band_feet.y()) <= 2;
    EXPECT_EQ(p.wide_group, on_band) << p.feet_px.transpose() << describe(uncapped);
  }
  params.max_proposals = 1;
  const RobotProposals capped =
      RobotProposer(params, FieldDimensions::loadDefault()).run(img.view(), cam, all, regions, true);
  EXPECT_TRUE(proposedAt(capped, far_feet, far_h))
      << "far feet " << far_feet.transpose() << describe(capped);
  params.defer_width_factor = 100;  // no deferral: the lower band takes the place
  const RobotProposals undeferred =
      RobotProposer(params, FieldDimensions::loadDefault()).run(img.view(), cam, all, regions, true);
  EXPECT_FALSE(proposedAt(undeferred, far_feet, far_h)) << describe(undeferred);
}

TEST(RobotProposer, FarRobotInTheUpperPartOfANearerBoxIsKept) {
  // A far robot beside a near one, its feet inside the near robot's box but high above the near
  // robot's feet (a knee or hand is no higher than half the robot).
  const CameraModel cam = testCamera();
  GrayImage img = carpet(8);
  const Eigen::Vector2d near_px = *cam.robotToPixel({0.8, 0.0, 0});
  const double near_w = robotSizePx(cam, near_px).w;
  const Eigen::Vector2d far_px0 = *cam.robotToPixel({3.0, 0.0, 0});
  const auto far_ground = cam.pixelToGround({near_px.x() - 0.6 * near_w, far_px0.y()});
  ASSERT_TRUE(far_ground.has_value());
  const Eigen::Vector2d far_feet = drawRobot(img, cam, *far_ground);
  const Eigen::Vector2d near_feet = drawRobot(img, cam, {0.8, 0.0});
  const RobotProposals out = propose(img, cam);
  EXPECT_TRUE(proposedAt(out, near_feet, robotSizePx(cam, near_feet).h))
      << "near feet " << near_feet.transpose() << describe(out);
  EXPECT_TRUE(proposedAt(out, far_feet, robotSizePx(cam, far_feet).h))
      << "far feet " << far_feet.transpose() << describe(out);
}

// A near robot 0.8 m ahead and, drawn behind it, a farther one whose feet stand `right_widths`
// of the near robot's widths to the right of its feet and `up_heights` of its heights above them.
struct NearAndFarRobots {
  GrayImage img;
  Eigen::Vector2d near_feet, far_feet;
  double near_h, far_h;
};
NearAndFarRobots drawNearAndFarRobots(const CameraModel& cam, std::uint64_t seed,
                                      double right_widths, double up_heights) {
  NearAndFarRobots s{carpet(seed), {}, {}, 0, 0};
  const Eigen::Vector2d near_px = *cam.robotToPixel({0.8, 0.0, 0});
  const auto [near_h, near_w] = robotSizePx(cam, near_px);
  const auto far_ground =
      cam.pixelToGround({near_px.x() + right_widths * near_w, near_px.y() - up_heights * near_h});
  EXPECT_TRUE(far_ground.has_value());
  s.far_feet = drawRobot(s.img, cam, far_ground.value_or(Eigen::Vector2d(3.0, 0.0)));
  s.near_feet = drawRobot(s.img, cam, {0.8, 0.0});
  s.near_h = near_h;
  s.far_h = robotSizePx(cam, s.far_feet).h;
  return s;
}

TEST(RobotProposer, FarRobotBesideANearOneAboveItsKneesIsKept) {
  // A far robot just beside a near one, its feet inside the near robot's (1.25 robots wide) box
  // and 0.45 of the near robot's height above its feet: above the knees and the hanging hands
  // (about a third of the height up), so no part of the near robot.
  const CameraModel cam = testCamera();
  const auto [img, near_feet, far_feet, near_h, far_h] = drawNearAndFarRobots(cam, 9, 0.58, 0.45);
  const RobotProposals out = propose(img, cam);
  EXPECT_TRUE(proposedAt(out, near_feet, near_h))
      << "near feet " << near_feet.transpose() << describe(out);
  EXPECT_TRUE(proposedAt(out, far_feet, far_h))
      << "far feet " << far_feet.transpose() << describe(out);
}

TEST(RobotProposer, FarRobotInTheLowerPartOfANearerBoxIsHeldBack) {
  // A far robot beside a near one, its feet inside the near robot's box 0.25 of the near robot's
  // height above its feet: where the near robot's hand could be. It is no proposal of its own but
  // held back behind the near one (the detector decides); with no room for held-back candidates
  // it is dropped as an overlap.
  const CameraModel cam = testCamera();
  const auto [img, near_feet, far_feet, near_h, far_h] = drawNearAndFarRobots(cam, 10, 0.3, 0.25);
  const RobotProposals out = propose(img, cam);
  ASSERT_TRUE(proposedAt(out, near_feet, near_h)) << describe(out);
  EXPECT_FALSE(proposedAt(out, far_feet, far_h)) << describe(out);
  int near_index = -1;
  for (std::size_t i = 0; i < out.proposals.size(); ++i) {
    if (std::abs(out.proposals[i].feet_px.y() - near_feet.y()) <= 2)
      near_index = static_cast<int>(i);
  }
  // (The near robot's own crotch edge is held back too.)
  const HeldBackRobotProposal* far = nullptr;
  std::string held;
  for (const HeldBackRobotProposal& h : out.held_back) {
    held += " (" + std::to_string(h.proposal.feet_px.x()) + ", " +
            std::to_string(h.proposal.feet_px.y()) + ")";
    if (std::abs(h.proposal.feet_px.y() - far_feet.y()) <= 2 &&
        std::abs(h.proposal.feet_px.x() - far_feet.x()) <= 0.3 * far_h) {
      far = &h;
    }
  }
  ASSERT_NE(far, nullptr) << "far feet " << far_feet.transpose() << " held back" << held
                          << describe(out);
  EXPECT_EQ(far->nearer, (std::vector<int>{near_index}));

  RobotProposerParams none = RobotProposerParams::loadDefault();
  none.max_held_back = 0;
  const IgnoreMask all = IgnoreMask::all(img.width(), img.height());
  const RobotProposals dropped =
      RobotProposer(none, FieldDimensions::loadDefault())
          .run(img.view(), cam, all, HighContrastDetector().run(img.view(), all), true);
  EXPECT_TRUE(dropped.held_back.empty());
  EXPECT_EQ(dropped.proposals.size(), out.proposals.size());
  bool overlap = false;
  for (const RejectedRobotCandidate& r : dropped.rejected) {
    overlap |=
        r.reason == RobotRejectReason::kOverlap && std::abs(r.feet_px.y() - far_feet.y()) <= 2;
  }
  EXPECT_TRUE(overlap) << describe(dropped);
}

TEST(RobotProposer, FeetStandAtTheBottomOfTheirDarkLowerPart) {
  // The feet's dark side panels (darker than the carpet) under the bright legs: the robot stands
  // at their bottom, not at the bright pixels above them (the darker reference after the dark
  // stretch hides those rows from the brightness test; the orientation stage's feet region
  // hangs from the feet row and lost the toes when it sat a few rows too high).
  const CameraModel cam = testCamera();
  GrayImage img = carpet(9, 70);
  const Eigen::Vector2d feet = drawRobot(img, cam, {1.5, 0.0});
  const auto [h, w] = robotSizePx(cam, feet);
  const int panel_px = static_cast<int>(0.05 * h);
  ASSERT_GE(panel_px, 5);
  cv::Mat m = wrap(img);
  for (double side : {-0.3, 0.3}) {
    const double cx = feet.x() + side * w;
    cv::rectangle(m, cv::Point(int(cx - 0.14 * w), int(feet.y()) - panel_px),
                  cv::Point(int(cx + 0.14 * w), int(feet.y()) - 1), cv::Scalar(25), cv::FILLED);
  }
  const RobotProposals out = propose(img, cam);
  EXPECT_TRUE(proposedAt(out, feet, h)) << "feet " << feet.transpose() << describe(out);
}

TEST(RobotProposer, ALongShadowBelowTheFeetIsNoPartOfThem) {
  // A cast shadow longer than a foot below the white feet: the feet stay where the robot is.
  const CameraModel cam = testCamera();
  GrayImage img = carpet(10, 90);
  const Eigen::Vector2d feet = drawRobot(img, cam, {1.5, 0.0});
  const auto [h, w] = robotSizePx(cam, feet);
  cv::Mat m = wrap(img);
  cv::rectangle(m, cv::Point(int(feet.x() - 0.6 * w), int(feet.y())),
                cv::Point(int(feet.x() + 0.6 * w), int(feet.y() + 0.25 * h)), cv::Scalar(30),
                cv::FILLED);
  const RobotProposals out = propose(img, cam);
  EXPECT_TRUE(proposedAt(out, feet, h)) << "feet " << feet.transpose() << describe(out);
}

// The proposer's parameters with the knee gap for backlit halls (off in the shipped file).
RobotProposerParams kneeGapParams() {
  RobotProposerParams p = RobotProposerParams::loadDefault();
  p.knee_gap_height_fraction = 0.10;
  return p;
}

// A knee joint in its own shade at the carpet's gray (60), 0.15 to 0.23 of the robot's height above
// its feet (longer than a run's gap), from left_w to right_w robot widths beside the feet.
void shadeKnee(GrayImage& img, const Eigen::Vector2d& feet, double h, double w, double left_w,
               double right_w) {
  const int knee_bottom = int(feet.y() - 0.15 * h), knee_top = int(feet.y() - 0.23 * h);
  ASSERT_GT(knee_bottom - knee_top, 0.04 * h + 3);
  cv::rectangle(wrap(img), cv::Point(int(feet.x() + left_w * w), knee_top),
                cv::Point(int(feet.x() + right_w * w), knee_bottom), cv::Scalar(60), cv::FILLED);
}

TEST(RobotProposer, BacklitKneeAtTheCarpetsGrayDoesNotLiftTheFeet) {
  // Directional light from beyond the robot: its knee joints, in their own shade, at the carpet's
  // gray over 0.08 of its height between the lit shins and thighs. Without the knee gap the run
  // from the shins ends there and the scan finds the feet at the thighs, a box too small. With it
  // (shipped) the bridged runs make a box of their own at the feet, besides every box found
  // without the gap; with the bridged feet points joining the others that thigh box is gone.
  const CameraModel cam = testCamera();
  GrayImage img = carpet(12);
  const Eigen::Vector2d feet = drawRobot(img, cam, {1.8, 0.1});
  const auto [h, w] = robotSizePx(cam, feet);
  shadeKnee(img, feet, h, w, -0.5, 0.5);
  const IgnoreMask all = IgnoreMask::all(img.width(), img.height());
  const ContrastRegions regions = HighContrastDetector().run(img.view(), all);
  const auto proposeWith = [&](const RobotProposerParams& p) {
    return RobotProposer(p, FieldDimensions::loadDefault()).run(img.view(), cam, all, regions, true);
  };
  RobotProposerParams no_gap = RobotProposerParams::loadDefault();
  no_gap.knee_gap_height_fraction = 0;
  const RobotProposals without = proposeWith(no_gap);
  EXPECT_FALSE(proposedAt(without, feet, h)) << describe(without);
  ASSERT_FALSE(without.proposals.empty()) << describe(without);

  const RobotProposals out = propose(img, cam);
  EXPECT_TRUE(proposedAt(out, feet, h)) << "feet " << feet.transpose() << describe(out);
  for (const RobotProposal& p : without.proposals) {
    EXPECT_TRUE(proposedAt(out, p.feet_px, h)) << "lost " << p.feet_px.transpose() << describe(out);
  }

  RobotProposerParams joined = RobotProposerParams::loadDefault();
  joined.max_knee_proposals = 0;
  const RobotProposals joined_out = proposeWith(joined);
  EXPECT_TRUE(proposedAt(joined_out, feet, h)) << describe(joined_out);
  EXPECT_LT(joined_out.proposals.size(), out.proposals.size()) << describe(joined_out);
}

TEST(RobotProposer, FeetReachedOverTheKneeOnlyInPartJoinTheOthers) {
  // The legs, blurred by the walk, one lit stretch 0.3 of the robot's width; the shaded knee at
  // the carpet's gray across its left half only. The right half's scan lines find the feet
  // without the knee gap, the left half's only over it: each half alone is narrower than a
  // robot's group (0.2 of its width), the two together make one box at the feet.
  const CameraModel cam = testCamera();
  GrayImage img = carpet(22);
  const Eigen::Vector2d feet = drawRobot(img, cam, {1.8, 0.1});
  const auto [h, w] = robotSizePx(cam, feet);
  cv::Mat m = wrap(img);
  cv::rectangle(m, cv::Point(int(feet.x() - 0.42 * w), int(feet.y() - 0.37 * h)),
                cv::Point(int(feet.x() + 0.42 * w), int(feet.y()) - 1), cv::Scalar(60), cv::FILLED);
  cv::rectangle(m, cv::Point(int(feet.x() - 0.15 * w), int(feet.y() - 0.37 * h)),
                cv::Point(int(feet.x() + 0.15 * w), int(feet.y()) - 1), cv::Scalar(170), cv::FILLED);
  shadeKnee(img, feet, h, w, -0.15, 0);
  const RobotProposals out = propose(img, cam);
  EXPECT_TRUE(proposedAt(out, feet, h)) << "feet " << feet.transpose() << describe(out);
  // Neither half makes a robot's group on its own.
  int narrow_at_feet = 0;
  for (const RejectedRobotCandidate& r : out.rejected) {
    narrow_at_feet += r.reason == RobotRejectReason::kTooNarrow && std::abs(r.feet_px.y() - feet.y()) <= 2;
  }
  EXPECT_GE(narrow_at_feet, 1) << describe(out);
}

// Every window of the image marked as high-contrast (the contrast stage need not mark a lit
// stripe's or band's lower edge), but for the lowest row, where the scan would not know the carpet.
ContrastRegions everyWindowButTheLowestRow(const GrayImage& img) {
  ContrastRegions every;
  every.columns = (img.width() + every.window_px - 1) / every.window_px;
  every.rows = (img.height() + every.window_px - 1) / every.window_px;
  every.mask.assign(static_cast<std::size_t>(every.columns) * every.rows, 1);
  std::fill(every.mask.end() - every.columns, every.mask.end(), 0);
  return every;
}

// The proposals with every window scanned but the lowest row's (the contrast stage need not mark
// what a test draws), the rejected candidates kept.
RobotProposals proposeInEveryWindow(const RobotProposerParams& params, const GrayImage& img,
                                    const CameraModel& cam) {
  return RobotProposer(params, FieldDimensions::loadDefault())
      .run(img.view(), cam, IgnoreMask::all(img.width(), img.height()),
           everyWindowButTheLowestRow(img), true);
}

TEST(RobotProposer, ALitCarpetStripeBelowARobotIsNoShin) {
  // The carpet lit brighter across the image (overexposed light: a bright stripe) a knee's gap
  // below a robot: the stripe runs on beside the robot, so its gap to the legs is no knee, and
  // the robot's feet stay where they are. Every window is scanned (the contrast stage need not
  // mark the stripe's lower edge).
  const CameraModel cam = testCamera();
  GrayImage img = carpet(13);
  const Eigen::Vector2d feet = drawRobot(img, cam, {1.8, 0.1});
  const double h = robotSizePx(cam, feet).h;
  cv::Mat m = wrap(img);
  const int lit_top = int(feet.y() + 0.05 * h);
  cv::rectangle(m, cv::Point(0, lit_top), cv::Point(639, lit_top + int(0.12 * h)), cv::Scalar(110),
                cv::FILLED);
  const RobotProposals out = proposeInEveryWindow(kneeGapParams(), img, cam);
  EXPECT_TRUE(proposedAt(out, feet, h)) << "feet " << feet.transpose() << describe(out);
  for (const RobotProposal& p : out.proposals) {
    EXPECT_LT(p.feet_px.y(), lit_top) << describe(out);
  }
}

TEST(RobotProposer, ARobotBeyondABandOfLitCarpetIsFound) {
  // Uneven light: a band of carpet lit brighter than the darker carpet around it, across the
  // image, ends a little in front of a robot. From its lower edge the band fills a run as a
  // robot's legs would, which ended the scan line's stretch there: the robot beyond it had no
  // feet point. The band is as bright beside as it is on the scan line, the robot's legs are
  // not: the band is carpet, and the scan goes on to the robot. Every window is scanned but the
  // lowest row's.
  const CameraModel cam = testCamera();
  GrayImage img = carpet(19, 60);
  const Eigen::Vector2d feet = drawRobot(img, cam, {3.0, 0.1});
  const double h = robotSizePx(cam, feet).h;
  const int band_top = int(feet.y() + 0.15 * h), band_bottom = int(feet.y() + 1.2 * h);
  ASSERT_LT(band_bottom, 440);
  cv::Mat m = wrap(img);
  cv::Mat band = m.rowRange(band_top, band_bottom);
  band += cv::Scalar(80);  // the carpet's texture stays
  RobotProposerParams params = RobotProposerParams::loadDefault();
  const RobotProposals out = proposeInEveryWindow(params, img, cam);
  EXPECT_TRUE(proposedAt(out, feet, h)) << "feet " << feet.transpose() << describe(out);
  for (const RobotProposal& p : out.proposals) {
    EXPECT_LT(p.feet_px.y(), band_top) << describe(out);  // no box on the band
  }
  params.lit_band_beside_width_factor = 0;  // without the test: the band ends every stretch
  const RobotProposals unchecked = proposeInEveryWindow(params, img, cam);
  EXPECT_FALSE(proposedAt(unchecked, feet, h)) << describe(unchecked);
}

TEST(RobotProposer, ARobotBeyondALineAlongLitCarpetIsFound) {
  // A band of lit carpet (uneven light) from a field line 1.2 m away to a little in front of a
  // robot 3 m away. Where the line is brighter than the lit carpet one robot width beside it (a
  // line that ends or bends there) and soft (seen 10 cm wide), the band's lowest rows were mostly
  // line and passed as a robot's: the run from the line's lower edge through the band to the robot
  // made a box on the line and ended the scan line's stretch. The band test now starts above such
  // a stripe of rows lit beside (at most line_stripe_factor line widths tall).
  const CameraModel cam = testCamera();
  GrayImage img = carpet(19, 60);
  const Eigen::Vector2d feet = drawRobot(img, cam, {3.0, 0.1});
  const double h = robotSizePx(cam, feet).h;
  const int band_top = int(feet.y() + 0.15 * h);
  const int band_bottom = int(std::lround(cam.robotToPixel({1.2, 0, 0})->y()));
  ASSERT_LT(band_bottom, 440);
  cv::Mat m = wrap(img);
  m.rowRange(band_top, band_bottom) += cv::Scalar(80);  // the carpet's texture stays
  fillGround(img, cam, 1.2, 1.3, -0.1, 0.3, 230);       // the line, under the robot's columns
  RobotProposerParams params = RobotProposerParams::loadDefault();
  const RobotProposals out = proposeInEveryWindow(params, img, cam);
  EXPECT_TRUE(proposedAt(out, feet, h)) << "feet " << feet.transpose() << describe(out);
  for (const RobotProposal& p : out.proposals) {
    EXPECT_LT(p.feet_px.y(), band_top) << describe(out);  // no box on the line or the band
  }
  params.line_stripe_factor = 0;  // no stripe (nor line test): the line's run ends the stretches
  const RobotProposals unchecked = proposeInEveryWindow(params, img, cam);
  EXPECT_FALSE(proposedAt(unchecked, feet, h)) << describe(unchecked);
}

TEST(RobotProposer, NoRobotStandsFartherThanTheCarpetsDiagonal) {
  // Two robot-like shapes: 11 m away (on the carpet, seen from one corner of the field) and 15 m
  // away, beyond the farthest two points of the carpet (12.8 m): there a frame's noise or the hall
  // behind the boards made boxes RobotNet took for far robots.
  const CameraModel cam = testCamera();
  GrayImage img = carpet(23);
  const Eigen::Vector2d on_carpet = drawRobot(img, cam, {11.0, -1.5});
  const Eigen::Vector2d beyond = drawRobot(img, cam, {15.0, 1.5});
  RobotProposerParams params = RobotProposerParams::loadDefault();
  const RobotProposals out = proposeInEveryWindow(params, img, cam);
  EXPECT_TRUE(proposedAt(out, on_carpet, robotSizePx(cam, on_carpet).h)) << describe(out);
  EXPECT_FALSE(proposedAt(out, beyond, robotSizePx(cam, beyond).h)) << describe(out);
  params.max_distance_carpet_diagonals = 0;
  const RobotProposals unchecked = proposeInEveryWindow(params, img, cam);
  EXPECT_TRUE(proposedAt(unchecked, beyond, robotSizePx(cam, beyond).h)) << describe(unchecked);
}

TEST(RobotProposer, ARobotBehindAShortObjectIsFound) {
  // A short bright object 1.2 m away (as the ball in front of a robot: its run, with its shadow
  // lowering the carpet reference, passes as legs), wider than the robot 3.5 m behind it, whose
  // every scan line it ends. Its object ends low with carpet above it: the scan goes on above it,
  // and the robot behind is held back behind the object's box (classified, and a robot where
  // RobotNet rejects that box).
  const CameraModel cam = testCamera();
  GrayImage img = carpet(29);
  const Eigen::Vector2d far = drawRobot(img, cam, {3.5, 0.0});
  const double far_h = robotSizePx(cam, far).h;
  const Eigen::Vector2d near = *cam.robotToPixel({1.2, 0, 0});
  const auto [near_h, near_w] = robotSizePx(cam, near);
  const double width = 2.2 * robotSizePx(cam, far).w;
  cv::rectangle(wrap(img), cv::Point(int(near.x() - width / 2), int(near.y() - 0.27 * near_h)),
                cv::Point(int(near.x() + width / 2), int(near.y()) - 1), cv::Scalar(200),
                cv::FILLED);
  ASSERT_LT(far.y(), near.y() - 0.4 * near_h);  // carpet between the object and the robot's feet
  const auto held_back_at = [&](const RobotProposals& out) {
    for (const HeldBackRobotProposal& h : out.held_back) {
      const Eigen::Vector2d& f = h.proposal.feet_px;
      if (std::abs(f.y() - far.y()) <= 2.0 && std::abs(f.x() - far.x()) <= 0.15 * far_h)
        return true;
    }
    return false;
  };
  RobotProposerParams params = RobotProposerParams::loadDefault();
  const RobotProposals out = proposeInEveryWindow(params, img, cam);
  EXPECT_TRUE(proposedAt(out, {near.x(), near.y()}, near_h)) << describe(out);  // the object's box
  EXPECT_TRUE(held_back_at(out) || proposedAt(out, far, far_h)) << describe(out);
  params.short_object_height_fraction = 0;  // one feet point per stretch: the object's
  const RobotProposals lowest = proposeInEveryWindow(params, img, cam);
  EXPECT_FALSE(held_back_at(lowest) || proposedAt(lowest, far, far_h)) << describe(lowest);
  params = RobotProposerParams::loadDefault();  // an object taller than the bound hides the robot
  params.short_object_height_fraction = 0.2;
  const RobotProposals tall = proposeInEveryWindow(params, img, cam);
  EXPECT_FALSE(held_back_at(tall) || proposedAt(tall, far, far_h)) << describe(tall);
}

TEST(PixelNoise, MeasuresTheNoiseNotTheObjects) {
  const CameraModel cam = testCamera();
  for (const double sigma : {4.0, 10.0, 20.0}) {
    GrayImage img = carpet(14, 90);  // its own noise: 3
    drawRobot(img, cam, {1.5, 0.2});
    drawRobot(img, cam, {2.5, -0.5});
    cv::rectangle(wrap(img), cv::Point(0, 300), cv::Point(639, 306), cv::Scalar(220), cv::FILLED);
    test::addNoise(img, sigma, 15);
    const double expected = std::hypot(sigma, 3.0);
    const double measured = pixelNoiseGray(img.view(), IgnoreMask::all(640, 480));
    // Within a tenth, and half a bin of the integer differences' histogram (0.5 / 0.6745 / sqrt 2).
    EXPECT_NEAR(measured, expected, 0.1 * expected + 0.53) << "sigma " << sigma;
  }
  GrayImage img = carpet(16);
  EXPECT_THROW(pixelNoiseGray(img.view(), IgnoreMask::all(320, 240)), Error);
}

TEST(RobotProposer, NoisyFrameKeepsTheFeet) {
  // A dark hall's high gain (noise sigma 15 on a carpet of 60): single carpet pixels pass the
  // fixed jump and the runs they start below the robot swallow its feet (the scan goes on above
  // them). The jump that follows the frame's noise finds the feet.
  const CameraModel cam = testCamera();
  GrayImage img = carpet(17);
  const Eigen::Vector2d feet = drawRobot(img, cam, {1.8, 0.1});
  const double h = robotSizePx(cam, feet).h;
  test::addNoise(img, 15, 18);
  const RobotProposals out = propose(img, cam);
  EXPECT_TRUE(proposedAt(out, feet, h)) << "feet " << feet.transpose() << describe(out);
  EXPECT_LE(out.proposals.size(), 3u) << describe(out);

  // The fixed jump alone (and without the lit-carpet test, which also takes most runs the noise
  // starts for carpet) loses the feet.
  RobotProposerParams fixed = RobotProposerParams::loadDefault();
  fixed.noise_jump_factor = 0;
  fixed.lit_band_beside_width_factor = 0;
  const IgnoreMask all = IgnoreMask::all(img.width(), img.height());
  const RobotProposals old = RobotProposer(fixed, FieldDimensions::loadDefault())
                                 .run(img.view(), cam, all, HighContrastDetector().run(img.view(), all));
  EXPECT_FALSE(proposedAt(old, feet, h)) << describe(old);

  // The noise the caller estimated once (the pipeline's Frame) is the one used: the frame's own
  // estimate gives the same proposals, a noise-free claim the fixed jump's.
  const RobotProposer shipped(RobotProposerParams::loadDefault(), FieldDimensions::loadDefault());
  const ContrastRegions regions = HighContrastDetector().run(img.view(), all);
  const RobotProposals given = shipped.run(img.view(), cam, all, regions, false, pixelNoiseGray(img.view(), all));
  EXPECT_EQ(describe(given), describe(shipped.run(img.view(), cam, all, regions)));
  EXPECT_TRUE(proposedAt(given, feet, h)) << describe(given);
  RobotProposerParams no_lit_band = RobotProposerParams::loadDefault();
  no_lit_band.lit_band_beside_width_factor = 0;
  EXPECT_FALSE(proposedAt(RobotProposer(no_lit_band, FieldDimensions::loadDefault())
                              .run(img.view(), cam, all, regions, false, 0.0),
                          feet, h));
}

TEST(RobotProposer, AVeryNoisyFrameIsScannedSmoothed) {
  // Noise sigma 35 (a dark hall at full gain) on a carpet of 125, the legs 75 gray levels
  // brighter: the jump that follows the noise (2.5 sigma) is higher than that, so too few single
  // pixels are lit. Averaged over three pixels of the row the noise falls by the square root of
  // three and the legs are lit.
  const CameraModel cam = testCamera();
  GrayImage img = carpet(21, 125);
  const Eigen::Vector2d feet = drawRobot(img, cam, {1.8, 0.1});
  const double h = robotSizePx(cam, feet).h;
  test::addNoise(img, 35, 22);
  const IgnoreMask all = IgnoreMask::all(img.width(), img.height());
  const ContrastRegions regions = HighContrastDetector().run(img.view(), all);
  RobotProposerParams params = RobotProposerParams::loadDefault();
  ASSERT_GE(pixelNoiseGray(img.view(), all), params.smooth_min_noise_gray);
  const RobotProposals out =
      RobotProposer(params, FieldDimensions::loadDefault()).run(img.view(), cam, all, regions);
  EXPECT_TRUE(proposedAt(out, feet, h)) << "feet " << feet.transpose() << describe(out);
  params.smooth_min_noise_gray = 0;  // each pixel on its own
  const RobotProposals unsmoothed =
      RobotProposer(params, FieldDimensions::loadDefault()).run(img.view(), cam, all, regions);
  EXPECT_FALSE(proposedAt(unsmoothed, feet, h)) << describe(unsmoothed);
}

TEST(RobotProposer, WrongSizedMaskIsAnError) {
  const CameraModel cam = testCamera();
  GrayImage img = carpet(4);
  const IgnoreMask small = IgnoreMask::all(320, 240);
  const ContrastRegions regions = HighContrastDetector().run(img.view(), IgnoreMask::all(640, 480));
  EXPECT_THROW(RobotProposer().run(img.view(), cam, small, regions), Error);
}

PixelBox pixelBox(double x0, double y0, double x1, double y1) {
  PixelBox b;
  b.x0 = x0;
  b.y0 = y0;
  b.x1 = x1;
  b.y1 = y1;
  return b;
}

TEST(RobotDetector, KeptBoxesDropOverlapsAndPartsOfALargerRobot) {
  const RobotDetectorParams p;  // min 0.5, IoU 0.3, inside 0.9
  const PixelBox robot = pixelBox(234, 84, 410, 364);
  const PixelBox hand = pixelBox(340, 114, 408, 222);     // wholly inside the robot's box
  const PixelBox shifted = pixelBox(250, 90, 420, 370);   // IoU with the robot's box > 0.3
  const PixelBox other = pixelBox(500, 100, 560, 200);    // another robot beside it
  const PixelBox half_out = pixelBox(380, 150, 450, 250); // half outside: no part of it
  // The hand more confident than its robot: still the robot stays, the hand goes.
  EXPECT_EQ(keptRobotBoxes({hand, robot, other}, {0.9f, 0.8f, 0.7f}, p), (std::vector<int>{1, 2}));
  EXPECT_EQ(keptRobotBoxes({robot, hand}, {0.9f, 0.6f}, p), (std::vector<int>{0}));
  EXPECT_EQ(keptRobotBoxes({robot, shifted}, {0.7f, 0.9f}, p), (std::vector<int>{1}));
  EXPECT_EQ(keptRobotBoxes({robot, half_out}, {0.9f, 0.8f}, p), (std::vector<int>{0, 1}));
  EXPECT_EQ(keptRobotBoxes({robot, other}, {0.4f, 0.6f}, p), (std::vector<int>{1}));  // below min
  EXPECT_THROW(keptRobotBoxes({robot}, {}, p), Error);
}

TEST(RobotDetector, ASureBoxInsideANearRobotsBoxAboveItsLowerPartIsARobotBehindIt) {
  // A near robot's box reaches round a robot standing behind it (game.yaml's R0 at 1.7 m behind R6
  // at 0.85 m, 0.93 inside its box): kept when RobotNet is sure of it (min_behind_robot_confidence)
  // and its lower edge stands above the near box's lower part (README robot19). A knee or hand box
  // in the lower part, or an unsure one, is still the near robot's part.
  RobotDetectorParams p;  // min 0.5, inside 0.9, behind 0.97, lower part 0.4
  const PixelBox near = pixelBox(100, 40, 400, 470);
  const PixelBox behind = pixelBox(250, 80, 330, 250);  // lower edge 0.51 of the height up
  const PixelBox knee = pixelBox(250, 300, 330, 400);   // lower edge 0.16 of the height up
  EXPECT_EQ(keptRobotBoxes({near, behind}, {1.0f, 0.99f}, p), (std::vector<int>{0, 1}));
  EXPECT_EQ(keptRobotBoxes({behind, near}, {0.99f, 0.98f}, p), (std::vector<int>{0, 1}));
  EXPECT_EQ(keptRobotBoxes({near, behind}, {1.0f, 0.9f}, p), (std::vector<int>{0}));
  EXPECT_EQ(keptRobotBoxes({near, knee}, {1.0f, 0.99f}, p), (std::vector<int>{0}));
  p.behind_lower_part_fraction = 0;
  EXPECT_EQ(keptRobotBoxes({near, behind}, {1.0f, 0.99f}, p), (std::vector<int>{0}));
}

// A proposal with this box, its feet point at the middle of the box's lower edge.
RobotProposal proposal(const PixelBox& box) {
  RobotProposal p;
  p.box = box;
  p.feet_px = {(box.x0 + box.x1) / 2, box.y1};
  return p;
}

// A stand-in robot net whose robot probability is sigmoid(weight (patch mean / 255) + bias).
cnn::Classifier meanNet(float bias, float weight) {
  cnn::Net n = cnn::parseDarknetCfg(
      "# colorfree normalization=unit\n[net]\nwidth=24\nheight=24\nchannels=1\n\n"
      "[convolutional]\nfilters=2\nsize=1\nstride=1\nactivation=linear\n\n[avgpool]\n\n[softmax]\n",
      "mean net");
  n.params() = {0.0f, bias, 0.0f, weight};  // biases (no robot, robot), then weights
  return cnn::Classifier(std::move(n));
}

// A stand-in for RobotNet: its robot probability is sigmoid(40 (patch mean / 255) - 20), above
// 0.5 on patches brighter than mid-gray.
RobotDetector brightnessDetector(const RobotDetectorParams& params = {}) {
  return RobotDetector(params, meanNet(-20, 40));
}

TEST(RobotDetector, HeldBackProposalIsClassifiedOnlyWhenNoNearerBoxHoldsARobot) {
  GrayImage img = carpet(11);
  cv::rectangle(wrap(img), cv::Point(400, 100), cv::Point(460, 220), cv::Scalar(230), cv::FILLED);
  const CameraModel cam = testCamera();
  const RobotProposal carpet_box = proposal(pixelBox(100, 100, 300, 420));  // no robot
  const RobotProposal bright_box = proposal(pixelBox(395, 95, 465, 225));   // a robot
  const RobotProposal behind = proposal(pixelBox(405, 105, 455, 215));      // held back
  RobotDetectorParams params;
  params.min_behind_robot_confidence = 1;  // nothing behind a robot is classified
  const RobotDetector detector = brightnessDetector(params);
  std::vector<RobotProposal> classified;
  std::vector<float> confidences;

  // Behind a box without a robot: freed and classified (a robot).
  auto robots =
      detector.run(img.view(), cam, {carpet_box}, {{behind, {0}}}, &classified, &confidences);
  ASSERT_EQ(classified.size(), 2u);
  ASSERT_EQ(confidences.size(), 2u);
  EXPECT_LT(confidences[0], 0.5f);
  EXPECT_GT(confidences[1], 0.5f);
  ASSERT_EQ(robots.size(), 1u);
  EXPECT_EQ(robots[0].box.x0, behind.box.x0);

  // Behind a box RobotNet accepts, or behind two of which one is a robot: never classified.
  robots = detector.run(img.view(), cam, {bright_box}, {{behind, {0}}}, &classified, &confidences);
  EXPECT_EQ(classified.size(), 1u);
  EXPECT_EQ(confidences.size(), 1u);
  ASSERT_EQ(robots.size(), 1u);
  EXPECT_EQ(robots[0].box.x0, bright_box.box.x0);
  detector.run(img.view(), cam, {carpet_box, bright_box}, {{behind, {0, 1}}}, &classified,
               &confidences);
  EXPECT_EQ(classified.size(), 2u);

  // Freed, but under the held-back candidates' own bar (0.7): RobotNet's robot probability 0.6.
  cv::rectangle(wrap(img), cv::Point(500, 300), cv::Point(570, 430), cv::Scalar(130), cv::FILLED);
  const RobotProposal unsure = proposal(pixelBox(505, 305, 565, 425));
  robots = detector.run(img.view(), cam, {carpet_box}, {{unsure, {0}}}, &classified, &confidences);
  ASSERT_EQ(confidences.size(), 2u);
  EXPECT_GT(confidences[1], 0.5f);
  EXPECT_LT(confidences[1], 0.7f);
  EXPECT_TRUE(robots.empty());

  EXPECT_THROW(
      detector.run(img.view(), cam, {carpet_box}, {{behind, {1}}}, &classified, &confidences),
      Error);
}

TEST(RobotDetector, APieceOfAWideGroupNeedsItsOwnBar) {
  // RobotNet's robot probability between min_confidence and min_wide_group_confidence: a percept
  // as a robot's own proposal, none as a piece of a wide row of feet points; a sure one is both.
  GrayImage img = carpet(11);
  cv::rectangle(wrap(img), cv::Point(100, 300), cv::Point(170, 430), cv::Scalar(130), cv::FILLED);
  cv::rectangle(wrap(img), cv::Point(400, 100), cv::Point(460, 220), cv::Scalar(230), cv::FILLED);
  const CameraModel cam = testCamera();
  RobotProposal unsure = proposal(pixelBox(105, 305, 165, 425));
  RobotProposal sure = proposal(pixelBox(395, 95, 465, 225));
  const RobotDetector detector = brightnessDetector();
  std::vector<RobotProposal> classified;
  std::vector<float> confidences;
  auto robots = detector.run(img.view(), cam, {unsure, sure}, {}, &classified, &confidences);
  ASSERT_EQ(confidences.size(), 2u);
  ASSERT_GT(confidences[0], 0.5f);
  ASSERT_LT(confidences[0], 0.9f);
  ASSERT_GT(confidences[1], 0.9f);
  EXPECT_EQ(robots.size(), 2u);
  unsure.wide_group = sure.wide_group = true;
  robots = detector.run(img.view(), cam, {unsure, sure}, {}, &classified, &confidences);
  ASSERT_EQ(robots.size(), 1u);
  EXPECT_EQ(robots[0].box.x0, sure.box.x0);
}

TEST(RobotDetector, APieceOfAWideGroupMovesSidewaysToWhereRobotNetScoresItBest) {
  // A piece half on a robot, under the pieces' bar (the stand-in net scores brightness), is looked
  // at 1 and 2 steps of 0.125 of its width to either side, and the best look stays: two steps
  // left, the most robot.
  GrayImage img = carpet(11);
  cv::rectangle(wrap(img), cv::Point(400, 100), cv::Point(460, 220), cv::Scalar(230), cv::FILLED);
  const CameraModel cam = testCamera();
  RobotProposal piece = proposal(pixelBox(430, 95, 490, 225));  // 60 px wide: steps of 7.5 px
  piece.wide_group = true;
  RobotDetectorParams params;
  params.feet_max_steps = 0;
  params.shin_gap_height_fraction = 0;
  std::vector<RobotProposal> classified;
  std::vector<float> confidences;
  brightnessDetector(params).run(img.view(), cam, {piece}, {}, &classified, &confidences);
  ASSERT_EQ(classified.size(), 1u);
  EXPECT_DOUBLE_EQ(classified[0].box.x0, 415.0);
  EXPECT_DOUBLE_EQ(classified[0].box.x1, 475.0);
  EXPECT_DOUBLE_EQ(classified[0].feet_px.x(), piece.feet_px.x() - 15.0);
  const float moved_score = confidences[0];

  // Where it was, RobotNet scored it lower; a robot's own box, or with the shift off, stays.
  params.wide_group_shift_width_fraction = 0;
  brightnessDetector(params).run(img.view(), cam, {piece}, {}, &classified, &confidences);
  EXPECT_DOUBLE_EQ(classified[0].box.x0, 430.0);
  EXPECT_LT(confidences[0], moved_score);
  RobotProposal own = piece;
  own.wide_group = false;
  brightnessDetector().run(img.view(), cam, {own}, {}, &classified, &confidences);
  EXPECT_DOUBLE_EQ(classified[0].box.x0, 430.0);

  // A piece RobotNet already takes (min_wide_group_confidence) is not looked at again.
  RobotProposal sure = proposal(pixelBox(415, 95, 475, 225));  // three quarters on the robot
  sure.wide_group = true;
  brightnessDetector().run(img.view(), cam, {sure}, {}, &classified, &confidences);
  ASSERT_GE(confidences[0], RobotDetectorParams().min_wide_group_confidence);
  EXPECT_DOUBLE_EQ(classified[0].box.x0, 415.0);
  RobotDetectorParams always;
  always.min_wide_group_confidence = 1;  // every piece under the bar: it moves onto the robot
  brightnessDetector(always).run(img.view(), cam, {sure}, {}, &classified, &confidences);
  EXPECT_DOUBLE_EQ(classified[0].box.x0, 400.0);
}

TEST(RobotDetector, TheRobotsGroundPointLiesBeyondItsFeetAlongTheLineOfSight) {
  // The feet point is the nearest edge of the feet; the robot stands feet_to_centre_m beyond it,
  // on the same bearing from the camera.
  GrayImage img = carpet(11);
  cv::rectangle(wrap(img), cv::Point(400, 100), cv::Point(460, 220), cv::Scalar(230), cv::FILLED);
  const CameraModel cam = testCamera();
  const RobotProposal sure = proposal(pixelBox(395, 95, 465, 225));
  RobotDetectorParams params;
  params.feet_max_steps = 0;
  params.shin_gap_height_fraction = 0;
  const auto feet_ground = cam.pixelToGround(sure.feet_px);
  ASSERT_TRUE(feet_ground.has_value());
  const Eigen::Vector2d from_camera = *feet_ground - cam.position().head<2>();
  for (const double beyond_m : {0.0, 0.07, 0.2}) {
    params.feet_to_centre_m = beyond_m;
    const auto robots = brightnessDetector(params).run(img.view(), cam, {sure});
    ASSERT_EQ(robots.size(), 1u);
    ASSERT_TRUE(robots[0].position_in_robot.has_value());
    const Eigen::Vector2d got = *robots[0].position_in_robot - cam.position().head<2>();
    EXPECT_NEAR(got.norm(), from_camera.norm() + beyond_m, 1e-9) << beyond_m;
    EXPECT_NEAR(std::atan2(got.y(), got.x()), std::atan2(from_camera.y(), from_camera.x()), 1e-9);
  }
  EXPECT_FALSE(robotGroundPoint(cam, {320, 0}, 0.07).has_value());  // above the horizon
}

TEST(RobotDetector, ARobotBehindAnAcceptedOneIsKeptOnlyWhenSureAndHoldingNoOtherBox) {
  GrayImage img = carpet(11);
  cv::rectangle(wrap(img), cv::Point(300, 60), cv::Point(620, 300), cv::Scalar(200), cv::FILLED);
  cv::rectangle(wrap(img), cv::Point(100, 320), cv::Point(200, 440), cv::Scalar(142), cv::FILLED);
  const CameraModel cam = testCamera();
  const RobotProposal near = proposal(pixelBox(400, 100, 460, 200));    // a robot (probability ~1)
  const RobotProposal beside = proposal(pixelBox(480, 120, 540, 220));  // ~1, overlaps nothing
  const RobotProposal around = proposal(pixelBox(320, 70, 600, 290));   // ~1, the near box inside it
  const RobotProposal unsure = proposal(pixelBox(100, 320, 200, 440));  // ~0.9
  const std::vector<HeldBackRobotProposal> held = {{around, {0}}, {beside, {0}}, {unsure, {0}}};
  RobotDetectorParams params;  // min_behind_robot_confidence 0.97, as shipped
  std::vector<RobotProposal> classified;
  std::vector<float> confidences;
  const auto robots =
      brightnessDetector(params).run(img.view(), cam, {near}, held, &classified, &confidences);
  ASSERT_EQ(classified.size(), 4u);
  ASSERT_EQ(confidences.size(), 4u);
  EXPECT_GT(confidences[1], 0.97f);  // around: sure, yet the near percept lies inside its box
  EXPECT_GT(confidences[2], 0.97f);
  EXPECT_GT(confidences[3], 0.7f);  // over the held-back bar, under the bar behind a robot
  EXPECT_LT(confidences[3], 0.97f);
  ASSERT_EQ(robots.size(), 2u);
  std::vector<double> x0s = {robots[0].box.x0, robots[1].box.x0};
  std::sort(x0s.begin(), x0s.end());
  EXPECT_EQ(x0s, (std::vector<double>{near.box.x0, beside.box.x0}));

  // Switched off: only the proposals are classified.
  params.min_behind_robot_confidence = 1;
  const auto off =
      brightnessDetector(params).run(img.view(), cam, {near}, held, &classified, &confidences);
  EXPECT_EQ(classified.size(), 1u);
  ASSERT_EQ(off.size(), 1u);
  EXPECT_EQ(off[0].box.x0, near.box.x0);
}

// A stand-in for RobotFeetNet reading the patch's lower rows (unit normalisation): "feet
// lower" when its bottom row (B, row 23) is bright, "feet higher" when the two rows above it (C,
// rows 21-22) are dark, "right" when C is bright and B dark: logits 20 C - 20 B - 5, 20 B - 10,
// 10 - 20 C. With `always_lower`, "feet lower" whatever the patch.
// A net of one 24×24 convolution of `filters` filters over the whole patch (unit normalisation),
// then softmax: filters biases, then filters × 576 weights (row-major), all zero.
cnn::Net wholePatchNet(int filters, const std::string& name) {
  cnn::Net n = cnn::parseDarknetCfg(
      "# colorfree normalization=unit\n[net]\nwidth=24\nheight=24\nchannels=1\n\n"
      "[convolutional]\nfilters=" + std::to_string(filters) +
          "\nsize=24\nstride=1\nactivation=linear\n\n[avgpool]\n\n[softmax]\n",
      name);
  EXPECT_EQ(n.params().size(), static_cast<std::size_t>(filters) * (1 + 576));
  std::fill(n.params().begin(), n.params().end(), 0.0f);
  return n;
}

cnn::Classifier feetStandIn(bool always_lower = false) {
  cnn::Net n = wholePatchNet(3, "feet net");
  std::vector<float>& w = n.params();
  if (always_lower) {
    w[1] = 10;
    return cnn::Classifier(std::move(n));
  }
  w[0] = -5;
  w[1] = -10;
  w[2] = 10;
  const auto weight = [&](int filter, int row, int col) -> float& {
    return w[3 + filter * 576 + row * 24 + col];
  };
  for (int col = 0; col < 24; ++col) {
    for (int row : {21, 22}) {
      weight(0, row, col) = 20.0f / 48;
      weight(2, row, col) = -20.0f / 48;
    }
    weight(0, 23, col) = -20.0f / 24;
    weight(1, 23, col) = 20.0f / 24;
  }
  return cnn::Classifier(std::move(n));
}

// A proposer-shaped box (robot_proposer.yaml's geometry) about a feet point.
RobotProposal proposerShapedBox(const CameraModel& cam, const Eigen::Vector2d& feet) {
  const RobotProposerParams pp = RobotProposerParams::loadDefault();
  const FieldDimensions dims = FieldDimensions::loadDefault();
  const double h = *cam.robotHeightPx(feet, dims.robot_height_m);
  const double w = pp.box_width_factor * h * dims.robot_width_m / dims.robot_height_m;
  RobotProposal p;
  p.feet_px = feet;
  p.box = pixelBox(feet.x() - w / 2,
                   feet.y() + pp.box_below_feet_fraction * h - pp.box_height_factor * h,
                   feet.x() + w / 2, feet.y() + pp.box_below_feet_fraction * h);
  return p;
}

TEST(RobotDetector, FeetMovedGoesStepsOfTheHeightAndScalesTheBoxAboutTheFeet) {
  const CameraModel cam = testCamera();
  const FieldDimensions dims = FieldDimensions::loadDefault();
  const RobotProposal box = proposerShapedBox(cam, {300, 300});
  const double h = *cam.robotHeightPx(box.feet_px, dims.robot_height_m);
  const auto down = feetMoved(box, cam, 0.1, 1, dims);
  ASSERT_TRUE(down);
  EXPECT_NEAR(down->feet_px.y(), 300 + 0.1 * h, 1e-9);
  EXPECT_EQ(down->feet_px.x(), 300);
  // Nearer, so taller: the box grows by the expected heights' ratio, the feet where they were in
  // it.
  const double ratio = *cam.robotHeightPx(down->feet_px, dims.robot_height_m) / h;
  EXPECT_GT(ratio, 1);
  EXPECT_NEAR(down->box.height(), box.box.height() * ratio, 1e-9);
  EXPECT_NEAR(down->box.width(), box.box.width() * ratio, 1e-9);
  EXPECT_NEAR(down->box.y1 - down->feet_px.y(), (box.box.y1 - box.feet_px.y()) * ratio, 1e-9);
  const auto up = feetMoved(box, cam, 0.1, -1, dims);
  ASSERT_TRUE(up);
  EXPECT_NEAR(up->feet_px.y(), 300 - 0.1 * h, 1e-9);
  EXPECT_LT(up->box.height(), box.box.height());
  // Above the horizon no robot stands.
  EXPECT_FALSE(feetMoved(proposerShapedBox(cam, {300, 300}), cam, 5, -1, dims));
}

// A bright robot h pixels tall and h / 2 wide standing on the carpet with its feet at `feet`.
GrayImage brightRobot(const Eigen::Vector2d& feet, double h) {
  GrayImage img = carpet(21);
  cv::rectangle(wrap(img), cv::Point(int(feet.x() - 0.25 * h), int(feet.y() - h)),
                cv::Point(int(feet.x() + 0.25 * h), int(feet.y()) - 1), cv::Scalar(230),
                cv::FILLED);
  return img;
}

TEST(RobotDetector, FeetNetMovesAnAcceptedBoxToTheRobotsFeet) {
  // A bright robot on the carpet, its feet at row 330, as tall as the camera expects there.
  const CameraModel cam = testCamera();
  const FieldDimensions dims = FieldDimensions::loadDefault();
  const Eigen::Vector2d feet(320, 330);
  const double h = *cam.robotHeightPx(feet, dims.robot_height_m);
  const GrayImage img = brightRobot(feet, h);
  RobotDetectorParams params;  // 0.05 of the height a step, up to 6 steps, from 0.6
  params.feet_step_height_fraction = 0.05;
  params.feet_max_steps = 6;
  params.shin_gap_height_fraction = 0;  // the feet net alone
  cnn::Net brightness = cnn::parseDarknetCfg(
      "# colorfree normalization=unit\n[net]\nwidth=24\nheight=24\nchannels=1\n\n"
      "[convolutional]\nfilters=2\nsize=1\nstride=1\nactivation=linear\n\n[avgpool]\n\n[softmax]\n",
      "brightness net");
  brightness.params() = {0.0f, -20.0f, 0.0f, 40.0f};
  const RobotDetector detector(params, cnn::Classifier(brightness), dims, feetStandIn());
  for (const double start : {-0.2, -0.1, 0.0, 0.1, 0.2}) {  // fractions of h; negative: too high
    SCOPED_TRACE(start);
    const RobotProposal p = proposerShapedBox(cam, feet + Eigen::Vector2d(0, start * h));
    const auto robots = detector.run(img.view(), cam, {p});
    ASSERT_EQ(robots.size(), 1u);
    EXPECT_NEAR(robots[0].feet_px.y(), 330, 0.06 * h);
    EXPECT_NEAR(robots[0].feet_px.x(), 320, 1e-9);
    // Without the net the box stays where the proposer put it.
    const auto unmoved =
        RobotDetector(params, cnn::Classifier(brightness), dims).run(img.view(), cam, {p});
    ASSERT_EQ(unmoved.size(), 1u);
    EXPECT_EQ(unmoved[0].feet_px.y(), p.feet_px.y());
  }
  // At most feet_max_steps steps, and none with 0.
  const RobotProposal high = proposerShapedBox(cam, feet + Eigen::Vector2d(0, -0.2 * h));
  params.feet_max_steps = 2;
  auto robots = RobotDetector(params, cnn::Classifier(brightness), dims, feetStandIn(true))
                    .run(img.view(), cam, {high});
  ASSERT_EQ(robots.size(), 1u);
  const auto once = feetMoved(high, cam, 0.05, 1, dims);
  const auto twice = feetMoved(*once, cam, 0.05, 1, dims);
  EXPECT_NEAR(robots[0].feet_px.y(), twice->feet_px.y(), 1e-9);
  EXPECT_NEAR(robots[0].box.y0, twice->box.y0, 1e-9);
  params.feet_max_steps = 0;
  robots = RobotDetector(params, cnn::Classifier(brightness), dims, feetStandIn(true))
               .run(img.view(), cam, {high});
  ASSERT_EQ(robots.size(), 1u);
  EXPECT_EQ(robots[0].feet_px.y(), high.feet_px.y());
  // A feet net of the wrong shape is refused.
  EXPECT_THROW(
      RobotDetector(params, cnn::Classifier(brightness), dims, cnn::Classifier(brightness)), Error);
}

// A robot proposed at its knees (its shaded legs at the carpet's gray): RobotNet rejects the box
// too high; RobotFeetNet moves it down to the feet, where RobotNet accepts it from the search's
// bar. The stand-in RobotNet reads the patch's lower rows as feetStandIn does: robot logit
// 20 C - 20 B - 1 (C rows 21-22, B row 23): a box whose bottom rows are all robot (too high) scores
// 0.27, one whose feet end above its bottom row (at the feet) about 1.
TEST(RobotDetector, FeetSearchMovesARejectedBoxToTheRobotsFeet) {
  const CameraModel cam = testCamera();
  const FieldDimensions dims = FieldDimensions::loadDefault();
  const Eigen::Vector2d feet(320, 330);
  const double h = *cam.robotHeightPx(feet, dims.robot_height_m);
  const GrayImage img = brightRobot(feet, h);
  cnn::Net lower_rows = wholePatchNet(2, "lower rows net");
  std::vector<float>& w = lower_rows.params();
  w[1] = -1;
  for (int col = 0; col < 24; ++col) {
    for (int row : {21, 22}) w[2 + 576 + row * 24 + col] = 20.0f / 48;
    w[2 + 576 + 23 * 24 + col] = -20.0f / 24;
  }
  const RobotProposal high = proposerShapedBox(cam, feet + Eigen::Vector2d(0, -0.2 * h));
  RobotDetectorParams params;
  params.shin_gap_height_fraction = 0;  // the feet net alone
  params.feet_search_min_confidence = 0.1;
  params.feet_search_accept_confidence = 0.97;
  const auto robots = RobotDetector(params, cnn::Classifier(lower_rows), dims, feetStandIn())
                          .run(img.view(), cam, {high});
  ASSERT_EQ(robots.size(), 1u);
  EXPECT_NEAR(robots[0].feet_px.y(), 330, 0.06 * h);
  EXPECT_GE(robots[0].confidence, 0.97f);
  // A box accepted at its first look, at the feet but off to the side (less sure than the searched
  // box, centred), takes the robot: the searched box yields.
  const RobotProposal aside = proposerShapedBox(cam, feet + Eigen::Vector2d(0.15 * h, 0));
  std::vector<float> confidences;
  const auto both = RobotDetector(params, cnn::Classifier(lower_rows), dims, feetStandIn())
                        .run(img.view(), cam, {high, aside}, &confidences);
  ASSERT_EQ(confidences.size(), 2u);
  EXPECT_GT(confidences[0], confidences[1]);
  EXPECT_GE(confidences[1], params.min_confidence);
  ASSERT_EQ(both.size(), 1u);
  EXPECT_EQ(both[0].feet_px.x(), aside.feet_px.x());
  // Off, over the first look's score (0.27), or the moved look under the bar: nothing.
  for (const auto& [floor, bar] : {std::pair{0.5, 0.97}, {0.3, 0.97}, {0.1, 1.0}}) {
    params.feet_search_min_confidence = floor;
    params.feet_search_accept_confidence = bar;
    SCOPED_TRACE(std::to_string(floor) + " " + std::to_string(bar));
    EXPECT_TRUE(RobotDetector(params, cnn::Classifier(lower_rows), dims, feetStandIn())
                    .run(img.view(), cam, {high})
                    .empty());
  }
}

TEST(RobotDetector, ARobotTrackedThereLiftsAnUnsureBoxOverTheBar) {
  // A stand-in RobotNet that scores every patch 0.4, under the bar of 0.5: with a robot tracked at
  // the box's ground point and odds x 2 it is 0.57 and detected; tracked a metre away, or with the
  // prior off, not. RobotNet's own score stays in `confidences`.
  const CameraModel cam = testCamera();
  const FieldDimensions dims = FieldDimensions::loadDefault();
  const RobotProposal box = proposerShapedBox(cam, {320, 330});
  cnn::Net constant = wholePatchNet(2, "constant net");
  constant.params()[1] = static_cast<float>(std::log(0.4 / 0.6));
  RobotDetectorParams params;
  params.shin_gap_height_fraction = 0;
  params.track_prior_odds = 2;
  const RobotDetector detector(params, cnn::Classifier(constant), dims);
  const GrayImage img = carpet(13);
  const auto ground = robotGroundPoint(cam, box.feet_px, params.feet_to_centre_m);
  ASSERT_TRUE(ground.has_value());
  const auto runWith = [&](const RobotDetector& d, const std::vector<Eigen::Vector2d>* tracked,
                           std::vector<float>& confidences) {
    return d.run(img.view(), cam, {box}, {}, nullptr, &confidences, tracked);
  };
  std::vector<float> confidences;
  EXPECT_TRUE(runWith(detector, nullptr, confidences).empty());
  const std::vector<Eigen::Vector2d> here{*ground + Eigen::Vector2d(0.1, -0.1)};
  const auto found = runWith(detector, &here, confidences);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_NEAR(found[0].confidence, 0.8 / 1.4, 1e-4);
  ASSERT_EQ(confidences.size(), 1u);
  EXPECT_NEAR(confidences[0], 0.4, 1e-4);
  const std::vector<Eigen::Vector2d> away{*ground + Eigen::Vector2d(1.0, 0)};
  EXPECT_TRUE(runWith(detector, &away, confidences).empty());
  params.track_prior_odds = 1;
  EXPECT_TRUE(runWith(RobotDetector(params, cnn::Classifier(constant), dims), &here, confidences).empty());
}

TEST(RobotDetector, AnUnsureBoxIsScoredByTheMeanOfItsLookAndItsMirroredLook) {
  // A box bright on its left half only, and a stand-in net that tells left from right: its robot
  // logit is beta + a x (the left half's mean - the right half's) / 2 of the patch (unit range).
  GrayImage img = carpet(13);
  cv::rectangle(wrap(img), cv::Point(300, 100), cv::Point(329, 219), cv::Scalar(230), cv::FILLED);
  const CameraModel cam = testCamera();
  const RobotProposal box = proposal(pixelBox(300, 100, 360, 220));
  std::vector<float> patch(24 * 24);
  cnn::extractPatch(img.view(), robotPatchBox(box), 24, 24, cnn::PatchNormalization::kUnitRange,
                    patch.data());
  double left = 0, right = 0;
  for (int y = 0; y < 24; ++y) {
    for (int x = 0; x < 24; ++x) (x < 12 ? left : right) += patch[y * 24 + x] / 288.0;
  }
  ASSERT_GT(left - right, 0.3);
  // The look scores 0.65, the mirrored look 0.15: their mean 0.4 is under the bar of 0.5.
  const auto logit = [](double p) { return std::log(p / (1 - p)); };
  const double beta = 0.5 * (logit(0.65) + logit(0.15));
  const double a = (logit(0.65) - beta) / (0.5 * (left - right));
  cnn::Net sided = cnn::parseDarknetCfg(
      "# colorfree normalization=unit\n[net]\nwidth=24\nheight=24\nchannels=1\n\n"
      "[connected]\noutput=2\nactivation=linear\n\n[softmax]\n",
      "sided net");
  std::vector<float>& w = sided.params();  // biases (no robot, robot), then weights per class
  ASSERT_EQ(w.size(), 2u + 2u * 576u);
  w[1] = static_cast<float>(beta);
  for (int y = 0; y < 24; ++y) {
    for (int x = 0; x < 24; ++x)
      w[2 + 576 + y * 24 + x] = static_cast<float>((x < 12 ? a : -a) / 576);
  }
  const auto runOn = [&](const RobotProposal& b, double lo, double hi,
                         std::vector<float>& confidences) {
    RobotDetectorParams params;
    params.mirror_min_confidence = lo;
    params.mirror_max_confidence = hi;
    params.shin_gap_height_fraction = 0;
    return RobotDetector(params, cnn::Classifier(sided))
        .run(img.view(), cam, {b}, {}, nullptr, &confidences);
  };
  const auto run = [&](double lo, double hi, std::vector<float>& confidences) {
    return runOn(box, lo, hi, confidences);
  };
  std::vector<float> confidences;
  // Never mirrored (equal bounds), or 0.65 outside the band: the look alone, a robot.
  for (const auto& [lo, hi] : {std::pair{0.0, 0.0}, {0.3, 0.6}, {0.7, 0.8}}) {
    SCOPED_TRACE(lo);
    EXPECT_EQ(run(lo, hi, confidences).size(), 1u);
    ASSERT_EQ(confidences.size(), 1u);
    EXPECT_NEAR(confidences[0], 0.65, 1e-4);
  }
  // Within the band: the mean of both looks, no robot.
  EXPECT_TRUE(run(0.3, 0.8, confidences).empty());
  ASSERT_EQ(confidences.size(), 1u);
  EXPECT_NEAR(confidences[0], 0.4, 1e-4);
  // Boxes the image's border cuts, every look mirrored (band 0 to 1): the look alone where the
  // left, right or bottom border cuts it, the mean of both where the top does.
  cv::rectangle(wrap(img), cv::Point(15, 100), cv::Point(29, 219), cv::Scalar(230), cv::FILLED);
  cv::rectangle(wrap(img), cv::Point(0, 380), cv::Point(29, 479), cv::Scalar(230), cv::FILLED);
  cv::rectangle(wrap(img), cv::Point(610, 100), cv::Point(624, 219), cv::Scalar(230), cv::FILLED);
  cv::rectangle(wrap(img), cv::Point(300, 0), cv::Point(329, 99), cv::Scalar(230), cv::FILLED);
  const std::vector<std::pair<PixelBox, bool>> cut = {{pixelBox(-30, 100, 30, 220), false},
                                                      {pixelBox(610, 100, 670, 220), false},
                                                      {pixelBox(0, 380, 60, 500), false},
                                                      {pixelBox(300, -20, 360, 100), true}};
  for (const auto& [b, mirrored] : cut) {
    SCOPED_TRACE(b.x0);
    std::vector<float> own, both;
    runOn(proposal(b), 0, 0, own);
    runOn(proposal(b), 0, 1, both);
    ASSERT_EQ(own.size(), 1u);
    ASSERT_EQ(both.size(), 1u);
    if (mirrored) {
      EXPECT_GT(std::abs(both[0] - own[0]), 0.05);
    } else {
      EXPECT_EQ(both[0], own[0]);
    }
  }
}

TEST(RobotDetector, ANearBoxIsScoredByTheMeanOfItsBilinearLookAndItsAreaLook) {
  // One-pixel stripes, 30 and 230 gray, under a box ten patch widths wide: read bilinearly, its
  // 24 samples across land on pixel centres of one parity, all dark or all bright as the box moves
  // by a pixel; read by area, each sample is the stripes' mean, 130 gray, either way.
  GrayImage img = carpet(17);
  for (int y = 60; y < 420; ++y)
    for (int x = 60; x < 640; ++x) img.at(x, y) = x % 2 ? 230 : 30;
  const CameraModel cam = testCamera();
  const auto score = [&](double area_min_patch_widths, double x0, double width) {
    RobotDetectorParams params;
    params.area_min_patch_widths = area_min_patch_widths;
    params.mirror_min_confidence = params.mirror_max_confidence = 0;
    params.shin_gap_height_fraction = 0;
    std::vector<float> confidences;
    brightnessDetector(params).run(img.view(), cam, {proposal(pixelBox(x0, 100, x0 + width, 340))},
                                   {}, nullptr, &confidences);
    EXPECT_EQ(confidences.size(), 1u);
    return confidences.empty() ? -1.0 : double(confidences[0]);
  };
  // Bilinear alone (never area, or a box under the bar): a robot or none by one pixel's move.
  for (const double bar : {0.0, 11.0}) {
    SCOPED_TRACE(bar);
    EXPECT_GT(score(bar, 100.5, 240), 0.99);
    EXPECT_LT(score(bar, 101.5, 240), 0.01);
  }
  // From 10 patch widths (and from 4): the mean of that look and the area look's.
  const double area_score = 1 / (1 + std::exp(-(40 * 130.0 / 255 - 20)));
  for (const double bar : {10.0, 4.0}) {
    for (const double x0 : {100.5, 101.5}) {
      SCOPED_TRACE(bar + x0);
      EXPECT_NEAR(score(bar, x0, 240), 0.5 * (score(0, x0, 240) + area_score), 0.01);
    }
  }
  // A box under the bar (2 patch widths, bar 4) has its bilinear look alone, and so has one the
  // image's right border cuts.
  EXPECT_EQ(score(4, 100.5, 48), score(0, 100.5, 48));
  EXPECT_EQ(score(4, 460.5, 240), score(0, 460.5, 240));
  EXPECT_GT(std::abs(score(4, 460.5, 240) - score(4, 461.5, 240)), 0.9);
}

TEST(RobotDetector, ABoxStoodOnABallIsLookedAtAboveItOrDropped) {
  // Two balls on dark carpet. Above the left one stands a robot (a bright box, which the stand-in
  // net accepts) whose box the proposer drew from the ball's lower edge; above the right one there
  // is only carpet (the box held the ball and what stands far behind it).
  const CameraModel cam = testCamera();
  const FieldDimensions dims = FieldDimensions::loadDefault();
  BallPercept left_ball, right_ball;
  left_ball.centre_px = {200, 330};
  right_ball.centre_px = {470, 330};
  left_ball.radius_px = right_ball.radius_px = 20;
  const RobotProposal on_left = proposerShapedBox(cam, {200, 348});
  const RobotProposal on_right = proposerShapedBox(cam, {470, 348});
  const auto behind_left = feetMovedTo(on_left, cam, {200, 310}, dims);
  ASSERT_TRUE(behind_left);
  GrayImage img = carpet(5);
  const PixelBox& b = behind_left->box;
  cv::rectangle(wrap(img), cv::Point(int(b.x0), int(b.y0)), cv::Point(int(b.x1), int(b.y1)),
                cv::Scalar(230), cv::FILLED);
  const auto percept = [](const RobotProposal& p, double confidence) {
    RobotPercept r;
    r.box = p.box;
    r.feet_px = p.feet_px;
    r.confidence = confidence;
    return r;
  };
  const RobotPercept far_from_balls = percept(proposerShapedBox(cam, {330, 250}), 0.7);
  const RobotPercept above_right_ball = percept(proposerShapedBox(cam, {470, 305}), 0.7);
  const std::vector<RobotPercept> robots = {percept(on_left, 0.6), percept(on_right, 0.7),
                                            far_from_balls, above_right_ball};
  const RobotDetector detector = brightnessDetector();
  const auto out = detector.liftOffBalls(img.view(), cam, robots, {left_ball, right_ball});
  // The left box stands at the ball's top now, RobotNet's score of that look its confidence; the
  // right one is gone; a box far from the balls and one whose feet lie above the right ball's top
  // (a robot standing behind it) stay as they were.
  ASSERT_EQ(out.size(), 3u);
  EXPECT_NEAR(out[0].feet_px.y(), 310, 1e-9);
  EXPECT_NEAR(out[0].box.y1, b.y1, 1e-9);
  EXPECT_GT(out[0].confidence, 0.99);
  ASSERT_TRUE(out[0].position_in_robot);
  EXPECT_EQ(out[1].feet_px, far_from_balls.feet_px);
  EXPECT_EQ(out[1].confidence, 0.7);
  EXPECT_EQ(out[2].feet_px, above_right_ball.feet_px);
  // The second look needs the held-back candidates' bar.
  RobotDetectorParams strict;
  strict.min_held_back_confidence = 1;
  EXPECT_EQ(brightnessDetector(strict)
                .liftOffBalls(img.view(), cam, robots, {left_ball, right_ball})
                .size(),
            2u);
  // Without the balls, or with the re-look off, or for a box RobotNet is surer of than the bound:
  // nothing moves.
  EXPECT_EQ(detector.liftOffBalls(img.view(), cam, robots, {}).size(), 4u);
  RobotDetectorParams off;
  off.ball_feet_radii = 0;
  EXPECT_EQ(
      brightnessDetector(off).liftOffBalls(img.view(), cam, robots, {left_ball, right_ball}).size(),
      4u);
  RobotDetectorParams sure;
  sure.ball_feet_max_confidence = 0.65;
  const auto kept =
      brightnessDetector(sure).liftOffBalls(img.view(), cam, robots, {left_ball, right_ball});
  ASSERT_EQ(kept.size(), 4u);  // the left box (0.6) looked at again; the right one (0.7) stays
  EXPECT_NEAR(kept[0].feet_px.y(), 310, 1e-9);
  EXPECT_EQ(kept[1].feet_px, on_right.feet_px);
}

TEST(RobotDetector, RobotBehindNetVetoesBoxesInsideANearerRobots) {
  // A near robot's box, a held-back candidate behind it and a proposal whose feet point lies in
  // its box above its feet, all on a bright patch RobotNet (brightness) is sure of; RobotBehindNet
  // looks at the two inside the near robot's box: one taking dark patches for robots rejects them
  // (under behind_net_veto_confidence: no robots), one like RobotNet keeps them with RobotNet's
  // scores. The near box, inside none, is RobotNet's alone; veto 0: RobotBehindNet is not asked.
  GrayImage img = carpet(11);
  cv::rectangle(wrap(img), cv::Point(300, 60), cv::Point(620, 300), cv::Scalar(200), cv::FILLED);
  const CameraModel cam = testCamera();
  const RobotProposal near = proposal(pixelBox(400, 100, 460, 200));
  const RobotProposal beside = proposal(pixelBox(480, 120, 540, 220));  // held back behind near
  const RobotProposal inside = proposal(pixelBox(420, 60, 450, 150));   // feet in near's box
  const std::vector<HeldBackRobotProposal> held = {{beside, {0}}};
  RobotDetectorParams params;  // as shipped: behind a robot from 0.97, the veto under 0.5
  const auto detect = [&](std::optional<cnn::Classifier> behind_net,
                          std::vector<float>& confidences) {
    std::vector<RobotProposal> classified;
    auto robots = RobotDetector(params, meanNet(-20, 40), {}, std::nullopt, std::move(behind_net))
                      .run(img.view(), cam, {near, inside}, held, &classified, &confidences);
    EXPECT_EQ(classified.size(), 3u);
    std::vector<double> x0s;
    for (const RobotPercept& r : robots) x0s.push_back(r.box.x0);
    std::sort(x0s.begin(), x0s.end());
    return x0s;
  };
  std::vector<float> without, dark, alike;
  EXPECT_EQ(detect(std::nullopt, without), (std::vector<double>{400, 420, 480}));
  EXPECT_EQ(detect(meanNet(20, -40), dark), (std::vector<double>{400}));
  EXPECT_EQ(detect(meanNet(-20, 40), alike), (std::vector<double>{400, 420, 480}));
  // The confidences are RobotNet's whatever RobotBehindNet says.
  EXPECT_GT(without[1], 0.97f);
  EXPECT_GT(without[2], 0.97f);
  EXPECT_EQ(dark, without);
  EXPECT_EQ(alike, without);
  params.behind_net_veto_confidence = 0;
  std::vector<float> off;
  EXPECT_EQ(detect(meanNet(20, -40), off), (std::vector<double>{400, 420, 480}));
  EXPECT_EQ(off, without);
  params.behind_net_veto_confidence = 0.5;
  // A net of another shape is refused.
  EXPECT_THROW(RobotDetector(params, meanNet(-20, 40), {}, std::nullopt, feetStandIn()), Error);
}

TEST(RobotDetector, AKneeBoxInsideARobotHeldBackBehindAnotherDoesNotShutItOut) {
  // A robot held back behind a nearer one (feet in its lower part, overlapping it little), and a
  // free proposal at that robot's own knee, inside its box: RobotNet accepts all three. The knee
  // box is the held-back robot's part, not the nearer robot, so the robot stays and the knee box
  // goes as its part (README robot30; before, the knee box shut the robot out and stayed).
  GrayImage img = carpet(11);
  cv::rectangle(wrap(img), cv::Point(100, 100), cv::Point(299, 419), cv::Scalar(200), cv::FILLED);
  cv::rectangle(wrap(img), cv::Point(250, 230), cv::Point(329, 339), cv::Scalar(230), cv::FILLED);
  // (The knee's box a little less bright than the robot's: RobotNet a little less sure of it.)
  cv::rectangle(wrap(img), cv::Point(262, 240), cv::Point(317, 309), cv::Scalar(160), cv::FILLED);
  const CameraModel cam = testCamera();
  const RobotProposal front = proposal(pixelBox(100, 100, 300, 420));
  const RobotProposal behind = proposal(pixelBox(250, 230, 330, 340));
  const RobotProposal knee = proposal(pixelBox(262, 240, 318, 310));
  RobotDetectorParams params;
  params.shin_gap_height_fraction = 0;
  ASSERT_TRUE(feetInLowerPart(behind.feet_px, front, params.behind_lower_part_fraction));
  ASSERT_LT(boxIou(behind.box, front.box), params.max_overlap_iou);
  ASSERT_TRUE(feetInLowerPart(knee.feet_px, behind, params.behind_lower_part_fraction));
  ASSERT_GE(boxInsideFraction(knee.box, behind.box), params.max_inside_fraction);
  std::vector<RobotProposal> classified;
  std::vector<float> confidences;
  const auto robots = brightnessDetector(params).run(img.view(), cam, {front, knee},
                                                     {{behind, {0}}}, &classified, &confidences);
  ASSERT_EQ(confidences.size(), 3u);
  for (const float c : confidences) EXPECT_GT(c, params.min_behind_robot_confidence);
  EXPECT_GT(confidences[2], confidences[1]);  // behind, knee
  ASSERT_EQ(robots.size(), 2u);
  std::vector<double> x0s = {robots[0].box.x0, robots[1].box.x0};
  std::sort(x0s.begin(), x0s.end());
  EXPECT_EQ(x0s, (std::vector<double>{front.box.x0, behind.box.x0}));

  // A box inside it whose feet stand above its lower part (the nearer robot's body seen through
  // its patch, as in ARobotBehindAnAcceptedOneIsKeptOnlyWhenSureAndHoldingNoOtherBox) still does.
  const RobotProposal body = proposal(pixelBox(262, 232, 318, 290));
  ASSERT_FALSE(feetInLowerPart(body.feet_px, behind, params.behind_lower_part_fraction));
  ASSERT_GE(boxInsideFraction(body.box, behind.box), params.max_inside_fraction);
  const auto shut = brightnessDetector(params).run(img.view(), cam, {front, body}, {{behind, {0}}},
                                                   &classified, &confidences);
  ASSERT_EQ(shut.size(), 2u);
  x0s = {shut[0].box.x0, shut[1].box.x0};
  std::sort(x0s.begin(), x0s.end());
  EXPECT_EQ(x0s, (std::vector<double>{front.box.x0, body.box.x0}));
}

TEST(RobotDetector, ABoxBehindARobotOverlappingItLikeARobotIsItsKneeOrHand) {
  // The near robot's box reaches past the lit body onto the carpet; the held-back box at its knee
  // lies wholly on the body, and RobotNet is surer of it than of the robot.
  GrayImage img = carpet(11);
  cv::rectangle(wrap(img), cv::Point(300, 60), cv::Point(620, 300), cv::Scalar(200), cv::FILLED);
  const CameraModel cam = testCamera();
  const RobotProposal near = proposal(pixelBox(290, 100, 350, 200));
  const RobotProposal knee = proposal(pixelBox(300, 110, 360, 210));  // IoU 0.6 with the near box
  std::vector<RobotProposal> classified;
  std::vector<float> confidences;
  const auto robots = brightnessDetector().run(img.view(), cam, {near}, {{knee, {0}}}, &classified,
                                               &confidences);
  ASSERT_EQ(confidences.size(), 2u);
  EXPECT_GT(confidences[0], 0.97f);
  EXPECT_GT(confidences[1], confidences[0]);
  ASSERT_EQ(robots.size(), 1u);
  EXPECT_EQ(robots[0].box.x0, near.box.x0);
}

TEST(RobotDetector, AnAcceptedBoxAtANearerRobotsKneesNeedsTheBarBehindARobot) {
  // Two proposals RobotNet accepts: a near robot, and a box whose feet lie in the near box's
  // column 0.27 of its height above its feet (its knee or hand, or a robot behind it), which
  // overlaps it too little to be dropped as an overlap or a part. The proposer kept it as a
  // proposal (it came first). It stays only from min_behind_robot_confidence (README robot19).
  GrayImage img = carpet(11);
  cv::rectangle(wrap(img), cv::Point(200, 100), cv::Point(299, 399), cv::Scalar(200), cv::FILLED);
  cv::rectangle(wrap(img), cv::Point(300, 230), cv::Point(323, 319), cv::Scalar(44), cv::FILLED);
  const CameraModel cam = testCamera();
  const RobotProposal near = proposal(pixelBox(200, 100, 300, 400));
  const RobotProposal knee = proposal(pixelBox(264, 230, 324, 320));
  ASSERT_TRUE(feetInLowerPart(knee.feet_px, near, 0.4));
  ASSERT_LT(boxIou(knee.box, near.box), 0.3);
  RobotDetectorParams params;
  std::vector<RobotProposal> classified;
  std::vector<float> confidences;
  auto robots =
      brightnessDetector(params).run(img.view(), cam, {knee, near}, {}, &classified, &confidences);
  ASSERT_EQ(confidences.size(), 2u);
  EXPECT_GT(confidences[0], params.min_confidence);
  EXPECT_LT(confidences[0], params.min_behind_robot_confidence);
  ASSERT_EQ(robots.size(), 1u);
  EXPECT_EQ(robots[0].box.x0, near.box.x0);
  // Without the test both stay.
  RobotDetectorParams off = params;
  off.behind_lower_part_fraction = 0;
  EXPECT_EQ(brightnessDetector(off).run(img.view(), cam, {knee, near}, {}, nullptr, nullptr).size(),
            2u);
  // RobotNet sure of it: a robot behind the near one, kept.
  cv::rectangle(wrap(img), cv::Point(300, 230), cv::Point(323, 319), cv::Scalar(170), cv::FILLED);
  robots =
      brightnessDetector(params).run(img.view(), cam, {knee, near}, {}, &classified, &confidences);
  ASSERT_EQ(confidences.size(), 2u);
  EXPECT_GT(confidences[0], params.min_behind_robot_confidence);
  EXPECT_EQ(robots.size(), 2u);
}

// A percept as the proposer and RobotNet would give it with its feet at `feet` (the proposer's
// box: 1.25 robot widths, 1.08 heights, 0.04 of a height below the feet).
RobotPercept perceptAt(const CameraModel& cam, const Eigen::Vector2d& feet) {
  const auto [h, w] = robotSizePx(cam, feet);
  RobotPercept r;
  r.feet_px = feet;
  r.box = pixelBox(feet.x() - 0.625 * w, feet.y() + 0.04 * h - 1.08 * h, feet.x() + 0.625 * w,
                   feet.y() + 0.04 * h);
  r.confidence = 0.9f;
  r.position_in_robot = cam.pixelToGround(feet);
  return r;
}

std::optional<RobotPercept> onShins(const GrayImage& img, const CameraModel& cam,
                                    const RobotPercept& r) {
  return feetOnShins(img.view(), cam, r, RobotDetectorParams::loadDefault(),
                     FieldDimensions::loadDefault());
}

TEST(RobotDetector, FeetGoDownToShinsBelowABacklitKnee) {
  // The legs, blurred by the walk, one lit stretch half a robot wide; the knees at the carpet's
  // gray over 7 rows, 0.07 of the height (longer than a run's gap): the proposal's feet stand on
  // the thighs, its box too high. The shins below it move the feet (and the box) down to them.
  const CameraModel cam = testCamera();
  GrayImage img = carpet(21);
  const Eigen::Vector2d feet = drawRobot(img, cam, {3.0, 0.1});
  const auto [h, w] = robotSizePx(cam, feet);
  cv::rectangle(wrap(img), cv::Point(int(feet.x() - 0.42 * w), int(feet.y() - 0.37 * h)),
                cv::Point(int(feet.x() + 0.42 * w), int(feet.y()) - 1), cv::Scalar(60), cv::FILLED);
  cv::rectangle(wrap(img), cv::Point(int(feet.x() - 0.25 * w), int(feet.y() - 0.37 * h)),
                cv::Point(int(feet.x() + 0.25 * w), int(feet.y()) - 1), cv::Scalar(170),
                cv::FILLED);
  const int knee_bottom = int(feet.y() - 0.15 * h), knee_top = knee_bottom - 6;
  ASSERT_GT(knee_bottom + 1 - knee_top, std::max(3.0, 0.04 * h));  // longer than a run's gap
  cv::rectangle(wrap(img), cv::Point(int(feet.x() - 0.5 * w), knee_top),
                cv::Point(int(feet.x() + 0.5 * w), knee_bottom), cv::Scalar(60), cv::FILLED);
  const Eigen::Vector2d on_thighs(feet.x() + 0.2 * w, knee_top);
  const auto lowered = onShins(img, cam, perceptAt(cam, on_thighs));
  ASSERT_TRUE(lowered.has_value());
  EXPECT_NEAR(lowered->feet_px.y(), feet.y(), 2.0);
  EXPECT_NEAR(lowered->feet_px.x(), feet.x(), 0.1 * w);
  const RobotPercept truth = perceptAt(cam, feet);
  EXPECT_NEAR(lowered->box.y1, truth.box.y1, 3.0);
  EXPECT_NEAR(lowered->box.height(), truth.box.height(), 0.05 * h);
  EXPECT_NEAR(lowered->box.width(), truth.box.width(), 0.05 * w);
  ASSERT_TRUE(lowered->position_in_robot.has_value());
  EXPECT_NEAR(lowered->position_in_robot->x(), 3.0, 0.1);

  // Switched off, or with no shins below the knee: the percept stays as it is.
  RobotDetectorParams off = RobotDetectorParams::loadDefault();
  off.shin_gap_height_fraction = 0;
  EXPECT_FALSE(feetOnShins(img.view(), cam, perceptAt(cam, on_thighs), off,
                           FieldDimensions::loadDefault()));
  cv::rectangle(wrap(img), cv::Point(int(feet.x() - 0.5 * w), knee_bottom),
                cv::Point(int(feet.x() + 0.5 * w), int(feet.y()) + 2), cv::Scalar(60),
                cv::FILLED);
  EXPECT_FALSE(onShins(img, cam, perceptAt(cam, on_thighs)));
}

TEST(RobotDetector, ABallOrAFieldLineBelowTheFeetIsNoShin) {
  // A robot standing where its percept says, with the ball or a field line a knee's gap below
  // its feet: the ball's lower edge is round, the line runs on beside the robot.
  const CameraModel cam = testCamera();
  for (int what = 0; what < 2; ++what) {
    GrayImage img = carpet(22 + what);
    const Eigen::Vector2d feet = drawRobot(img, cam, {2.0, 0.0});
    const auto [h, w] = robotSizePx(cam, feet);
    const RobotPercept r = perceptAt(cam, feet);
    EXPECT_FALSE(onShins(img, cam, r)) << "before drawing " << what;
    cv::Mat m = wrap(img);
    if (what == 0) {
      // The nearest ball whose top is 0.04 of the height below the feet.
      double d = 2.0;
      Eigen::Vector2d ball;
      double radius = 0;
      do {
        d -= 0.01;
        ball = *cam.robotToPixel({d, 0.0, 0.05});
        radius = *cam.ballRadiusPx(ball, 0.05);
      } while (ball.y() - radius - feet.y() < 0.04 * h);
      ASSERT_GT(ball.y() - radius - feet.y(), 2);  // a gap between them
      ASSERT_LT(ball.y() - radius - feet.y(), 0.10 * h);
      cv::circle(m, cv::Point(int(ball.x()), int(ball.y())), int(radius), cv::Scalar(220),
                 cv::FILLED);
    } else {
      const int y = int(feet.y() + 0.05 * h);
      cv::rectangle(m, cv::Point(0, y), cv::Point(639, y + int(0.12 * h)), cv::Scalar(220),
                    cv::FILLED);
    }
    EXPECT_FALSE(onShins(img, cam, r)) << (what == 0 ? "ball" : "line");
  }
}

TEST(RobotDetector, AFieldLineInTheCarpetsNoiseIsNoShin) {
  // A thin field line a knee's gap below the feet, and the noisy carpet's lit pixels around it:
  // lit rows every 4 rows (closer than a run's gap) across the robot's width, from just below the
  // feet to 0.3 of its height below them. The stretch is a shin's height and lit beside it on the
  // line's rows only, but lit on under half of its rows: no shin. (At noise sigma 6 such a
  // stretch took an accepted robot's feet 62 px down onto the line, camera_noise case 2.)
  const CameraModel cam = testCamera();
  GrayImage img = carpet(24);
  const Eigen::Vector2d feet = drawRobot(img, cam, {2.0, 0.0});
  const auto [h, w] = robotSizePx(cam, feet);
  const RobotPercept r = perceptAt(cam, feet);
  cv::Mat m = wrap(img);
  const int line_y = int(feet.y() + 0.10 * h);
  cv::rectangle(m, cv::Point(0, line_y), cv::Point(639, line_y + int(0.04 * h)), cv::Scalar(220),
                cv::FILLED);
  for (int y = int(feet.y() + 0.04 * h); y < feet.y() + 0.3 * h; y += 4) {
    cv::line(m, cv::Point(int(feet.x() - 0.5 * w), y), cv::Point(int(feet.x() + 0.5 * w), y),
             cv::Scalar(220));
  }
  EXPECT_FALSE(onShins(img, cam, r));
}

TEST(Cns, SameResponseUnderTwoIlluminationLevels) {
  // A horizontal step edge (dark below, bright above) at two contrasts and brightness levels.
  auto edge = [](int dark, int bright) {
    GrayImage img(64, 64);
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) img.at(x, y) = static_cast<std::uint8_t>(y < 32 ? bright : dark);
    return img;
  };
  const GrayImage dim = edge(20, 60), bright = edge(80, 240);
  const CnsImage a = contrastNormalizedSobel(dim.view(), 0, 0, 64, 64, 2, 1.0);
  const CnsImage b = contrastNormalizedSobel(bright.view(), 0, 0, 64, 64, 2, 1.0);
  for (int y : {31, 32}) {
    EXPECT_NEAR(a.gyAt(30, y), b.gyAt(30, y), 0.02);
    EXPECT_LT(a.gyAt(30, y), -0.5);  // bright above dark: negative
  }
  EXPECT_NEAR(a.gyAt(30, 10), 0.0, 1e-6);
  EXPECT_NEAR(a.gx[32 * 64 + 30], 0.0, 1e-6);
}

// The definition, pixel by pixel in double with clamped reads: Sobel / sqrt(64 · variance + σ²)
// over the (2r+1)² window.
double cnsReference(const GrayImage& img, int x, int y, int r, double sigma, bool vertical) {
  auto px = [&](int i, int j) -> double {
    return img.at(std::clamp(i, 0, img.width() - 1), std::clamp(j, 0, img.height() - 1));
  };
  const double g = vertical ? (px(x - 1, y + 1) + 2 * px(x, y + 1) + px(x + 1, y + 1)) -
                                  (px(x - 1, y - 1) + 2 * px(x, y - 1) + px(x + 1, y - 1))
                            : (px(x + 1, y - 1) + 2 * px(x + 1, y) + px(x + 1, y + 1)) -
                                  (px(x - 1, y - 1) + 2 * px(x - 1, y) + px(x - 1, y + 1));
  double s = 0, s2 = 0;
  for (int j = -r; j <= r; ++j)
    for (int i = -r; i <= r; ++i) {
      s += px(x + i, y + j);
      s2 += px(x + i, y + j) * px(x + i, y + j);
    }
  const double n = (2 * r + 1) * (2 * r + 1);
  const double var = std::max(0.0, s2 / n - (s / n) * (s / n));
  return g / std::sqrt(64 * var + sigma * sigma);
}

TEST(Cns, MatchesTheDefinitionInsideAndAtTheImageBorder) {
  GrayImage img(40, 30);
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int> v(0, 255);
  for (int y = 0; y < 30; ++y)
    for (int x = 0; x < 40; ++x) img.at(x, y) = static_cast<std::uint8_t>(v(rng));
  // Regions inside, touching every border, and cut by the image (clamped to it).
  struct Region {
    int x0, y0, w, h, r;
  };
  for (const Region& g : {Region{5, 4, 20, 15, 2}, Region{0, 0, 40, 30, 2}, Region{-3, 20, 12, 20, 3},
                          Region{30, -2, 15, 8, 1}, Region{10, 10, 7, 5, 4}}) {
    const CnsImage c = contrastNormalizedSobel(img.view(), g.x0, g.y0, g.w, g.h, g.r, 40.0);
    ASSERT_GT(c.width, 0);
    ASSERT_GT(c.height, 0);
    EXPECT_EQ(c.x0, std::max(g.x0, 0));
    EXPECT_EQ(c.y0, std::max(g.y0, 0));
    for (int y = c.y0; y < c.y0 + c.height; ++y)
      for (int x = c.x0; x < c.x0 + c.width; ++x) {
        const std::size_t k = static_cast<std::size_t>(y - c.y0) * c.width + (x - c.x0);
        ASSERT_NEAR(c.gy[k], cnsReference(img, x, y, g.r, 40.0, true), 1e-4) << x << "," << y << " r=" << g.r;
        ASSERT_NEAR(c.gx[k], cnsReference(img, x, y, g.r, 40.0, false), 1e-4) << x << "," << y << " r=" << g.r;
      }
  }
}

TEST(Cns, EdgeMaskIsTheThresholdedVerticalResponse) {
  // Random pixels (every response) and a smooth ramp with steps (many near the threshold).
  GrayImage noise(48, 36), steps(48, 36);
  std::mt19937_64 rng(5);
  std::uniform_int_distribution<int> v(0, 255), d(-6, 6);
  for (int y = 0; y < 36; ++y)
    for (int x = 0; x < 48; ++x) {
      noise.at(x, y) = static_cast<std::uint8_t>(v(rng));
      steps.at(x, y) = static_cast<std::uint8_t>(std::clamp(60 + (y / 5) * 18 - (y % 5) * 3 + d(rng), 0, 255));
    }
  struct Region {
    int x0, y0, w, h, r;
  };
  int on = 0, off = 0;
  for (const GrayImage* img : {&noise, &steps})
    for (const Region& g : {Region{5, 4, 20, 15, 2}, Region{0, 0, 48, 36, 2}, Region{-3, 20, 12, 20, 3},
                            Region{30, -2, 25, 8, 1}, Region{10, 10, 7, 5, 0}, Region{2, 3, 40, 30, 6}})
      for (double sigma : {40.0, 5.0})
        for (double t : {0.0, 0.3, 0.5, 1.2}) {
          const CnsImage c = contrastNormalizedSobel(img->view(), g.x0, g.y0, g.w, g.h, g.r, sigma);
          const CnsEdgeMask m = brightAboveEdgeMask(img->view(), g.x0, g.y0, g.w, g.h, g.r, sigma, t);
          ASSERT_EQ(m.x0, c.x0);
          ASSERT_EQ(m.y0, c.y0);
          ASSERT_EQ(m.width, c.width);
          ASSERT_EQ(m.height, c.height);
          for (int y = c.y0; y < c.y0 + c.height; ++y)
            for (int x = c.x0; x < c.x0 + c.width; ++x) {
              const bool want = -c.gyAt(x, y) > static_cast<float>(t);
              ASSERT_EQ(m.at(x, y), want) << x << "," << y << " r=" << g.r << " sigma=" << sigma << " t=" << t;
              ++(want ? on : off);
            }
        }
  EXPECT_GT(on, 1000);  // both answers are exercised
  EXPECT_GT(off, 1000);
  EXPECT_TRUE(brightAboveEdgeMask(noise.view(), 60, 0, 10, 10, 2, 40, 0.5).on.empty());  // outside the image
  EXPECT_THROW(brightAboveEdgeMask(noise.view(), 0, 0, 10, 10, kMaxEdgeMaskRadiusPx + 1, 40, 0.5), Error);
}

RobotOrientationEstimator untrainedEstimator(
    const RobotOrientationParams& params = RobotOrientationParams::loadDefault()) {
  auto net = [](int i) {
    cnn::Net n = cnn::readDarknetCfg(cnn::kShippedNets[i].cfgPath());
    n.initialise(3);
    return cnn::Classifier(std::move(n));
  };
  return RobotOrientationEstimator(params, FieldDimensions::loadDefault(), net(3), net(4));
}

// The robot percept of a drawn block (its image outline `hull`, its centre on the ground) as the
// proposer gives it: the feet point at the outline's lowest row, the box a robot's size above it.
RobotPercept perceptOfBlock(const CameraModel& cam, const std::vector<cv::Point>& hull,
                            const Eigen::Vector2d& centre) {
  RobotPercept robot;
  int lowest = 0;
  for (const auto& q : hull) lowest = std::max(lowest, q.y);
  robot.feet_px = {cam.robotToPixel({centre.x(), centre.y(), 0})->x(), double(lowest)};
  const double h = robotSizePx(cam, robot.feet_px).h;
  robot.box = {robot.feet_px.x() - 0.4 * h, robot.feet_px.y() - h, robot.feet_px.x() + 0.4 * h,
               robot.feet_px.y() + 0.05 * h};
  robot.position_in_robot = centre;
  return robot;
}

// The image outline of a block on the ground (both feet seen together), 0.16 deep, 0.20 wide and
// 0.05 high, about `centre`, turned by `yaw_deg`.
std::vector<cv::Point> footBlockHull(const CameraModel& cam, const Eigen::Vector2d& centre,
                                     double yaw_deg) {
  const double yaw = yaw_deg * std::numbers::pi / 180;
  const Eigen::Vector2d u(std::cos(yaw), std::sin(yaw)), v(-std::sin(yaw), std::cos(yaw));
  std::vector<cv::Point> pts, hull;
  for (double a : {-0.08, 0.08})
    for (double b : {-0.10, 0.10})
      for (double z : {0.0, 0.05}) {
        const Eigen::Vector2d g = centre + a * u + b * v;
        const auto p = cam.robotToPixel({g.x(), g.y(), z});
        pts.emplace_back(int(std::lround(p->x())), int(std::lround(p->y())));
      }
  cv::convexHull(pts, hull);
  return hull;
}

// `shadow_ratio` >= 0: the block casts a dark shadow on the carpet towards the camera and its
// left (directional light), and the lines generator runs with that above-the-carpet ratio.
void checkFootBlockLine(double yaw_deg, double shadow_ratio = -1) {
  const CameraModel cam = testCamera();
  {
    GrayImage img = carpet(5);
    // A bright block on the ground (both feet seen together), 0.20 wide, 0.16 deep, 0.05 high.
    const Eigen::Vector2d centre(1.2, 0.0);
    const double yaw = yaw_deg * std::numbers::pi / 180;
    const Eigen::Vector2d u(std::cos(yaw), std::sin(yaw)), v(-std::sin(yaw), std::cos(yaw));
    const std::vector<cv::Point> hull = footBlockHull(cam, centre, yaw_deg);
    cv::Mat m = wrap(img);
    if (shadow_ratio >= 0) {
      // The shadow: the block's footprint swept along the light on the ground, towards the camera
      // and the left (darker than the carpet); left of the block its upper edge has the carpet
      // above it, a bright-above-dark edge as strong as the block's.
      std::vector<cv::Point> shadow_pts, shadow;
      for (double a : {-0.08, 0.08})
        for (double b : {-0.10, 0.10})
          for (double s : {0.0, 1.0}) {
            const Eigen::Vector2d g = centre + a * u + b * v + s * Eigen::Vector2d(-0.05, 0.12);
            const auto p = cam.robotToPixel({g.x(), g.y(), 0});
            shadow_pts.emplace_back(int(std::lround(p->x())), int(std::lround(p->y())));
          }
      cv::convexHull(shadow_pts, shadow);
      cv::fillConvexPoly(m, shadow, cv::Scalar(20));
    }
    cv::fillConvexPoly(m, hull, cv::Scalar(200));
    const RobotPercept robot = perceptOfBlock(cam, hull, centre);
    const int lowest = static_cast<int>(robot.feet_px.y());
    RobotOrientationParams params = RobotOrientationParams::loadDefault();
    if (shadow_ratio >= 0) params.silhouette_min_above_carpet_ratio = shadow_ratio;
    const RobotLines lines = untrainedEstimator(params).findLines(img.view(), cam, robot);
    int left = 640, right = 0;
    for (const auto& q : hull) left = std::min(left, q.x), right = std::max(right, q.x);
    auto offBlock = [&](const Eigen::Vector2d& q) { return q.x() < left - 3 || q.x() > right + 3 || q.y() > lowest + 3; };
    if (shadow_ratio == 0) {
      // Without the test, the shadow's edge left of the block is the lowest long chain there.
      EXPECT_TRUE(std::any_of(lines.silhouette_px.begin(), lines.silhouette_px.end(), offBlock)) << yaw_deg;
      return;
    }
    // Every silhouette point lies on the block, none on the shadow beside and below it.
    for (const auto& q : lines.silhouette_px) EXPECT_FALSE(offBlock(q)) << yaw_deg << " " << q.transpose();
    ASSERT_FALSE(lines.regions.empty()) << yaw_deg;
    const Eigen::Vector2d d = lines.regions[0].line_in_robot.direction();
    // The lower silhouette is the block's near edges: the first line lies along one of them.
    const double along_v = std::abs(d.dot(v)), along_u = std::abs(d.dot(u));
    EXPECT_GT(std::max(along_u, along_v), std::cos(6 * std::numbers::pi / 180)) << yaw_deg;
  }
}

TEST(LinesGenerator, FindsTheFrontEdgeOfADrawnFootBlock) { checkFootBlockLine(0.0); }

// Turned, the block shows two near edges meeting at a corner; the hull edge closing them behind
// (no edge of the block) and noise points below the edges must not win.
TEST(LinesGenerator, FindsAnEdgeOfATurnedFootBlock) {
  for (double yaw : {30.0, -50.0, 15.0, 70.0, -35.0}) checkFootBlockLine(yaw);
}

// A bright-above-dark edge in the feet region well behind the feet point (lit carpet beyond the
// robot, a field line's edge, or a feet point put too low) is not the feet's: no line there; one
// a little behind it still is, and without the limit the far one is too.
TEST(LinesGenerator, DropsALineFarBehindTheFeetPoint) {
  const CameraModel cam = testCamera();
  const Eigen::Vector2d feet_centre(1.2, 0.0);
  const RobotPercept robot = perceptOfBlock(cam, footBlockHull(cam, feet_centre, 0), feet_centre);
  const auto feet = cam.pixelToGround(robot.feet_px);
  ASSERT_TRUE(feet);
  const double limit = RobotOrientationParams::loadDefault().line_max_feet_distance_m;
  ASSERT_GT(limit, 0);
  for (const double behind_m : {0.5 * limit, 1.5 * limit}) {
    SCOPED_TRACE(behind_m);
    GrayImage img = carpet(5);
    const Eigen::Vector2d centre = feet_centre + Eigen::Vector2d(behind_m, 0);
    cv::fillConvexPoly(wrap(img), footBlockHull(cam, centre, 0), cv::Scalar(200));
    for (const double max_distance : {limit, 0.0}) {
      RobotOrientationParams params = RobotOrientationParams::loadDefault();
      params.line_max_feet_distance_m = max_distance;
      const RobotLines lines = untrainedEstimator(params).findLines(img.view(), cam, robot);
      if (max_distance > 0 && behind_m > limit) {
        EXPECT_TRUE(lines.regions.empty());
        continue;
      }
      ASSERT_FALSE(lines.regions.empty()) << max_distance;
      // The block's near edge, as far behind the feet point as the block was moved.
      const LineHypothesis& line = lines.regions[0].line_in_robot;
      EXPECT_NEAR(((line.a + line.b) / 2 - *feet).x(), behind_m, 0.03) << max_distance;
    }
  }
}

// Directional light: the block's cast shadow below it has the carpet above its near edge. The
// silhouette keeps only edges with more than the carpet above them: the block's, not the shadow's
// (which, without that test, would be the lowest chain and so the silhouette).
TEST(LinesGenerator, IgnoresTheCastShadowBelowAFootBlock) {
  const double ratio = RobotOrientationParams::loadDefault().silhouette_min_above_carpet_ratio;
  ASSERT_GT(ratio, 0);
  for (double yaw : {0.0, 30.0, -50.0}) {
    checkFootBlockLine(yaw, ratio);
    checkFootBlockLine(yaw, 0.0);
  }
}

// A field line on the carpet just in front of the feet (its middle 0.07 m before the block's near
// face, 0.05 wide, 3 m long across the line of sight), or the centre circle's line passing there:
// its lower edge is bright above dark like the feet's and lower in the image, so without the field
// features the silhouette lies on it. Given the frame's detected lines (or circle), its edge is
// dropped and the silhouette is the block's again; a short line (a robot's leg taken for one) or
// one along the line of sight drops nothing.
TEST(LinesGenerator, ADetectedFieldLineInFrontOfTheFeetIsNoSilhouette) {
  const CameraModel cam = testCamera();
  const Eigen::Vector2d centre(1.2, 0.0);
  const double line_x = centre.x() - 0.08 - 0.07;
  const double radius = FieldDimensions::loadDefault().centre_circle_diameter_m / 2;
  const Eigen::Vector2d circle_centre(line_x - radius, 0.0);
  const auto px = [&](double x, double y) {
    const auto q = cam.robotToPixel({x, y, 0});
    return cv::Point(int(std::lround(q->x())), int(std::lround(q->y())));
  };
  LinePercept field_line;
  field_line.start_in_robot = {line_x, -1.5};
  field_line.end_in_robot = {line_x, 1.5};
  LinePercept short_line = field_line;
  short_line.start_in_robot = {line_x, -0.2};
  short_line.end_in_robot = {line_x, 0.2};
  LinePercept along_sight = field_line;
  along_sight.start_in_robot = {line_x - 1.0, 0.0};
  along_sight.end_in_robot = {line_x + 1.0, 0.0};
  // As the field lines stage gives them: ends on the ground and in the image.
  const auto features = [&](std::vector<LinePercept> lines, bool circle) {
    FieldFeatures f;
    for (LinePercept& l : lines) {
      l.start_px = *cam.robotToPixel({l.start_in_robot.x(), l.start_in_robot.y(), 0});
      l.end_px = *cam.robotToPixel({l.end_in_robot.x(), l.end_in_robot.y(), 0});
    }
    f.lines = std::move(lines);
    if (circle) f.centre_circle = CircleMarkPercept{circle_centre, *cam.robotToPixel({circle_centre.x(), 0, 0})};
    return f;
  };
  const RobotOrientationEstimator estimator = untrainedEstimator();
  ASSERT_GT(estimator.params().field_line_margin_px, 0);
  ASSERT_GT(estimator.params().field_line_min_length_m, 0.4);
  for (const bool ring : {false, true}) {
    SCOPED_TRACE(ring ? "centre circle" : "straight line");
    GrayImage img = carpet(13);
    cv::Mat m = wrap(img);
    if (ring) {
      // The circle's line (0.05 wide) as a polygon ring of 360 steps.
      for (int k = 0; k < 360; ++k) {
        std::vector<cv::Point> piece;
        for (const auto& [r, a] : std::vector<std::pair<double, int>>{
                 {radius - 0.025, k}, {radius - 0.025, k + 1}, {radius + 0.025, k + 1}, {radius + 0.025, k}}) {
          const double t = a * std::numbers::pi / 180;
          piece.push_back(px(circle_centre.x() + r * std::cos(t), r * std::sin(t)));
        }
        cv::fillConvexPoly(m, piece, cv::Scalar(200));
      }
    } else {
      cv::fillConvexPoly(m, std::vector<cv::Point>{px(line_x - 0.025, -1.5), px(line_x - 0.025, 1.5),
                                                   px(line_x + 0.025, 1.5), px(line_x + 0.025, -1.5)},
                         cv::Scalar(200));
    }
    const std::vector<cv::Point> hull = footBlockHull(cam, centre, 0);
    cv::fillConvexPoly(m, hull, cv::Scalar(200));
    const RobotPercept robot = perceptOfBlock(cam, hull, centre);
    int lowest_block = 0;
    for (const auto& q : hull) lowest_block = std::max(lowest_block, q.y);
    const auto onStripe = [&](const Eigen::Vector2d& q) { return q.y() > lowest_block + 3; };
    for (const auto& lines : {std::vector<LinePercept>{}, {short_line}, {along_sight}}) {
      const RobotLines out = estimator.findLines(img.view(), cam, robot, features(lines, false));
      EXPECT_TRUE(std::any_of(out.silhouette_px.begin(), out.silhouette_px.end(), onStripe)) << lines.size();
    }
    const RobotLines out = estimator.findLines(
        img.view(), cam, robot, ring ? features({}, true) : features({field_line}, false));
    EXPECT_GT(out.silhouette_px.size(), 20u);
    for (const auto& q : out.silhouette_px) EXPECT_FALSE(onStripe(q)) << q.transpose();
    ASSERT_FALSE(out.regions.empty());
    const Eigen::Vector2d mid = (out.regions[0].line_in_robot.a + out.regions[0].line_in_robot.b) / 2;
    EXPECT_NEAR(mid.x(), centre.x() - 0.08, 0.02);  // the block's near edge
  }
}

// A robot standing on a field line: the feet's near edge lies over the line, a dark sole right
// below it and the line's white below that. Dropping every edge on the detected line drops the
// feet's too (the silhouette there is gone); the sole's thin dark stripe under an edge tells it is
// the feet's, and it stays: the block's near edge is the first line (on a robot box tall enough
// for a sole to show).
TEST(LinesGenerator, AFeetEdgeOverADetectedFieldLineWithASoleBelowStays) {
  const CameraModel cam = testCamera();
  const Eigen::Vector2d centre(1.2, 0.0);
  const double near_x = centre.x() - 0.08;  // the block's near face, over the line's middle
  const auto px = [&](double x, double y, double z = 0) {
    const auto q = cam.robotToPixel({x, y, z});
    return cv::Point(int(std::lround(q->x())), int(std::lround(q->y())));
  };
  GrayImage img = carpet(17);
  cv::Mat m = wrap(img);
  cv::fillConvexPoly(m, std::vector<cv::Point>{px(near_x - 0.025, -1.5), px(near_x - 0.025, 1.5),
                                               px(near_x + 0.025, 1.5), px(near_x + 0.025, -1.5)},
                     cv::Scalar(200));
  const std::vector<cv::Point> hull = footBlockHull(cam, centre, 0);
  cv::fillConvexPoly(m, hull, cv::Scalar(200));
  // The sole: the near face's lowest 8 mm, near black.
  cv::fillConvexPoly(m, std::vector<cv::Point>{px(near_x, -0.1), px(near_x, 0.1), px(near_x, 0.1, 0.008),
                                               px(near_x, -0.1, 0.008)},
                     cv::Scalar(15));
  const RobotPercept robot = perceptOfBlock(cam, hull, centre);
  LinePercept line;
  line.start_in_robot = {near_x, -1.5};
  line.end_in_robot = {near_x, 1.5};
  line.start_px = *cam.robotToPixel({near_x, -1.5, 0});
  line.end_px = *cam.robotToPixel({near_x, 1.5, 0});
  FieldFeatures field;
  field.lines = {line};
  const int sole_top = px(near_x, 0.0, 0.008).y;
  const int left = px(near_x, 0.1).x, right = px(near_x, -0.1).x;
  const auto onNearEdge = [&](const Eigen::Vector2d& q) {
    return q.x() > left && q.x() < right && std::abs(q.y() - sole_top) <= 3;
  };
  RobotOrientationParams params = RobotOrientationParams::loadDefault();
  ASSERT_GT(params.field_line_sole_max_gray_ratio, 0);
  const RobotLines kept = untrainedEstimator(params).findLines(img.view(), cam, robot, field);
  EXPECT_GT(std::count_if(kept.silhouette_px.begin(), kept.silhouette_px.end(), onNearEdge), 0.8 * (right - left));
  ASSERT_FALSE(kept.regions.empty());
  const LineHypothesis& first = kept.regions[0].line_in_robot;
  EXPECT_GT(std::abs(first.direction().y()), std::cos(5 * std::numbers::pi / 180));
  EXPECT_NEAR((first.a + first.b).x() / 2, near_x, 0.03);
  ASSERT_GE(robot.box.height(), params.field_line_sole_min_box_height_px);
  // Off, or on a robot box too small for its sole to show: the edge goes with the line.
  RobotOrientationParams off = params, small = params;
  off.field_line_sole_max_gray_ratio = 0;
  small.field_line_sole_min_box_height_px = robot.box.height() + 1;
  for (const RobotOrientationParams& q : {off, small}) {
    const RobotLines dropped = untrainedEstimator(q).findLines(img.view(), cam, robot, field);
    EXPECT_LT(std::count_if(dropped.silhouette_px.begin(), dropped.silhouette_px.end(), onNearEdge),
              0.2 * (right - left));
  }
}

// OriNet looks at each region as it is and mirrored, the mirrored look's side classes swapped: a
// stand-in OriNet that says "side facing left" more surely when a region's left half is the
// brighter (logit 2 as it is, 1 mirrored, against 0 for the front) gives a side region of unknown
// facing (0.44 left, 0.37 right); with one look, 0.88 facing left.
TEST(RobotOrientation, OriNetsMirroredLookHasItsSideClassesSwapped) {
  const CameraModel cam = testCamera();
  GrayImage img = carpet(5);
  const Eigen::Vector2d centre(1.2, 0.0);
  const std::vector<cv::Point> hull = footBlockHull(cam, centre, 20);
  cv::fillConvexPoly(wrap(img), hull, cv::Scalar(200));
  const RobotPercept robot = perceptOfBlock(cam, hull, centre);
  RobotOrientationParams params = RobotOrientationParams::loadDefault();
  const RobotLines lines = untrainedEstimator(params).findLines(img.view(), cam, robot);
  ASSERT_FALSE(lines.regions.empty());
  const PixelBox& r = lines.regions[0].box;
  std::vector<float> patch(24 * 24);
  cnn::extractPatch(img.view(), {float(r.x0), float(r.y0), float(r.width()), float(r.height())}, 24,
                    24, cnn::PatchNormalization::kStandardize, patch.data());
  double d = 0;  // (the left half's mean - the right half's) / 2
  for (int y = 0; y < 24; ++y) {
    for (int x = 0; x < 24; ++x) d += (x < 12 ? 0.5 : -0.5) * patch[y * 24 + x] / 288.0;
  }
  ASSERT_GT(std::abs(d), 0.02);
  const double k = 0.5 / d, beta = 1.5;  // logits 2 as it is, 1 mirrored
  cnn::Net usable = cnn::parseDarknetCfg(
      "# colorfree normalization=standardize\n[net]\nwidth=12\nheight=12\nchannels=1\n\n"
      "[connected]\noutput=2\nactivation=linear\n\n[softmax]\n",
      "usable net");
  usable.params()[1] = 20;  // every region usable
  cnn::Net sided = cnn::parseDarknetCfg(
      "# colorfree normalization=standardize\n[net]\nwidth=24\nheight=24\nchannels=1\n\n"
      "[connected]\noutput=4\nactivation=linear\n\n[softmax]\n",
      "sided ori net");
  std::vector<float>& w = sided.params();  // biases (front, back, left, right), then weights
  w[0] = 0;
  w[1] = w[3] = -20;
  w[2] = static_cast<float>(beta);
  for (int y = 0; y < 24; ++y) {
    for (int x = 0; x < 24; ++x) w[4 + 2 * 576 + y * 24 + x] = float((x < 12 ? k : -k) / 576);
  }
  for (const bool mirrored : {true, false}) {
    SCOPED_TRACE(mirrored);
    params.ori_net_mirrored_look = mirrored;
    const RobotLines out =
        RobotOrientationEstimator(params, FieldDimensions::loadDefault(), cnn::Classifier(usable),
                                  cnn::Classifier(sided))
            .estimate(img.view(), cam, robot);
    ASSERT_FALSE(out.regions.empty());
    const LineRegion& g = out.regions[0];
    ASSERT_TRUE(g.side.has_value());
    EXPECT_EQ(*g.side, RobotSide::kSide);
    const double left = 1 / (1 + std::exp(-2.0)), left_mirrored = 1 / (1 + std::exp(-1.0));
    EXPECT_NEAR(g.side_confidence, mirrored ? 0.5 * (left + left_mirrored) : left, 1e-3);
    EXPECT_EQ(g.side_facing_known, !mirrored);
    if (!mirrored) {
      EXPECT_TRUE(g.faces_left);
    }
  }
}

// A back view's heels: a block on the ground, 0.16 deep, 0.20 wide, 0.08 high, of gray
// `shoe_gray`, its near face (a = -0.08, towards the camera) dark from the ground to 0.04 m;
// `rim` draws a 1-px white rim along the panel's upper edge.
struct HeelBlock {
  const CameraModel& cam;
  Eigen::Vector2d centre, u, v;
  HeelBlock(const CameraModel& c, double yaw_deg) : cam(c), centre(1.2, 0.0) {
    const double yaw = yaw_deg * std::numbers::pi / 180;
    u = {std::cos(yaw), std::sin(yaw)};
    v = {-std::sin(yaw), std::cos(yaw)};
  }
  cv::Point px(double a, double b, double z) const {
    const Eigen::Vector2d g = centre + a * u + b * v;
    const auto q = cam.robotToPixel({g.x(), g.y(), z});
    return {int(std::lround(q->x())), int(std::lround(q->y()))};
  }
  // The near face's row at height z over column x.
  double rowOn(double z, double x) const {
    const cv::Point l = px(-0.08, -0.10, z), r = px(-0.08, 0.10, z);
    return l.y + (x - l.x) * double(r.y - l.y) / (r.x - l.x);
  }
  std::vector<cv::Point> draw(GrayImage& img, int shoe_gray, bool rim) const {
    std::vector<cv::Point> pts, hull;
    for (double a : {-0.08, 0.08})
      for (double b : {-0.10, 0.10})
        for (double z : {0.0, 0.08}) pts.push_back(px(a, b, z));
    cv::convexHull(pts, hull);
    cv::Mat m = wrap(img);
    cv::fillConvexPoly(m, hull, cv::Scalar(shoe_gray));
    const std::vector<cv::Point> panel = {px(-0.08, -0.10, 0), px(-0.08, 0.10, 0),
                                          px(-0.08, 0.10, 0.04), px(-0.08, -0.10, 0.04)};
    cv::fillConvexPoly(m, panel, cv::Scalar(25));
    if (rim) cv::line(m, px(-0.08, -0.10, 0.04), px(-0.08, 0.10, 0.04), cv::Scalar(255), 1);
    return hull;
  }
  // The silhouette points over the near face's columns (3 px in from its ends): how many, and how
  // many of them lie within 2.5 rows of the face's row at height z.
  std::pair<int, int> pointsOnFace(const RobotLines& lines, double z) const {
    const cv::Point l = px(-0.08, -0.10, 0), r = px(-0.08, 0.10, 0);
    int n = 0, at_z = 0;
    for (const auto& q : lines.silhouette_px) {
      if (q.x() < std::min(l.x, r.x) + 3 || q.x() > std::max(l.x, r.x) - 3) continue;
      ++n;
      at_z += std::abs(q.y() - rowOn(z, q.x())) <= 2.5;
    }
    return {n, at_z};
  }
};

// The white shoe above the panel: the silhouette's edge is the panel's upper edge (white above
// dark); below the panel the points move to its lower end, the ground: the line lies on the face's
// ground edge. With the rule off they stay on the upper edge, the panel's height above.
TEST(LinesGenerator, MovesBelowAHeelPanelToTheGround) {
  const CameraModel cam = testCamera();
  for (const double yaw_deg : {0.0, 20.0, -25.0}) {
    GrayImage img = carpet(7, 90);
    const HeelBlock heel(cam, yaw_deg);
    const RobotPercept robot = perceptOfBlock(cam, heel.draw(img, 220, false), heel.centre);
    const double h = robotSizePx(cam, robot.feet_px).h;
    const cv::Point face_l = heel.px(-0.08, -0.10, 0);
    const double panel_px = heel.rowOn(0, face_l.x) - heel.rowOn(0.04, face_l.x);
    ASSERT_GT(panel_px, 0.045 * h) << yaw_deg;  // a panel the rule takes (its default bounds)
    ASSERT_LT(panel_px, 0.1 * h) << yaw_deg;
    std::optional<PixelBox> region_off;  // the first line's region without the rule
    for (const bool on : {false, true}) {
      RobotOrientationParams params = RobotOrientationParams::loadDefault();
      ASSERT_GT(params.dark_panel_max_gray_ratio, 0);
      if (!on) params.dark_panel_max_gray_ratio = 0;
      const RobotLines lines = untrainedEstimator(params).findLines(img.view(), cam, robot);
      const std::string what = std::to_string(yaw_deg) + (on ? " on" : " off");
      const auto [on_face, at_z] = heel.pointsOnFace(lines, on ? 0.0 : 0.04);
      EXPECT_GT(on_face, 20) << what;
      EXPECT_EQ(at_z, on_face) << what;
      ASSERT_FALSE(lines.regions.empty()) << what;
      if (!on) {
        region_off = lines.regions[0].box;
        continue;
      }
      // The region still hangs from the panel's upper edge, where the nets were trained to see it.
      EXPECT_NEAR(lines.regions[0].box.y0, region_off->y0, 3) << yaw_deg;
      EXPECT_NEAR(lines.regions[0].box.y1, region_off->y1, 3) << yaw_deg;
      const Eigen::Vector2d d = lines.regions[0].line_in_robot.direction();
      EXPECT_GT(std::abs(d.dot(heel.v)), std::cos(4 * std::numbers::pi / 180)) << yaw_deg;
      // The line lies on the ground edge: its points 0.08 m in front of the centre.
      const Eigen::Vector2d mid =
          (lines.regions[0].line_in_robot.a + lines.regions[0].line_in_robot.b) / 2;
      EXPECT_NEAR((mid - heel.centre).dot(heel.u), -0.08, 0.015) << yaw_deg;
    }
  }
}

// The shoe in shade (gray 100 on carpet of 80) with a thin white rim over the panel (directional
// or uneven light on a back view): the shoe-to-panel step is too weak, and the rim-to-panel edge
// answers on one row only. With a panel right below, one row is edge enough
// (dark_panel_edge_min_rows): the silhouette is the face's ground edge. Asking two rows there (the
// rule for other edges), no silhouette point lies on the ground edge.
TEST(LinesGenerator, AThinRimOverAHeelPanelIsItsEdge) {
  const CameraModel cam = testCamera();
  for (const double yaw_deg : {0.0, 20.0, -25.0}) {
    GrayImage img = carpet(11, 80);
    const HeelBlock heel(cam, yaw_deg);
    const RobotPercept robot = perceptOfBlock(cam, heel.draw(img, 100, true), heel.centre);
    for (const int panel_rows : {2, 1}) {
      RobotOrientationParams params = RobotOrientationParams::loadDefault();
      ASSERT_EQ(params.silhouette_min_rows, 2);
      ASSERT_EQ(params.dark_panel_edge_min_rows, 1);
      params.dark_panel_edge_min_rows = panel_rows;
      const RobotLines lines = untrainedEstimator(params).findLines(img.view(), cam, robot);
      const std::string what = std::to_string(yaw_deg) + " rows " + std::to_string(panel_rows);
      const auto [on_face, on_ground] = heel.pointsOnFace(lines, 0.0);
      if (panel_rows == 2) {
        EXPECT_EQ(on_ground, 0) << what;
        continue;
      }
      EXPECT_GT(on_face, 20) << what;
      EXPECT_EQ(on_ground, on_face) << what;
      ASSERT_FALSE(lines.regions.empty()) << what;
      const Eigen::Vector2d d = lines.regions[0].line_in_robot.direction();
      EXPECT_GT(std::abs(d.dot(heel.v)), std::cos(4 * std::numbers::pi / 180)) << what;
    }
  }
}

TEST(RobotTracks, AssociatesOverFramesAndExpires) {
  OrientationFilterParams filter;
  filter.expiry_s = 1.0;
  RobotTracks tracks;
  auto percept = [](double x, double y, std::optional<double> angle) {
    RobotPercept r;
    r.position_in_robot = Eigen::Vector2d(x, y);
    if (angle) r.orientation_raw = RobotOrientation{*angle, true};
    return r;
  };
  std::vector<RobotPercept> f1{percept(1.0, 0.0, 0.5), percept(2.0, 1.0, -1.0)};
  updateRobotTracks(tracks, f1, 0.0, 0.5, filter);
  ASSERT_EQ(tracks.tracks.size(), 2u);
  EXPECT_NE(f1[0].track_id, f1[1].track_id);
  // Next frame: listed in the other order, both moved a little; a third robot appears.
  std::vector<RobotPercept> f2{percept(2.1, 1.0, -1.0), percept(1.05, 0.05, 0.6), percept(3, -2, {})};
  updateRobotTracks(tracks, f2, 0.1, 0.5, filter);
  EXPECT_EQ(f2[0].track_id, f1[1].track_id);
  EXPECT_EQ(f2[1].track_id, f1[0].track_id);
  EXPECT_NE(f2[2].track_id, f1[0].track_id);
  EXPECT_NE(f2[2].track_id, f1[1].track_id);
  ASSERT_TRUE(f2[1].orientation_filtered.has_value());
  EXPECT_FALSE(f2[2].orientation_filtered.has_value());
  // Each track counts its frames with a percept (the detector's track prior asks for some).
  const auto hitsOf = [&](int id) {
    for (const RobotTracks::Track& t : tracks.tracks) {
      if (t.id == id) return t.hits;
    }
    return -1;
  };
  EXPECT_EQ(hitsOf(f2[0].track_id), 2);
  EXPECT_EQ(hitsOf(f2[1].track_id), 2);
  EXPECT_EQ(hitsOf(f2[2].track_id), 1);
  // The detector's tracked robots: seen in 2 frames (not the new one), and not expired.
  const auto tracked = trackedRobots(tracks, 0.2, 2, 1.0);
  ASSERT_EQ(tracked.size(), 2u);
  EXPECT_TRUE(trackedRobots(tracks, 0.2, 3, 1.0).empty());
  EXPECT_EQ(trackedRobots(tracks, 0.2, 1, 1.0).size(), 3u);
  EXPECT_TRUE(trackedRobots(tracks, 1.2, 1, 1.0).empty());
  EXPECT_EQ(trackedRobots(tracks, 1.05, 1, 1.0).size(), 3u);
  // Long after: the old tracks expired, the same place starts a new track.
  std::vector<RobotPercept> f3{percept(1.0, 0.0, 0.5)};
  updateRobotTracks(tracks, f3, 5.0, 0.5, filter);
  EXPECT_EQ(tracks.tracks.size(), 1u);
  EXPECT_GT(f3[0].track_id, f2[2].track_id);
}

}  // namespace
}  // namespace colorfree
