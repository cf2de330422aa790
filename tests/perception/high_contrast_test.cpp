#include "colorfree/perception/high_contrast.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

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

// In a dark frame the threshold follows the light: on a carpet of 40 (threshold 0.3 × 40 = 12) a
// window split 40 | 66 (contrast 13) is marked, and 40 | 60 (contrast 10) is not; with the
// absolute threshold only, neither. On a carpet of 100 (0.3 × 100 = 30: the absolute 22 holds) a
// window of contrast 20 is not marked, one of 25 is.
TEST(HighContrast, DarkFrameThresholdFollowsTheLight) {
  GrayImage image(640, 480, 40);
  for (int y = 160; y < 176; ++y) {
    for (int x = 160; x < 168; ++x) image.at(x, y) = 60;  // d = 20 → contrast 10
    for (int x = 320; x < 328; ++x) image.at(x, y) = 66;  // d = 26 → contrast 13
  }
  // (The light rule alone: this frame, with one window passing, is a sparse one; see below.)
  HighContrastParams shipped = HighContrastParams::loadDefault();
  ASSERT_DOUBLE_EQ(shipped.light_contrast_fraction, 0.3);
  shipped.sparse_max_seed_fraction = 0;
  const ContrastRegions r =
      HighContrastDetector(shipped).run(image.view(), IgnoreMask::all(640, 480));
  EXPECT_FALSE(r.seeds[10 * r.columns + 10]);
  EXPECT_TRUE(r.seeds[10 * r.columns + 20]);
  EXPECT_EQ(std::count(r.seeds.begin(), r.seeds.end(), 1), 1);
  HighContrastParams absolute = shipped;
  absolute.light_contrast_fraction = 0;
  EXPECT_EQ(
      HighContrastDetector(absolute).run(image.view(), IgnoreMask::all(640, 480)).markedCount(), 0);
  GrayImage bright(640, 480, 100);
  for (int y = 160; y < 176; ++y) {
    for (int x = 160; x < 168; ++x) bright.at(x, y) = 140;  // contrast 20
    for (int x = 320; x < 328; ++x) bright.at(x, y) = 150;  // contrast 25
  }
  const ContrastRegions b =
      HighContrastDetector(shipped).run(bright.view(), IgnoreMask::all(640, 480));
  EXPECT_FALSE(b.seeds[10 * b.columns + 10]);
  EXPECT_TRUE(b.seeds[10 * b.columns + 20]);
}

