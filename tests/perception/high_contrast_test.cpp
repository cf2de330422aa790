#include "colorfree/perception/high_contrast.h"

#include <gtest/gtest.h>

#include <cmath>

#include "colorfree/perception/error.h"
#include "synthetic_field.h"

namespace colorfree {
namespace {

TEST(Otsu, SplitsTwoModesBetweenThem) {
  std::uint32_t hist[256] = {};
  hist[40] = 192;   // w0 = 0.75
  hist[200] = 64;   // w1 = 0.25
  const OtsuResult o = otsu(hist);
  EXPECT_GE(o.threshold, 40);
  EXPECT_LT(o.threshold, 200);
  EXPECT_DOUBLE_EQ(o.mean0, 40);
  EXPECT_DOUBLE_EQ(o.mean1, 200);
  EXPECT_NEAR(o.between_std, std::sqrt(0.75 * 0.25) * 160, 1e-9);
}

TEST(Otsu, SingleValueHasNoContrast) {
  std::uint32_t hist[256] = {};
  hist[77] = 256;
  EXPECT_EQ(otsu(hist).between_std, 0);
}

GrayImage carpet(std::uint64_t seed) { return test::noiseImage(640, 480, 80, 6, seed); }

// A ball-like blob: a bright disc with dark patches, centred at (cx, cy).
void drawBlob(GrayImage& image, int cx, int cy, int radius) {
  for (int y = cy - radius; y <= cy + radius; ++y) {
    for (int x = cx - radius; x <= cx + radius; ++x) {
      const int dx = x - cx, dy = y - cy;
      if (dx * dx + dy * dy > radius * radius) continue;
      const bool patch = ((dx + radius) / 6 + (dy + radius) / 6) % 2 == 0;
      image.at(x, y) = patch ? 20 : 230;
    }
  }
}

TEST(HighContrast, FindsABlobAndOnlyAroundIt) {
  GrayImage image = carpet(3);
  drawBlob(image, 300, 250, 14);
  const ContrastRegions r =
      HighContrastDetector().run(image.view(), IgnoreMask::all(640, 480));
  ASSERT_EQ(r.columns, 40);
  ASSERT_EQ(r.rows, 30);
  // The blob's own window is a seed.
  EXPECT_TRUE(r.seeds[(250 / 16) * r.columns + 300 / 16]);
  ASSERT_EQ(r.regions.size(), 1u);
  const PixelBox& box = r.regions[0].box;
  EXPECT_LE(box.x0, 300 - 14);
  EXPECT_GE(box.x1, 300 + 14);
  EXPECT_LE(box.y0, 250 - 14);
  EXPECT_GE(box.y1, 250 + 14);
  // Dilated by one window around the seeds, nothing far away.
  EXPECT_LE(box.width(), 5 * 16);
  EXPECT_LE(box.height(), 5 * 16);
  for (int row = 0; row < r.rows; ++row) {
    for (int col = 0; col < r.columns; ++col) {
      if (std::abs(col * 16 + 8 - 300) > 48 || std::abs(row * 16 + 8 - 250) > 48) {
        EXPECT_FALSE(r.marked(col, row)) << col << "," << row;
      }
    }
  }
  // A seed's neighbours are marked by the dilation.
  for (int row = 0; row < r.rows; ++row) {
    for (int col = 0; col < r.columns; ++col) {
      if (!r.seeds[row * r.columns + col]) continue;
      for (int dr = -1; dr <= 1; ++dr) {
        for (int dc = -1; dc <= 1; ++dc) {
          EXPECT_TRUE(r.marked(std::clamp(col + dc, 0, r.columns - 1), std::clamp(row + dr, 0, r.rows - 1)));
        }
      }
    }
  }
}

TEST(HighContrast, NothingOnFlatOrNoisyCarpet) {
  const HighContrastDetector detector;
  for (std::uint64_t seed : {1u, 2u, 3u}) {
    const GrayImage image = carpet(seed);
    EXPECT_EQ(detector.run(image.view(), IgnoreMask::all(640, 480)).markedCount(), 0) << seed;
  }
  // The textured carpet of the synthetic field, with an illumination gradient, no markings.
  test::SyntheticScene scene;
  scene.gradient = 0.5;
  const GrayImage textured = test::renderScene(test::testCamera(30), scene);
  EXPECT_EQ(detector.run(textured.view(), IgnoreMask::all(640, 480)).markedCount(), 0);
  for (std::uint8_t v : {std::uint8_t{0}, std::uint8_t{128}, std::uint8_t{255}}) {
    const GrayImage flat(640, 480, v);
    EXPECT_EQ(detector.run(flat.view(), IgnoreMask::all(640, 480)).markedCount(), 0);
  }
}

TEST(HighContrast, IgnoredWindowsAreNotLookedAt) {
  GrayImage image = carpet(4);
  drawBlob(image, 300, 40, 14);  // above the field boundary
  IgnoreMask mask = IgnoreMask::all(640, 480);
  std::fill(mask.top_y.begin(), mask.top_y.end(), 100);
  const ContrastRegions r = HighContrastDetector().run(image.view(), mask);
  EXPECT_EQ(r.markedCount(), 0);
  mask.width = 320;
  EXPECT_THROW(HighContrastDetector().run(image.view(), mask), Error);
}

TEST(HighContrast, ContrastThresholdDecides) {
  // Two halves of a window differing by d: between-class std = d / 2.
  GrayImage image(640, 480, 100);
  for (int y = 160; y < 176; ++y) {
    for (int x = 160; x < 168; ++x) image.at(x, y) = 140;  // d = 40 → contrast 20
    for (int x = 320; x < 328; ++x) image.at(x, y) = 150;  // d = 50 → contrast 25
  }
  HighContrastParams p;
  p.min_contrast = 22;
  const ContrastRegions r = HighContrastDetector(p).run(image.view(), IgnoreMask::all(640, 480));
  EXPECT_FALSE(r.seeds[10 * r.columns + 10]);
  EXPECT_TRUE(r.seeds[10 * r.columns + 20]);
  EXPECT_NEAR(r.contrast[10 * r.columns + 20], 25, 1e-4);
}

}  // namespace
}  // namespace colorfree
