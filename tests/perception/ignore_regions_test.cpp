#include "colorfree/perception/ignore_regions.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "colorfree/perception/error.h"
#include "synthetic_field.h"

namespace colorfree {
namespace {

using test::renderScene;
using test::SyntheticScene;
using test::testCamera;

TEST(FieldBoundary, NeverAboveTheHorizon) {
  const CameraModel cam = testCamera(12);
  SyntheticScene scene;
  const GrayImage image = renderScene(cam, scene);
  const FieldBoundary b = FieldBoundaryDetector().run(image.view(), cam);
  ASSERT_EQ(b.boundary_y.size(), 640u);
  const double horizon = *cam.horizonY(320);
  EXPECT_NEAR(b.horizon_y[320], horizon, 1.0);
  for (int x = 0; x < 640; ++x) EXPECT_GE(b.boundary_y[x], b.horizon_y[x]);
}

TEST(FieldBoundary, FollowsWhereTheCarpetEnds) {
  // The carpet ends 3 m ahead; beyond it, the hall (brighter, strongly textured).
  const CameraModel cam = testCamera(12);
  SyntheticScene scene;
  scene.carpet_edge_m = 3.0;
  const GrayImage image = renderScene(cam, scene);
  const FieldBoundary b = FieldBoundaryDetector().run(image.view(), cam);
  // Row of the carpet's edge at the middle column.
  const double edge_row = cam.robotToPixel({3.0, 0, 0})->y();
  const double horizon = *cam.horizonY(320);
  ASSERT_GT(edge_row - horizon, 30);  // the test means something only if they are apart
  const FieldBoundaryParams p;
  EXPECT_NEAR(b.boundary_y[320], edge_row, p.block_height_px + p.margin_px + 1);
  EXPECT_GT(b.boundary_y[320], horizon + 15);
  EXPECT_FALSE(b.texture_points_px.empty());
}

TEST(FieldBoundary, AllCarpetReachesTheTopWhenLookingDown) {
  const CameraModel cam = testCamera(60);
  const GrayImage image = renderScene(cam, SyntheticScene{});
  const FieldBoundary b = FieldBoundaryDetector().run(image.view(), cam);
  for (int x = 0; x < 640; ++x) EXPECT_EQ(b.boundary_y[x], 0) << x;
}

TEST(FieldBoundary, BlackAndWhiteFramesKeepTheHorizon) {
  const CameraModel cam = testCamera(12);
  for (std::uint8_t v : {std::uint8_t{0}, std::uint8_t{255}}) {
    const GrayImage image(640, 480, v);
    const FieldBoundary b = FieldBoundaryDetector().run(image.view(), cam);
    for (int x = 0; x < 640; ++x) EXPECT_EQ(b.boundary_y[x], b.horizon_y[x]);
  }
}

CameraModel bottomCamera(double pitch_deg) {
  CameraPose pose;
  pose.x_m = 0.06;
  pose.height_m = 0.47;
  pose.pitch_rad = pitch_deg * 3.14159265358979323846 / 180;
  return CameraModel(CameraIntrinsics::fromHorizontalFov(320, 240, 60.9 * 3.14159265358979323846 / 180), pose);
}

TEST(FieldBoundary, BlockStatsAreTheSamplesMeanAndSpread) {
  // Every or every other pixel and row, blocks of 16 and 32 pixels (summed 16 at a time) and
  // others (summed one by one), against the samples' mean and standard deviation.
  const GrayImage image = test::noiseImage(640, 480, 120, 60, 11);
  for (int step : {1, 2, 3}) {
    for (int bw : {8, 16, 32, 24}) {
      for (int x0 : {0, 16, 7, 601}) {
        const int y0 = 3 + x0 % 50, x1 = std::min(640, x0 + bw), y1 = y0 + 8;
        double sum = 0, sq = 0;
        int n = 0;
        for (int y = y0; y < y1; y += step) {
          for (int x = x0; x < x1; x += step) sum += image.at(x, y), sq += image.at(x, y) * image.at(x, y), ++n;
        }
        const double mean = sum / n;
        const BlockStats s = blockStats(image.view(), x0, y0, x1, y1, step);
        EXPECT_EQ(s.mean, static_cast<float>(mean)) << step << " " << bw << " " << x0;
        EXPECT_EQ(s.spread, static_cast<float>(std::sqrt(std::max(0.0, sq / n - mean * mean))))
            << step << " " << bw << " " << x0;
      }
    }
  }
  const GrayImage white(64, 64, 255);
  EXPECT_EQ(blockStats(white.view(), 0, 0, 64, 64, 1).mean, 255.f);
  EXPECT_EQ(blockStats(white.view(), 0, 0, 64, 64, 2).spread, 0.f);
  EXPECT_EQ(blockStats(white.view(), 5, 5, 5, 9, 2).mean, 0.f);
}

TEST(BodyContour, BottomCameraSeesTheFeet) {
  const CameraModel cam = bottomCamera(70);
  const BodyModelParams p;
  const BodyContour body = BodyContourProvider(p).run(cam);
  ASSERT_EQ(body.top_y.size(), 320u);
  ASSERT_FALSE(body.polygons_px.empty());
  // The toe of each foot, just inside the box, lies in the masked part of the image.
  for (double side : {-1.0, 1.0}) {
    const Eigen::Vector3d toe(p.foot_centre_x_m + p.foot_length_m / 2 - 0.01, side * p.feet_separation_m / 2,
                              p.foot_height_m);
    const auto px = cam.robotToPixel(toe);
    ASSERT_TRUE(px);
    ASSERT_GE(px->x(), 0);
    ASSERT_LT(px->x(), 320);
    EXPECT_GE(px->y(), body.top_y[static_cast<int>(px->x())]);
  }
  // Ground 30 cm in front of the feet is not masked.
  const auto free_px = cam.robotToPixel({p.foot_centre_x_m + p.foot_length_m / 2 + 0.3, 0, 0});
  if (free_px && free_px->y() >= 0 && free_px->y() < 240) {
    EXPECT_LT(free_px->y(), body.top_y[static_cast<int>(free_px->x())]);
  }
}

TEST(BodyContour, TopCameraLookingAheadSeesNoBody) {
  const BodyContour body = BodyContourProvider().run(testCamera(20));
  for (int y : body.top_y) EXPECT_EQ(y, 480);
}

TEST(IgnoreMask, CombinesBoundaryAndBody) {
  FieldBoundary b;
  b.boundary_y.assign(4, 1);
  BodyContour body;
  body.top_y = {3, 3, 2, 4};
  const IgnoreMask m = IgnoreMask::combine(b, body, 4, 4);
  EXPECT_FALSE(m.looked(0, 0));
  EXPECT_TRUE(m.looked(0, 1));
  EXPECT_FALSE(m.looked(0, 3));
  EXPECT_FALSE(m.looked(2, 2));
  EXPECT_TRUE(m.looked(3, 3));
  body.top_y.resize(3);
  EXPECT_THROW(IgnoreMask::combine(b, body, 4, 4), Error);
}

}  // namespace
}  // namespace colorfree