TEST(HighContrast, ASparseFrameIsMarkedWithTheLowerBar) {
  // A soft lens in a dim hall: two blurred blocks, 45 gray levels over carpet 50, their edges
  // ramps of 12 px. No 16-px window reaches the frame's bar (0.3 x 50 = 15; these edges give at
  // most some 14), so with the sparse rule the frame is marked at 0.2 x 50 = 10.
  GrayImage image(640, 480, 50);
  const auto block = [&](int x0, int y0, int x1, int y1) {
    for (int y = y0 - 6; y < y1 + 6; ++y) {
      for (int x = x0 - 6; x < x1 + 6; ++x) {
        const double fx = std::clamp(std::min(x - (x0 - 6), (x1 + 6) - x) / 12.0, 0.0, 1.0);
        const double fy = std::clamp(std::min(y - (y0 - 6), (y1 + 6) - y) / 12.0, 0.0, 1.0);
        image.at(x, y) = static_cast<std::uint8_t>(std::lround(50 + 45 * std::min(fx, fy)));
      }
    }
  };
  block(100, 100, 180, 300);
  block(400, 200, 440, 260);
  HighContrastParams p;
  p.light_contrast_fraction = 0.3;
  p.sparse_max_seed_fraction = 0;
  const IgnoreMask all = IgnoreMask::all(640, 480);
  EXPECT_EQ(HighContrastDetector(p).run(image.view(), all).markedCount(), 0);
  p.sparse_max_seed_fraction = 0.1;
  p.sparse_light_contrast_fraction = 0.2;
  const ContrastRegions soft = HighContrastDetector(p).run(image.view(), all);
  EXPECT_GT(soft.markedCount(), 20);
  // Every seed lies on a block's edge, none on the carpet.
  for (int r = 0; r < soft.rows; ++r) {
    for (int c = 0; c < soft.columns; ++c) {
      if (!soft.seeds[r * soft.columns + c]) continue;
      const int x = c * 16 + 8, y = r * 16 + 8;
      const bool near_a = x > 72 && x < 208 && y > 72 && y < 328;
      const bool near_b = x > 372 && x < 468 && y > 172 && y < 288;
      EXPECT_TRUE(near_a || near_b) << "seed at window " << c << ", " << r;
    }
  }
  // A sharp frame with the same blocks has windows enough: the rule leaves it as it is.
  GrayImage sharp(640, 480, 50);
  for (int y = 100; y < 300; ++y) {
    for (int x = 100; x < 180; ++x) sharp.at(x, y) = 90;
  }
  for (int y = 40; y < 480; y += 100) {  // rows of dots: windows enough
    for (int k = 0; k < 200; ++k) sharp.at(20 + 3 * k, y) = 200;
  }
  HighContrastParams off = p;
  off.sparse_max_seed_fraction = 0;
  const ContrastRegions a = HighContrastDetector(p).run(sharp.view(), all);
  const ContrastRegions b = HighContrastDetector(off).run(sharp.view(), all);
  ASSERT_GE(std::count(b.seeds.begin(), b.seeds.end(), 1), 0.1 * b.seeds.size());
  EXPECT_EQ(a.seeds, b.seeds);
  EXPECT_EQ(a.contrast, b.contrast);
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
  p.sparse_max_seed_fraction = 0;  // (two windows of 1200 would make it a sparse frame)
  const ContrastRegions r = HighContrastDetector(p).run(image.view(), IgnoreMask::all(640, 480));
  EXPECT_FALSE(r.seeds[10 * r.columns + 10]);
  EXPECT_TRUE(r.seeds[10 * r.columns + 20]);
  EXPECT_NEAR(r.contrast[10 * r.columns + 20], 25, 1e-4);
}

}  // namespace
}  // namespace colorfree

