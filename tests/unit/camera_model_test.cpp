#include "colorfree/perception/camera_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "colorfree/perception/error.h"
#include "test_support.h"

namespace colorfree {
namespace {

constexpr double kPi = 3.14159265358979323846;

CameraModel naoTopCamera(double pitch_deg = 20, double yaw_deg = 0, double roll_deg = 0) {
  CameraPose pose;
  pose.x_m = 0.05;
  pose.height_m = 0.51;
  pose.pitch_rad = pitch_deg * kPi / 180;
  pose.yaw_rad = yaw_deg * kPi / 180;
  pose.roll_rad = roll_deg * kPi / 180;
  return CameraModel(CameraIntrinsics::fromHorizontalFov(640, 480, 60.9 * kPi / 180), pose);
}

TEST(CameraModel, PrincipalRayPointsForwardAndDown) {
  const CameraModel cam = naoTopCamera(30);
  const Eigen::Vector3d ray = cam.pixelRay({320, 240});
  EXPECT_NEAR(ray.x(), std::cos(30 * kPi / 180), 1e-12);
  EXPECT_NEAR(ray.y(), 0, 1e-12);
  EXPECT_NEAR(ray.z(), -std::sin(30 * kPi / 180), 1e-12);
}

TEST(CameraModel, ImageRightIsRobotRight) {
  const CameraModel cam = naoTopCamera(30);
  const auto left = cam.pixelToGround({100, 400});
  const auto right = cam.pixelToGround({540, 400});
  ASSERT_TRUE(left && right);
  EXPECT_GT(left->y(), 0);   // robot y points left
  EXPECT_LT(right->y(), 0);
}

class CameraRoundTrip : public ::testing::TestWithParam<std::tuple<double, double, double>> {};

TEST_P(CameraRoundTrip, PixelToGroundToPixel) {
  const auto [pitch, yaw, roll] = GetParam();
  const CameraModel cam = naoTopCamera(pitch, yaw, roll);
  int checked = 0;
  for (double y = 0.5; y < 480; y += 37) {
    for (double x = 0.5; x < 640; x += 41) {
      const auto ground = cam.pixelToGround({x, y});
      if (!ground) continue;
      const auto back = cam.robotToPixel({ground->x(), ground->y(), 0});
      ASSERT_TRUE(back);
      EXPECT_NEAR(back->x(), x, 1e-6);
      EXPECT_NEAR(back->y(), y, 1e-6);
      ++checked;
    }
  }
  EXPECT_GT(checked, 20);
}

INSTANTIATE_TEST_SUITE_P(Poses, CameraRoundTrip,
                         ::testing::Values(std::make_tuple(20.0, 0.0, 0.0),
                                           std::make_tuple(45.0, 30.0, 0.0),
                                           std::make_tuple(5.0, -60.0, 4.0),
                                           std::make_tuple(70.0, 10.0, -8.0)));

TEST(CameraModel, HorizonSeparatesGroundFromSky) {
  const CameraModel cam = naoTopCamera(10, 0, 5);
  for (double x : {0.5, 320.0, 639.5}) {
    const auto h = cam.horizonY(x);
    ASSERT_TRUE(h);
    EXPECT_FALSE(cam.pixelToGround({x, *h - 0.5}));
    EXPECT_TRUE(cam.pixelToGround({x, *h + 0.5}));
  }
}

TEST(CameraModel, LevelCameraHorizonThroughCentre) {
  const CameraModel cam = naoTopCamera(0);
  EXPECT_NEAR(*cam.horizonY(320), 240, 1e-9);
  EXPECT_NEAR(*cam.horizonY(0), 240, 1e-9);
}

TEST(CameraModel, BallRadiusMatchesProjectedBall) {
  const CameraModel cam = naoTopCamera(25);
  const double r = 0.05;
  // A ball 2 m ahead: the projected top and bottom rim points span about two radii.
  const Eigen::Vector3d centre(2.0, 0, r);
  const auto c_px = cam.robotToPixel(centre);
  ASSERT_TRUE(c_px);
  const auto radius = cam.ballRadiusPx(*c_px, r);
  ASSERT_TRUE(radius);
  const double dist = (centre - cam.position()).norm();
  EXPECT_NEAR(*radius, cam.intrinsics().focal_y_px * r / dist, 0.05);
  const double horizon = *cam.horizonY(320);
  EXPECT_FALSE(cam.ballRadiusPx({320, horizon - 5}, r)) << "above the horizon there is no ground";
}

TEST(CameraModel, RobotHeightShrinksWithDistance) {
  const CameraModel cam = naoTopCamera(15);
  const auto near_feet = cam.robotToPixel({1.0, 0, 0});
  const auto far_feet = cam.robotToPixel({3.0, 0, 0});
  ASSERT_TRUE(near_feet && far_feet);
  const double near_h = *cam.robotHeightPx(*near_feet, 0.574);
  const double far_h = *cam.robotHeightPx(*far_feet, 0.574);
  EXPECT_GT(near_h, 2.5 * far_h);
  EXPECT_LT(near_h, 3.5 * far_h);
}

// robotHeightPx and ballRadiusPx are closed forms of their definitions: the feet pixel to the
// ground, the point robot_height_m above it back to a pixel, the distance between the two
// pixels; the ball's centre on its plane and the angle its sphere subtends from the camera. Over
// the whole image (the horizon and above it included) under pitched, turned and rolled cameras,
// with unequal focal lengths, both agree, and so do their empty answers.
TEST(CameraModel, RobotHeightAndBallRadiusFollowTheirDefinitions) {
  CameraIntrinsics stretched = CameraIntrinsics::fromHorizontalFov(640, 480, 60.9 * kPi / 180);
  stretched.focal_y_px *= 1.1;
  stretched.center_x_px = 310;
  CameraPose tilted;
  tilted.height_m = 0.45;
  tilted.pitch_rad = 35 * kPi / 180;
  tilted.roll_rad = -12 * kPi / 180;
  tilted.yaw_rad = 40 * kPi / 180;
  const CameraModel cams[] = {naoTopCamera(20), naoTopCamera(-5, 30, 8), naoTopCamera(60, -45, -20),
                              CameraModel(stretched, tilted)};
  int heights = 0, radii = 0, empty = 0;
  const auto expectSame = [&](const std::optional<double>& got, const std::optional<double>& expected,
                              double u, double v, int& count) {
    ASSERT_EQ(got.has_value(), expected.has_value()) << "at (" << u << ", " << v << ")";
    if (!expected) {
      ++empty;
      return;
    }
    ++count;
    ASSERT_NEAR(*got, *expected, 1e-9 * std::max(1.0, *expected)) << "at (" << u << ", " << v << ")";
  };
  for (const CameraModel& cam : cams) {
    for (double v = 0.5; v < 480; v += 7) {
      for (double u = 0.5; u < 640; u += 9) {
        const Eigen::Vector2d px(u, v);
        for (const double h : {0.574, 0.2}) {
          std::optional<double> expected;
          if (const auto g = cam.pixelToGround(px)) {
            if (const auto top = cam.robotToPixel({g->x(), g->y(), h})) expected = (px - *top).norm();
          }
          expectSame(cam.robotHeightPx(px, h), expected, u, v, heights);
        }
        for (const double r : {0.05, 0.3}) {
          std::optional<double> expected;
          if (const auto c = cam.pixelToGround(px, r)) {
            const double dist = (Eigen::Vector3d(c->x(), c->y(), r) - cam.position()).norm();
            if (dist > r) expected = cam.intrinsics().focal_y_px * std::tan(std::asin(r / dist));
          }
          expectSame(cam.ballRadiusPx(px, r), expected, u, v, radii);
        }
      }
    }
  }
  EXPECT_GT(heights, 1000);
  EXPECT_GT(radii, 1000);
  EXPECT_GT(empty, 1000) << "the poses must show the sky too";
}

TEST(CameraModel, RejectsImpossibleValues) {
  CameraIntrinsics k = CameraIntrinsics::fromHorizontalFov(640, 480, 1.0);
  CameraPose pose;
  pose.height_m = -0.1;
  EXPECT_THROW(CameraModel(k, pose), Error);
  pose.height_m = 0.5;
  k.focal_x_px = 0;
  EXPECT_THROW(CameraModel(k, pose), Error);
  k.focal_x_px = std::nan("");
  EXPECT_THROW(CameraModel(k, pose), Error);
  k = CameraIntrinsics::fromHorizontalFov(0, 480, 1.0);
  EXPECT_THROW(CameraModel(k, pose), Error);
}

TEST(CameraModel, FileRoundTrip) {
  const CameraModel cam = naoTopCamera(22, -35, 3);
  const std::string path = ::testing::TempDir() + "/camera_round_trip.yaml";
  cam.save(path);
  const CameraModel back = CameraModel::load(path);
  EXPECT_TRUE(back.cameraToRobot().isApprox(cam.cameraToRobot(), 1e-9));
  EXPECT_DOUBLE_EQ(back.intrinsics().focal_x_px, cam.intrinsics().focal_x_px);
  EXPECT_TRUE(back.exposureSmearPx().isZero(0));  // absent: the camera was still
  // The camera's own smear over the exposure (optional keys, written only when not zero).
  CameraModel turning = cam;
  turning.setExposureSmearPx({12.5, -3.25});
  turning.save(path);
  EXPECT_EQ(CameraModel::load(path).exposureSmearPx(), Eigen::Vector2d(12.5, -3.25));
  EXPECT_TRUE(CameraModel::load(path).rollingShutterShiftPx().isZero(0));
  turning.setRollingShutterShiftPx({-20, 4.5});
  turning.save(path);
  EXPECT_EQ(CameraModel::load(path).rollingShutterShiftPx(), Eigen::Vector2d(-20, 4.5));
  std::filesystem::remove(path);
}

// A rolling shutter read the top row half the readout before the frame's time and the bottom row
// half after: a point seen there is put back by half the shift either way, the middle row stays.
TEST(CameraModel, AtFrameTimeTakesOutTheRowsShareOfTheRollingShutterShift) {
  CameraModel cam = naoTopCamera(22, -35, 3);
  const Eigen::Vector2d p(100.25, 37.5);
  EXPECT_EQ(cam.atFrameTime(p), p);  // no shift given
  cam.setRollingShutterShiftPx({30, -8});
  const double h = cam.height();
  EXPECT_TRUE(cam.atFrameTime({100, 0.5 * h}).isApprox(Eigen::Vector2d(100, 0.5 * h), 1e-12));
  EXPECT_TRUE(cam.atFrameTime({100, 0}).isApprox(Eigen::Vector2d(115, -4), 1e-12));
  EXPECT_TRUE(cam.atFrameTime({100, h}).isApprox(Eigen::Vector2d(85, h + 4), 1e-12));
  EXPECT_TRUE(
      cam.atFrameTime({100, 0.25 * h}).isApprox(Eigen::Vector2d(107.5, 0.25 * h - 2), 1e-12));
  EXPECT_THROW(cam.setRollingShutterShiftPx({0, std::nan("")}), Error);
}

TEST(CameraModel, ExposureSmearKeysComeInPairsWithinBounds) {
  const std::string path = ::testing::TempDir() + "/camera_smear.yaml";
  const std::string base =
      "width_px: 640\nheight_px: 480\nfocal_x_px: 560\nfocal_y_px: 560\ncenter_x_px: 320\n"
      "center_y_px: 240\nx_m: 0\ny_m: 0\nheight_m: 0.5\nroll_deg: 0\npitch_deg: 10\nyaw_deg: 0\n";
  const auto fails = [&](const std::string& extra, const std::string& key) {
    {
      std::ofstream f(path);
      f << base << extra;
    }
    try {
      CameraModel::load(path);
    } catch (const Error& e) {
      return std::string(e.what()).find(path) != std::string::npos &&
             std::string(e.what()).find(key) != std::string::npos;
    }
    return false;
  };
  EXPECT_TRUE(fails("exposure_smear_x_px: 4\n", "exposure_smear_y_px"));  // one of the pair
  EXPECT_TRUE(fails("rolling_shift_y_px: 4\n", "rolling_shift_x_px"));
  EXPECT_TRUE(fails("exposure_smear_x_px: 4\nexposure_smear_y_px: .nan\n", "exposure_smear_y_px"));
  EXPECT_TRUE(fails("exposure_smear_x_px: 1e6\nexposure_smear_y_px: 0\n", "exposure_smear_x_px"));
  EXPECT_FALSE(fails("exposure_smear_x_px: -4\nexposure_smear_y_px: 1.5\n", "exposure_smear"));
  EXPECT_EQ(CameraModel::load(path).exposureSmearPx(), Eigen::Vector2d(-4, 1.5));
  std::filesystem::remove(path);
}

TEST(CameraModel, FileErrorsNameFileAndKey) {
  const std::string path = ::testing::TempDir() + "/camera_bad.yaml";
  {
    std::ofstream f(path);
    f << "width_px: 640\nheight_px: 480\nfocal_x_px: 0\nfocal_y_px: 500\ncenter_x_px: 320\n"
         "center_y_px: 240\nx_m: 0\ny_m: 0\nheight_m: 0.5\nroll_deg: 0\npitch_deg: 10\nyaw_deg: 0\n";
  }
  try {
    CameraModel::load(path);
    FAIL() << "zero focal length accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("focal"), std::string::npos);
  }
  {
    std::ofstream f(path);
    f << "width_px: 640\n";
  }
  try {
    CameraModel::load(path);
    FAIL() << "missing keys accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("height_px"), std::string::npos);
  }
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace colorfree
