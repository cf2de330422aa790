#include "colorfree/sim/camera_effects.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "colorfree/perception/error.h"

namespace colorfree::sim {
namespace {

FloatImage flat(int w, int h, float value) {
  FloatImage f;
  f.width = w;
  f.height = h;
  f.pixels.assign(static_cast<std::size_t>(w) * h, value);
  return f;
}

struct Stats {
  double mean = 0;
  double variance = 0;
};
Stats stats(const GrayImage& g) {
  Stats s;
  for (std::uint8_t v : g.pixels()) s.mean += v;
  s.mean /= static_cast<double>(g.pixels().size());
  for (std::uint8_t v : g.pixels()) s.variance += (v - s.mean) * (v - s.mean);
  s.variance /= static_cast<double>(g.pixels().size() - 1);
  return s;
}

TEST(CameraEffectsTest, NoEffectsRoundsOnly) {
  FloatImage f = flat(4, 2, 10.4f);
  f.pixels[3] = 10.6f;
  const GrayImage g = applySensor(f, EffectsSpec{}, 1);
  EXPECT_EQ(g.at(0, 0), 10);
  EXPECT_EQ(g.at(3, 0), 11);
}

TEST(CameraEffectsTest, GainScalesAndClips) {
  FloatImage f = flat(3, 1, 0);
  f.pixels = {40, 100, 200};
  EffectsSpec e;
  e.gain = 2;
  const GrayImage g = applySensor(f, e, 1);
  EXPECT_EQ(g.at(0, 0), 80);
  EXPECT_EQ(g.at(1, 0), 200);
  EXPECT_EQ(g.at(2, 0), 255);
  e.gain = 0.5;
  EXPECT_EQ(applySensor(f, e, 1).at(2, 0), 100);
}

TEST(CameraEffectsTest, GaussianNoiseHasTheAskedSigmaAndNoBias) {
  EffectsSpec e;
  e.noise_sigma = 4;
  const GrayImage g = applySensor(flat(200, 200, 100), e, 42);
  const Stats s = stats(g);
  // 40000 samples: the standard error of the mean is 0.02, of the variance about 0.11.
  EXPECT_NEAR(s.mean, 100, 0.1);
  EXPECT_NEAR(s.variance, 16 + 1.0 / 12, 0.6);  // + rounding
}

TEST(CameraEffectsTest, ShotNoiseGrowsWithBrightness) {
  EffectsSpec e;
  e.shot_noise = 0.5;
  const Stats dark = stats(applySensor(flat(200, 200, 20), e, 7));
  const Stats bright = stats(applySensor(flat(200, 200, 180), e, 7));
  EXPECT_NEAR(dark.variance, 0.5 * 20 + 1.0 / 12, 0.5);
  EXPECT_NEAR(bright.variance, 0.5 * 180 + 1.0 / 12, 3.5);
  EXPECT_NEAR(bright.mean, 180, 0.2);
}

TEST(CameraEffectsTest, NoiseIsFixedBySeed) {
  EffectsSpec e;
  e.noise_sigma = 3;
  const FloatImage f = flat(64, 48, 128);
  EXPECT_EQ(applySensor(f, e, 9).pixels(), applySensor(f, e, 9).pixels());
  EXPECT_NE(applySensor(f, e, 9).pixels(), applySensor(f, e, 10).pixels());
  EXPECT_NE(frameSeed(1, 0), frameSeed(1, 1));
  EXPECT_NE(frameSeed(1, 0), frameSeed(2, 0));
  EXPECT_EQ(frameSeed(3, 4), frameSeed(3, 4));
}

TEST(CameraEffectsTest, RejectsNegativeOrNanSettings) {
  EffectsSpec e;
  e.gain = std::nan("");
  EXPECT_THROW(applySensor(flat(2, 2, 1), e, 1), Error);
  e.gain = 1;
  e.noise_sigma = -1;
  EXPECT_THROW(applySensor(flat(2, 2, 1), e, 1), Error);
}

TEST(CameraEffectsTest, WithoutBlurOrRollingShutterOneInstantRender) {
  const ExposurePlan plan(EffectsSpec{}, 10);
  EXPECT_TRUE(plan.isInstant());
  EffectsSpec exposure_only;
  exposure_only.exposure_s = 0.02;  // no sub-frames asked: no blur
  EXPECT_TRUE(ExposurePlan(exposure_only, 10).isInstant());
}

TEST(CameraEffectsTest, BlurAveragesSubframesSpreadOverTheExposure) {
  EffectsSpec e;
  e.exposure_s = 0.02;
  e.blur_subframes = 4;
  const ExposurePlan plan(e, 3);
  ASSERT_EQ(plan.subframeTimes().size(), 4u);
  const double expected[] = {-0.0075, -0.0025, 0.0025, 0.0075};
  for (int j = 0; j < 4; ++j) EXPECT_NEAR(plan.subframeTimes()[j], expected[j], 1e-12);
  std::vector<GrayImage> subs;
  for (int j = 0; j < 4; ++j) subs.emplace_back(2, 3, static_cast<std::uint8_t>(10 + 20 * j));
  // A moving edge: pixel (1, 1) is bright in the first sub-frame only.
  subs[0].at(1, 1) = 250;
  const FloatImage f = composeSubframes(subs, plan);
  EXPECT_NEAR(f.at(0, 0), (10 + 30 + 50 + 70) / 4.0, 1e-4);
  EXPECT_NEAR(f.at(1, 1), (250 + 30 + 50 + 70) / 4.0, 1e-4);
}

TEST(CameraEffectsTest, RollingShutterExposesRowsTopToBottom) {
  EffectsSpec e;
  e.rolling_shutter = true;
  e.readout_s = 0.03;
  e.rolling_shutter_bands = 3;
  const ExposurePlan plan(e, 6);
  ASSERT_EQ(plan.subframeTimes().size(), 3u);
  EXPECT_NEAR(plan.subframeTimes()[0], -0.01, 1e-12);
  EXPECT_NEAR(plan.subframeTimes()[2], 0.01, 1e-12);
  std::vector<GrayImage> subs;
  for (int j = 0; j < 3; ++j) subs.emplace_back(1, 6, static_cast<std::uint8_t>(100 * j));
  const FloatImage f = composeSubframes(subs, plan);
  // Two rows per band: the top band from the earliest render, the bottom from the latest.
  const float expected[] = {0, 0, 100, 100, 200, 200};
  for (int y = 0; y < 6; ++y) EXPECT_FLOAT_EQ(f.at(0, y), expected[y]) << y;
}

TEST(CameraEffectsTest, RollingShutterWithBlurWeightsRowsByOverlap) {
  EffectsSpec e;
  e.rolling_shutter = true;
  e.readout_s = 0.02;
  e.exposure_s = 0.01;
  e.blur_subframes = 2;
  e.rolling_shutter_bands = 1;
  const ExposurePlan plan(e, 4);
  // span 30 ms in 5 ms sub-frames.
  ASSERT_EQ(plan.subframeTimes().size(), 6u);
  for (int y = 0; y < 4; ++y) {
    double sum = 0, mean_time = 0;
    for (const auto& [j, w] : plan.rowWeights(y)) {
      sum += w;
      mean_time += w * plan.subframeTimes()[static_cast<std::size_t>(j)];
    }
    EXPECT_NEAR(sum, 1.0, 1e-6);
    // Row centres at -7.5, -2.5, 2.5, 7.5 ms.
    EXPECT_NEAR(mean_time, 0.02 * ((y + 0.5) / 4 - 0.5), 1e-6) << y;
  }
}

TEST(CameraEffectsTest, SmearTurnsSubframeCopiesIntoOneContinuousStreak) {
  // Four sub-frame copies of a bright point, 6 px apart (what composeSubframes makes of a camera
  // turning 6 px per sub-frame): after the smear, one even streak from x = 17 to 41, no gaps.
  FloatImage comb = flat(60, 9, 0.0f);
  for (int k = 0; k < 4; ++k) comb.pixels[4 * 60 + 20 + 6 * k] = 100.0f;
  const FloatImage s = smearAlong(comb, 6.0, 0.0);
  double total = 0;
  for (float v : s.pixels) total += v;
  EXPECT_NEAR(total, 400.0, 1e-3);  // nothing lost, nothing added
  for (int x = 18; x <= 40; ++x) {
    EXPECT_NEAR(s.at(x, 4), 400.0 / 24.0, 4.0) << "x = " << x;  // even: no ghost left
  }
  for (int x = 0; x < 60; ++x) {
    if (x < 16 || x > 42) {
      EXPECT_EQ(s.at(x, 4), 0.0f) << "x = " << x;  // no longer than the motion
    }
    EXPECT_EQ(s.at(x, 3), 0.0f);                                        // and only along it
    EXPECT_EQ(s.at(x, 5), 0.0f);
  }
  // Along a diagonal step the streak runs diagonally.
  FloatImage dot = flat(30, 30, 0.0f);
  dot.pixels[15 * 30 + 15] = 100.0f;
  const FloatImage d = smearAlong(dot, 6.0, 6.0);
  EXPECT_GT(d.at(17, 17), 5.0f);
  EXPECT_GT(d.at(13, 13), 5.0f);
  EXPECT_EQ(d.at(17, 13), 0.0f);
  // Under a pixel nothing changes; a NaN step is an error.
  EXPECT_EQ(smearAlong(comb, 0.6, 0.3).pixels, comb.pixels);
  EXPECT_THROW(smearAlong(comb, std::nan(""), 0.0), Error);
}

TEST(CameraEffectsTest, DefocusSpreadsAPointAsAGaussianAndGlareFlattensContrast) {
  // A point of 1000 through a lens of sigma 2 px: the light is kept, spread as exp(-r^2 / 8).
  FloatImage dot = flat(41, 41, 0.0f);
  dot.pixels[20 * 41 + 20] = 1000.0f;
  EffectsSpec e;
  e.defocus_px = 2.0;
  const FloatImage b = applyOptics(dot, e);
  double total = 0;
  for (float v : b.pixels) total += v;
  EXPECT_NEAR(total, 1000.0, 1e-2);
  const double peak = 1000.0 / (2 * std::numbers::pi * 4);
  EXPECT_NEAR(b.at(20, 20), peak, 0.02 * peak);
  EXPECT_NEAR(b.at(22, 20), peak * std::exp(-0.5), 0.02 * peak);  // one sigma in x ...
  EXPECT_NEAR(b.at(20, 24), peak * std::exp(-2.0), 0.02 * peak);  // ... two in y
  EXPECT_NEAR(b.at(22, 22), peak * std::exp(-1.0), 0.02 * peak);  // separable
  EXPECT_EQ(b.at(20, 29), 0.0f);  // beyond the kernel's 3 sigma nothing
  // Glare: black lifts and white drops toward the mean, which stays; contrast x (1 - g).
  FloatImage step = flat(10, 2, 0.0f);
  for (int x = 5; x < 10; ++x) step.pixels[x] = step.pixels[10 + x] = 200.0f;
  EffectsSpec g;
  g.veiling_glare = 0.25;
  const FloatImage f = applyOptics(step, g);
  EXPECT_FLOAT_EQ(f.at(0, 0), 25.0f);
  EXPECT_FLOAT_EQ(f.at(9, 1), 175.0f);
  // Neither: the image unchanged; out of range or not finite: an error.
  EXPECT_EQ(applyOptics(step, EffectsSpec{}).pixels, step.pixels);
  e.defocus_px = -1;
  EXPECT_THROW(applyOptics(step, e), Error);
  e.defocus_px = std::nan("");
  EXPECT_THROW(applyOptics(step, e), Error);
  g.veiling_glare = 0.95;
  EXPECT_THROW(applyOptics(step, g), Error);
}

TEST(CameraEffectsTest, ComposeRejectsMismatchedSubframes) {
  EffectsSpec e;
  e.exposure_s = 0.01;
  e.blur_subframes = 2;
  const ExposurePlan plan(e, 4);
  EXPECT_THROW(composeSubframes({GrayImage(2, 4)}, plan), Error);
  EXPECT_THROW(composeSubframes({GrayImage(2, 4), GrayImage(3, 4)}, plan), Error);
  EXPECT_THROW(composeSubframes({GrayImage(2, 5), GrayImage(2, 5)}, plan), Error);
}

}  // namespace
}  // namespace colorfree::sim