namespace colorfree {
namespace {

// The detector as the paper describes it, one window at a time with no shortcuts: the window's
// samples (every row_step-th row), their variance as the pre-test, a 32-bin histogram, Otsu,
// dilation, 8-connected regions. The fast detector must give the same windows, contrasts and
// regions (the ball and robot proposals read its mask).
ContrastRegions referenceContrast(const GrayView& image, const IgnoreMask& ignore, const HighContrastParams& p) {
  const int s = p.window_px;
  ContrastRegions out;
  out.window_px = s;
  out.columns = image.width / s;
  out.rows = image.height / s;
  const std::size_t n = static_cast<std::size_t>(out.columns) * out.rows;
  out.seeds.assign(n, 0);
  out.mask.assign(n, 0);
  out.contrast.assign(n, 0.f);
  // The light: the median of every 4th pixel of every 4th row, looked-at ones (all if none are).
  double light = 0;
  if (p.light_contrast_fraction > 0 || p.sparse_max_seed_fraction > 0) {
    std::vector<int> looked, every;
    for (int y = 2; y < image.height; y += 4) {
      for (int x = 2; x < image.width; x += 4) {
        every.push_back(image.at(x, y));
        if (ignore.looked(x, y)) looked.push_back(image.at(x, y));
      }
    }
    std::vector<int>& v = looked.empty() ? every : looked;
    std::sort(v.begin(), v.end());
    light = v[(v.size() - 1) / 2];
  }
  const auto bar = [&](double fraction) {
    return fraction > 0 ? std::min(p.min_contrast, std::max(p.light_min_contrast, fraction * light))
                        : p.min_contrast;
  };
  double min_contrast = bar(p.light_contrast_fraction);
  // A sparse frame (few windows pass): the whole frame again with the lower bar.
  int looked = 0, passed = 0;
  for (int r = 0; r < out.rows; ++r) {
    for (int c = 0; c < out.columns; ++c) looked += ignore.looked(c * s + s / 2, r * s + s / 2);
  }
  for (bool again = true; again;) {
    again = false;
    std::fill(out.seeds.begin(), out.seeds.end(), 0);
    std::fill(out.contrast.begin(), out.contrast.end(), 0.f);
    passed = 0;
    for (int r = 0; r < out.rows; ++r) {
      for (int c = 0; c < out.columns; ++c) {
        if (!ignore.looked(c * s + s / 2, r * s + s / 2)) continue;
        std::vector<int> samples;
        for (int y = r * s; y < (r + 1) * s; y += p.row_step_px) {
          for (int x = c * s; x < (c + 1) * s; ++x) samples.push_back(image.at(x, y));
        }
        double sum = 0, sq = 0;
        for (int v : samples) sum += v, sq += v * v;
        const double mean = sum / samples.size();
        if (sq / samples.size() - mean * mean < min_contrast * min_contrast) continue;
        std::uint32_t count[32] = {}, value_sum[32] = {};
        for (int v : samples) ++count[v / 8], value_sum[v / 8] += v;
        const OtsuResult o = otsuBinned(count, value_sum, 32);
        out.contrast[r * out.columns + c] = static_cast<float>(o.between_std);
        out.seeds[r * out.columns + c] = o.between_std >= min_contrast;
        passed += o.between_std >= min_contrast;
      }
    }
    const double lower = std::min(min_contrast, bar(p.sparse_light_contrast_fraction));
    if (p.sparse_max_seed_fraction > 0 && lower < min_contrast &&
        passed < p.sparse_max_seed_fraction * looked) {
      min_contrast = lower;
      again = true;
    }
  }
  const int d = p.dilation_windows;
  for (int r = 0; r < out.rows; ++r) {
    for (int c = 0; c < out.columns; ++c) {
      for (int rr = r - d; rr <= r + d; ++rr) {
        for (int cc = c - d; cc <= c + d; ++cc) {
          if (rr >= 0 && cc >= 0 && rr < out.rows && cc < out.columns && out.seeds[rr * out.columns + cc]) {
            out.mask[r * out.columns + c] = 1;
          }
        }
      }
    }
  }
  // Regions by repeated relabelling to the smallest label among 8 neighbours, numbered in the
  // order of their first window (row-major).
  std::vector<int> label(n, -1);
  for (std::size_t i = 0; i < n; ++i) label[i] = out.mask[i] ? static_cast<int>(i) : -1;
  for (bool changed = true; changed;) {
    changed = false;
    for (int r = 0; r < out.rows; ++r) {
      for (int c = 0; c < out.columns; ++c) {
        int& l = label[r * out.columns + c];
        if (l < 0) continue;
        for (int rr = std::max(0, r - 1); rr <= std::min(out.rows - 1, r + 1); ++rr) {
          for (int cc = std::max(0, c - 1); cc <= std::min(out.columns - 1, c + 1); ++cc) {
            const int other = label[rr * out.columns + cc];
            if (other >= 0 && other < l) l = other, changed = true;
          }
        }
      }
    }
  }
  std::vector<int> firsts;
  for (std::size_t i = 0; i < n; ++i) {
    if (label[i] == static_cast<int>(i)) firsts.push_back(static_cast<int>(i));
  }
  for (int first : firsts) {
    ContrastRegion region;
    int c0 = out.columns, c1 = -1, r0 = out.rows, r1 = -1;
    for (std::size_t i = 0; i < n; ++i) {
      if (label[i] != first) continue;
      ++region.window_count;
      const int r = static_cast<int>(i) / out.columns, c = static_cast<int>(i) % out.columns;
      c0 = std::min(c0, c), c1 = std::max(c1, c), r0 = std::min(r0, r), r1 = std::max(r1, r);
    }
    region.box = {double(c0 * s), double(r0 * s), double((c1 + 1) * s), double((r1 + 1) * s)};
    out.regions.push_back(region);
  }
  return out;
}

void expectSameRegions(const ContrastRegions& a, const ContrastRegions& b, const std::string& what) {
  ASSERT_EQ(a.columns, b.columns) << what;
  ASSERT_EQ(a.rows, b.rows) << what;
  EXPECT_EQ(a.seeds, b.seeds) << what;
  EXPECT_EQ(a.mask, b.mask) << what;
  EXPECT_EQ(a.contrast, b.contrast) << what;
  ASSERT_EQ(a.regions.size(), b.regions.size()) << what;
  for (std::size_t i = 0; i < a.regions.size(); ++i) {
    EXPECT_EQ(a.regions[i].window_count, b.regions[i].window_count) << what << " region " << i;
    EXPECT_EQ(a.regions[i].box.x0, b.regions[i].box.x0) << what << " region " << i;
    EXPECT_EQ(a.regions[i].box.y0, b.regions[i].box.y0) << what << " region " << i;
    EXPECT_EQ(a.regions[i].box.x1, b.regions[i].box.x1) << what << " region " << i;
    EXPECT_EQ(a.regions[i].box.y1, b.regions[i].box.y1) << what << " region " << i;
  }
}

TEST(HighContrast, SameAsTheStraightforwardDetector) {
  // Field frames with lines, noise and gradients; blobs on noise; odd window sizes and steps;
  // a field boundary and a body cut-out.
  std::vector<std::pair<std::string, GrayImage>> images;
  for (int i = 0; i < 3; ++i) {
    test::SyntheticScene scene = test::sceneFromField(FieldDimensions{}, {-2.0 + 1.7 * i, 0.4 * i, 0.5 * i});
    scene.pixel_noise = 4 + 6 * i;
    scene.gradient = 0.3 * i;
    scene.seed = 20 + i;
    images.emplace_back("field " + std::to_string(i), test::renderScene(test::testCamera(18 + 4 * i), scene));
  }
  {
    // A dark hall: the light-relative threshold is below the absolute one.
    test::SyntheticScene dark = test::sceneFromField(FieldDimensions{}, {-1.0, 0.2, 0.3});
    dark.carpet = 30;
    dark.paint = 75;
    dark.background = 45;
    dark.texture = 3;
    dark.pixel_noise = 2;
    dark.seed = 9;
    images.emplace_back("dark field", test::renderScene(test::testCamera(22), dark));
  }
  GrayImage blobs = test::noiseImage(640, 480, 90, 20, 7);
  for (int k = 0; k < 12; ++k) drawBlob(blobs, 30 + 50 * k, 40 + 35 * k, 6 + k);
  images.emplace_back("blobs", std::move(blobs));
  IgnoreMask cut = IgnoreMask::all(640, 480);
  for (int x = 0; x < 640; ++x) {
    cut.top_y[x] = 60 + x / 8;
    cut.bottom_y[x] = x > 200 && x < 420 ? 400 : 480;
  }
  std::vector<HighContrastParams> params(6);
  params[1].row_step_px = 1;
  params[1].light_contrast_fraction = 0;
  params[5].light_contrast_fraction = 0.6, params[5].light_min_contrast = 12;
  params[2].window_px = 20, params[2].row_step_px = 3, params[2].dilation_windows = 2;
  params[3].window_px = 13, params[3].min_contrast = 10, params[3].dilation_windows = 0;
  params[4].window_px = 64, params[4].row_step_px = 1, params[4].min_contrast = 5;
  // The sparse-frame rule: on the dark field (few windows pass) and, with a high fraction,
  // everywhere.
  params.push_back(HighContrastParams{});
  params[6].sparse_max_seed_fraction = 0.1;
  params.push_back(HighContrastParams{});
  params[7].sparse_max_seed_fraction = 0.9, params[7].sparse_light_contrast_fraction = 0.1;
  params[7].window_px = 20;
  for (const auto& [name, image] : images) {
    for (std::size_t k = 0; k < params.size(); ++k) {
      for (bool with_cut : {true, false}) {
        const IgnoreMask m = with_cut ? cut : IgnoreMask::all(640, 480);
        expectSameRegions(HighContrastDetector(params[k]).run(image.view(), m),
                          referenceContrast(image.view(), m, params[k]),
                          name + " params " + std::to_string(k) + (with_cut ? " cut" : ""));
      }
    }
  }
}

}  // namespace
}  // namespace colorfree
