// Darknet cfg/weights reading and writing, the shipped nets' sizes, bad model files, patches.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "colorfree/perception/cnn/classifier.h"
#include "colorfree/perception/cnn/net.h"
#include "colorfree/perception/cnn/patch.h"
#include "colorfree/perception/error.h"
#include "test_support.h"

namespace colorfree::cnn {
namespace {

std::string model(const std::string& name) { return defaultModelDir() + "/" + name; }

// Named after the running test too: CTest runs the tests of this file as parallel processes,
// which must not share /tmp/bad.cfg (one renamed the other's bad.cfg.tmp away).
std::string tempPath(const std::string& name) {
  const ::testing::TestInfo* t = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string prefix = t ? std::string(t->test_suite_name()) + "." + t->name() + "." : "";
  return ::testing::TempDir() + "/" + prefix + name;
}

void writeText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// Expects a colorfree::Error whose message contains every one of `parts`.
template <typename F>
void expectError(F&& f, std::initializer_list<std::string> parts) {
  try {
    f();
    ADD_FAILURE() << "no colorfree::Error thrown";
  } catch (const Error& e) {
    for (const auto& p : parts)
      EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
  }
}

struct PaperNet {
  const char* file;
  int input_side;
  int classes;
  int paper_params;
};

constexpr PaperNet kPaperNets[] = {
    {"robot_net.cfg", 24, 2, 884}, {"boost_ball_net.cfg", 12, 2, 125},
    {"ball_net.cfg", 26, 2, 444},  {"ori_boost_net.cfg", 12, 2, 246},
    {"ori_net.cfg", 24, 4, 657},  // front, back, side facing left, side facing right
};

TEST(CnnNet, ShippedNetsHaveThePapersSizesAndParameterCounts) {
  for (const PaperNet& p : kPaperNets) {
    SCOPED_TRACE(p.file);
    const Net net = readDarknetCfg(model(p.file));
    EXPECT_EQ(net.input(), (Shape{p.input_side, p.input_side, 1}));
    EXPECT_EQ(net.classes(), p.classes);
    // Within 6 % of the paper's count (the architectures are rebuilt from the paper's description).
    const double ratio = static_cast<double>(net.parameterCount()) / p.paper_params;
    EXPECT_GT(ratio, 0.94) << net.parameterCount();
    EXPECT_LT(ratio, 1.06) << net.parameterCount();
    // Extended Fire modules: at least one route concatenating two or more branches.
    bool has_fire = false;
    for (const Layer& l : net.layers())
      has_fire |= l.type == LayerType::kRoute && l.inputs.size() >= 2;
    EXPECT_TRUE(has_fire);
    EXPECT_EQ(net.layers().back().type, LayerType::kSoftmax);
  }
}

TEST(CnnNet, ParameterCountOfAHandCountedNet) {
  // conv 3x3 1->4: 4*(9+1)=40; route; conv 1x1 4->2 on 8x8: 2*(4+1)=10; connected 2*4*4 -> 3:
  // 3*(32+1)=99.
  const Net net = parseDarknetCfg(
      "[net]\nwidth=8\nheight=8\nchannels=1\n[convolutional]\nfilters=4\nsize=3\npad=1\n"
      "activation=leaky\n[convolutional]\nfilters=2\nsize=1\n[maxpool]\nsize=2\nstride=2\n"
      "[connected]\noutput=3\n[softmax]\n",
      "inline");
  EXPECT_EQ(net.parameterCount(), 40u + 10u + 99u);
  EXPECT_EQ(net.layers()[2].out, (Shape{4, 4, 2}));
  EXPECT_EQ(net.multiplyAdds(), 64 * 4 * 9 + 64 * 2 * 4 + 3 * 32);
}

TEST(CnnNet, CfgAndWeightsRoundTrip) {
  Net net = readDarknetCfg(model("robot_net.cfg"));
  net.initialise(3);
  writeDarknetCfg(net, tempPath("rt.cfg"));
  writeDarknetWeights(net, tempPath("rt.weights"));
  const Net back = readDarknet(tempPath("rt.cfg"), tempPath("rt.weights"));
  EXPECT_EQ(back.params(), net.params());
  EXPECT_EQ(darknetCfgText(back), darknetCfgText(net));
  EXPECT_EQ(back.normalization(), PatchNormalization::kStandardize);
  EXPECT_FALSE(std::filesystem::exists(tempPath("rt.weights.tmp")));
}

TEST(CnnNet, TheCfgNamesTheResamplingAndTheNormalization) {
  const std::string layers = "[net]\nwidth=4\nheight=4\nchannels=1\n[connected]\noutput=2\n";
  EXPECT_EQ(parseDarknetCfg(layers, "plain").resampling(), PatchResampling::kBilinear);
  Net area = parseDarknetCfg("# colorfree resampling=area\n" + layers, "area");
  EXPECT_EQ(area.resampling(), PatchResampling::kArea);
  EXPECT_EQ(parseDarknetCfg(darknetCfgText(area), "written").resampling(), PatchResampling::kArea);
  EXPECT_EQ(parseDarknetCfg("# colorfree resampling=bilinear\n" + layers, "b").resampling(),
            PatchResampling::kBilinear);
  expectError([&] { parseDarknetCfg("# colorfree resampling=cubic\n" + layers, "cubic.cfg"); },
              {"cubic.cfg:1", "unknown resampling 'cubic' (bilinear, area)"});
  expectError([&] { parseDarknetCfg("\n# colorfree normalization=foo\n" + layers, "foo.cfg"); },
              {"foo.cfg:2", "unknown normalization 'foo' (standardize, unit)"});
}

TEST(CnnNet, InitialisationIsSeeded) {
  Net a = readDarknetCfg(model("ori_net.cfg")), b = a, c = a;
  a.initialise(7);
  b.initialise(7);
  c.initialise(8);
  EXPECT_EQ(a.params(), b.params());
  EXPECT_NE(a.params(), c.params());
}

class CnnBadFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    net_ = readDarknetCfg(model("boost_ball_net.cfg"));
    net_.initialise(1);
    writeDarknetCfg(net_, cfg_);
    writeDarknetWeights(net_, weights_);
  }
  Net net_;
  std::string cfg_ = tempPath("bad.cfg");
  std::string weights_ = tempPath("bad.weights");
};

TEST_F(CnnBadFiles, TruncatedWeights) {
  std::filesystem::resize_file(weights_, std::filesystem::file_size(weights_) - 6);
  expectError([&] { readDarknet(cfg_, weights_); }, {weights_, "truncated"});
  std::filesystem::resize_file(weights_, 10);
  expectError([&] { readDarknet(cfg_, weights_); }, {weights_, "truncated"});
}

TEST_F(CnnBadFiles, WeightsOfAnotherNet) {
  // BallNet's cfg with BoostBallNet's weights: more parameters needed than present.
  expectError([&] { readDarknet(model("ball_net.cfg"), weights_); }, {weights_, "truncated"});
  // And the other way round: the file holds more than the cfg needs.
  Net big = readDarknetCfg(model("ball_net.cfg"));
  writeDarknetWeights(big, tempPath("big.weights"));
  expectError([&] { readDarknet(cfg_, tempPath("big.weights")); },
              {tempPath("big.weights"), "do not match"});
}

TEST_F(CnnBadFiles, NonFiniteWeight) {
  net_.params()[5] = std::nanf("");
  writeDarknetWeights(net_, weights_);
  expectError([&] { readDarknet(cfg_, weights_); }, {weights_, "weight 5", "finite"});
}

TEST_F(CnnBadFiles, UnknownLayerAndKeys) {
  writeText(cfg_, "[net]\nwidth=8\nheight=8\nchannels=1\n[shortcut]\nfrom=-3\n");
  expectError([&] { readDarknetCfg(cfg_); }, {cfg_ + ":5", "[shortcut]", "not supported"});
  writeText(cfg_,
            "[net]\nwidth=8\nheight=8\nchannels=1\n[convolutional]\nfilters=2\nsize=3\nflip=1\n");
  expectError([&] { readDarknetCfg(cfg_); }, {cfg_ + ":8", "flip"});
  writeText(cfg_,
            "[net]\nwidth=8\nheight=8\nchannels=1\n[convolutional]\nfilters=2\nactivation=mish\n");
  expectError([&] { readDarknetCfg(cfg_); }, {cfg_, "mish"});
  writeText(cfg_, "[net]\nwidth=8\nheight=8\nchannels=1\n[convolutional]\nfilters=x2\n");
  expectError([&] { readDarknetCfg(cfg_); }, {cfg_ + ":6", "not an integer"});
  writeText(cfg_, "[net]\nwidth=8\nheight=8\nchannels=1\n[convolutional]\nfilters=2\nsize=11\n");
  expectError([&] { readDarknetCfg(cfg_); }, {cfg_, "larger than"});
  writeText(cfg_, "[net]\nwidth=8\nheight=8\nchannels=1\n[route]\nlayers=-1\n");
  expectError([&] { readDarknetCfg(cfg_); }, {cfg_, "route"});
  writeText(cfg_, "[convolutional]\nfilters=2\n");
  expectError([&] { readDarknetCfg(cfg_); }, {cfg_, "[net]"});
  writeText(cfg_, "[net]\nwidth=8\nheight=8\nchannels=1\n[convolutional]\nbatch_normalize=1\n");
  expectError([&] { readDarknetCfg(cfg_); }, {cfg_, "batch_normalize"});
  expectError([&] { readDarknetCfg(tempPath("missing.cfg")); }, {"missing.cfg"});
}

TEST(CnnPatch, ExtractsAndNormalises) {
  GrayImage image(40, 30);
  for (int y = 0; y < 30; ++y) {
    for (int x = 0; x < 40; ++x) image.at(x, y) = static_cast<std::uint8_t>(x * 5);
  }
  // A box of 8x8 pixels sampled at 8x8: exact pixel values.
  float out[64];
  extractPatch(image.view(), {10, 5, 8, 8}, 8, 8, PatchNormalization::kUnitRange, out);
  for (int v = 0; v < 8; ++v) {
    for (int u = 0; u < 8; ++u) EXPECT_FLOAT_EQ(out[v * 8 + u], (10 + u) * 5 / 255.0f);
  }
  // Downscaled by two: samples between pixel pairs, a linear ramp stays linear.
  extractPatch(image.view(), {10, 5, 16, 16}, 8, 8, PatchNormalization::kUnitRange, out);
  EXPECT_FLOAT_EQ(out[0], (10.5f * 5) / 255.0f);
  EXPECT_FLOAT_EQ(out[7], (24.5f * 5) / 255.0f);
  // Standardised: zero mean, unit deviation, whatever the brightness.
  extractPatch(image.view(), {10, 5, 16, 16}, 8, 8, PatchNormalization::kStandardize, out);
  double sum = 0, sq = 0;
  for (float v : out) sum += v, sq += v * v;
  EXPECT_NEAR(sum / 64, 0.0, 1e-5);
  EXPECT_NEAR(sq / 64, 1.0, 1e-4);
  // Outside the image: the border repeats.
  extractPatch(image.view(), {-20, -20, 8, 8}, 8, 8, PatchNormalization::kUnitRange, out);
  EXPECT_FLOAT_EQ(out[63], 0.0f);
  // Past the right and bottom border: the last column repeats.
  extractPatch(image.view(), {35, 25, 8, 8}, 8, 8, PatchNormalization::kUnitRange, out);
  EXPECT_FLOAT_EQ(out[3], 38 * 5 / 255.0f);
  EXPECT_FLOAT_EQ(out[4], 39 * 5 / 255.0f);
  EXPECT_FLOAT_EQ(out[63], 39 * 5 / 255.0f);
  // A one-pixel-wide image.
  GrayImage column(1, 4, 100);
  extractPatch(column.view(), {0, 0, 1, 4}, 2, 2, PatchNormalization::kUnitRange, out);
  EXPECT_FLOAT_EQ(out[3], 100 / 255.0f);
  expectError(
      [&] {
        extractPatch(image.view(), {0, 0, 0, 8}, 8, 8, PatchNormalization::kUnitRange, out);
      },
      {"positive size"});
}

// The bilinear sample of extractPatch written out pixel by pixel (horizontal blend first, in
// 1/256 steps), before the scaling to 0..1.
float referenceSample(const GrayImage& image, const PatchBox& box, int width, int height, int u,
                      int v) {
  const float sx = box.width_px / width, sy = box.height_px / height;
  float x = std::clamp(box.x_px + (u + 0.5f) * sx - 0.5f, 0.0f, image.width() - 1.0f);
  const float y = std::clamp(box.y_px + (v + 0.5f) * sy - 0.5f, 0.0f, image.height() - 1.0f);
  int x0 = static_cast<int>(x);
  int fx = static_cast<int>((x - x0) * 256.0f + 0.5f);
  if (x0 + 1 >= image.width()) x0 = image.width() - 2, fx = 256;
  const int y0 = static_cast<int>(y), y1 = std::min(y0 + 1, image.height() - 1);
  const int fy = static_cast<int>((y - y0) * 256.0f + 0.5f);
  const auto at = [&](int xx, int yy) { return static_cast<int>(image.at(xx, yy)); };
  const int top = at(x0, y0) * 256 + (at(x0 + 1, y0) - at(x0, y0)) * fx;
  const int bottom = at(x0, y1) * 256 + (at(x0 + 1, y1) - at(x0, y1)) * fx;
  return static_cast<float>(top * 256 + (bottom - top) * fy) / 65536.0f;
}

TEST(CnnPatch, SameAsThePixelByPixelBilinearSample) {
  // Random pixels, boxes shrunk and enlarged, inside, across and beyond the borders, patch
  // widths with and without a remainder of the vector steps.
  GrayImage image(97, 61);
  std::mt19937 rng(11);
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) image.at(x, y) = static_cast<std::uint8_t>(rng());
  }
  std::uniform_real_distribution<float> pos(-30.0f, 110.0f), size(1.0f, 120.0f);
  const int sides[] = {5, 8, 12, 13, 24, 26, 31};
  std::vector<float> out(31 * 31);
  for (int trial = 0; trial < 300; ++trial) {
    const PatchBox box{pos(rng), pos(rng) * 0.6f, size(rng), size(rng)};
    const int w = sides[trial % 7], h = sides[(trial / 7) % 7];
    extractPatch(image.view(), box, w, h, PatchNormalization::kUnitRange, out.data());
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        ASSERT_EQ(out[v * w + u], referenceSample(image, box, w, h, u, v) * (1.0f / 255.0f))
            << "trial " << trial << " u " << u << " v " << v;
      }
    }
  }
}

// Area resampling checked against OpenCV's INTER_AREA (the box a whole multiple of the patch, at
// whole pixels: each sample the plain mean of its block; with the image's border replicated
// where the box leaves it), against the bilinear sample where a footprint is one pixel wide,
// and for what it is for: a fine pattern in a box many times the patch's size averages out
// instead of aliasing.
TEST(CnnPatch, AreaResamplingIsOpenCvsInterAreaAndBilinearAtOnePixel) {
  GrayImage image(97, 61);
  std::mt19937 rng(13);
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) image.at(x, y) = static_cast<std::uint8_t>(rng());
  }
  const cv::Mat mat(image.height(), image.width(), CV_8U, image.data());
  cv::Mat padded;
  cv::copyMakeBorder(mat, padded, 40, 40, 40, 40, cv::BORDER_REPLICATE);
  std::vector<float> out(24 * 24);
  struct Case {
    int x, y, w, h, side_x, side_y;
  };
  for (const Case& c :
       {Case{3, 2, 72, 48, 24, 24}, Case{10, 7, 36, 36, 12, 12}, Case{-20, -12, 60, 60, 12, 12},
        Case{70, 40, 48, 48, 24, 24}, Case{5, 5, 39, 26, 13, 13}}) {
    extractPatch(image.view(), PatchBox{float(c.x), float(c.y), float(c.w), float(c.h)}, c.side_x,
                 c.side_y, PatchNormalization::kUnitRange, out.data(), PatchResampling::kArea);
    cv::Mat expected;
    cv::resize(padded(cv::Rect(c.x + 40, c.y + 40, c.w, c.h)), expected,
               cv::Size(c.side_x, c.side_y), 0, 0, cv::INTER_AREA);
    for (int v = 0; v < c.side_y; ++v) {
      for (int u = 0; u < c.side_x; ++u) {
        // INTER_AREA rounds to whole grey levels; ours weighs in 1/256 steps (each weight within
        // 1/512 of its share, in two axes: about a grey level at most).
        ASSERT_NEAR(out[v * c.side_x + u] * 255.0f, expected.at<std::uint8_t>(v, u), 1.5f)
            << c.x << "," << c.y << " " << u << "," << v;
      }
    }
  }
  // A box the patch's size at fractional positions: every footprint one pixel wide, the bilinear
  // sample (which weighs in 1/256 steps).
  std::vector<float> bilinear(24 * 24);
  for (const PatchBox box : {PatchBox{10.3f, 4.7f, 24, 24}, PatchBox{80.6f, 45.2f, 24, 24},
                             PatchBox{30.0f, 20.5f, 12, 12}}) {
    extractPatch(image.view(), box, 24, 24, PatchNormalization::kUnitRange, out.data(),
                 PatchResampling::kArea);
    extractPatch(image.view(), box, 24, 24, PatchNormalization::kUnitRange, bilinear.data());
    for (std::size_t i = 0; i < out.size(); ++i) {
      ASSERT_NEAR(out[i] * 255.0f, bilinear[i] * 255.0f, 1.0f) << box.x_px << " " << i;
    }
  }
  // One-pixel stripes (0 and 200) in a box eight times the patch: the area patch is flat at the
  // stripes' mean; the bilinear one reads a few pixels per sample and keeps stripes of its own.
  GrayImage stripes(400, 300);
  for (int y = 0; y < 300; ++y) {
    for (int x = 0; x < 400; ++x) stripes.at(x, y) = static_cast<std::uint8_t>(x % 2 ? 200 : 0);
  }
  const auto spread = [](const std::vector<float>& p) {
    const auto [lo, hi] = std::minmax_element(p.begin(), p.end());
    return (*hi - *lo) * 255.0f;
  };
  const PatchBox wide{10.0f, 10.0f, 24 * 8 + 1.3f, 24 * 8};
  extractPatch(stripes.view(), wide, 24, 24, PatchNormalization::kUnitRange, out.data(),
               PatchResampling::kArea);
  extractPatch(stripes.view(), wide, 24, 24, PatchNormalization::kUnitRange, bilinear.data());
  EXPECT_LT(spread(out), 5.0f);  // the weights' 1/256 steps leave a few grey levels
  EXPECT_NEAR(out[0] * 255.0f, 100.0f, 1.0f);
  EXPECT_GT(spread(bilinear), 50.0f);
}

TEST(CnnPatch, StandardisesWithSixteenPartialSumsOfRoundedSquares) {
  // The partial sums written out (a square rounded before it is added: no fused multiply-add);
  // patch sizes without a tail, whose last values the compiler may sum either way.
  std::mt19937 rng(12);
  for (const int count : {16, 144, 576}) {
    for (int trial = 0; trial < 50; ++trial) {
      std::vector<float> values(count);
      for (float& v : values) v = static_cast<float>(rng() % 16711681) / 65536.0f;
      float sum[16] = {}, sum_sq[16] = {};
      for (int i = 0; i < count; ++i) {
        volatile float square = values[i] * values[i];
        sum[i % 16] += values[i];
        sum_sq[i % 16] += square;
      }
      float total = 0, total_sq = 0;
      for (int k = 0; k < 16; ++k) total += sum[k], total_sq += sum_sq[k];
      std::vector<float> out = values;
      normalizePatch(out.data(), count, PatchNormalization::kStandardize);
      // The mean and deviation from those sums, as normalizePatch computes them.
      const float mean = total / count;
      const float var = std::max(0.0f, total_sq / count - mean * mean);
      const float inv = 1.0f / std::max(std::sqrt(var), kMinStddev);
      for (int i = 0; i < count; ++i) {
        ASSERT_EQ(out[i], (values[i] - mean) * inv) << count << " " << trial << " " << i;
      }
    }
  }
}

// The unsharp mask: a flat patch stays flat; a blurred step (a soft lens's edge) gets steeper,
// keeps its mean, and over- and undershoots its two levels, symmetrically; a single bright pixel is
// v + a (v - G v) exactly where G's weights are known; bad sizes and values are refused.
TEST(CnnPatch, MirrorReversesEachRow) {
  std::vector<float> in(5 * 3), out(5 * 3, -1.0f);
  for (int i = 0; i < 15; ++i) in[i] = static_cast<float>(i * i);
  mirrorPatch(in.data(), 5, 3, out.data());
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 5; ++x) EXPECT_EQ(out[y * 5 + x], in[y * 5 + 4 - x]) << x << "," << y;
  }
}

// A bright disc on a darker ground, smeared sideways by a straight motion of 8 px (the mean over
// the segment, as deblurAlong models it): ten Richardson-Lucy steps along the same segment bring the
// patch nearer the disc, twenty nearer still; across the smear they take it farther; a flat patch,
// no steps or a segment under a pixel leave a patch as it is.
TEST(CnnPatch, DeblurAlongTakesAStraightSmearBack) {
  const int n = 26;
  std::vector<float> disc(n * n);
  for (int y = 0; y < n; ++y) {
    for (int x = 0; x < n; ++x) disc[y * n + x] = std::hypot(x - 12.5, y - 12.5) < 6 ? 200.0f : 60.0f;
  }
  // The smear: the mean of 81 samples along x from -4 to +4 px (linear between pixels).
  const auto smeared = [&](const std::vector<float>& v) {
    std::vector<float> out(v.size());
    for (int y = 0; y < n; ++y) {
      for (int x = 0; x < n; ++x) {
        double s = 0;
        for (int k = 0; k <= 80; ++k) {
          const double sx = std::clamp(x - 4.0 + k * 0.1, 0.0, n - 1.0);
          const int x0 = std::min(static_cast<int>(sx), n - 2);
          s += (1 - (sx - x0)) * v[y * n + x0] + (sx - x0) * v[y * n + x0 + 1];
        }
        out[y * n + x] = static_cast<float>(s / 81);
      }
    }
    return out;
  };
  const auto error = [&](const std::vector<float>& v) {
    double e = 0;
    for (int i = 0; i < n * n; ++i) e += (v[i] - disc[i]) * (v[i] - disc[i]);
    return std::sqrt(e / (n * n));
  };
  const std::vector<float> blurred = smeared(disc);
  std::vector<float> back = blurred;
  deblurAlong(back.data(), n, n, 8, 0, 10);
  // (measured: 22.0 smeared, 16.9 after 10 steps, 14.9 after 20; across the smear 33.8)
  EXPECT_LT(error(back), 0.8 * error(blurred)) << error(back) << " " << error(blurred);
  std::vector<float> longer = blurred;
  deblurAlong(longer.data(), n, n, 8, 0, 20);
  EXPECT_LT(error(longer), 0.95 * error(back));
  std::vector<float> across = blurred;
  deblurAlong(across.data(), n, n, 0, 8, 10);
  EXPECT_GT(error(across), error(blurred));
  std::vector<float> flat(n * n, 90.0f);
  deblurAlong(flat.data(), n, n, 5, 3, 10);
  for (const float v : flat) EXPECT_NEAR(v, 90.0f, 1e-3f);
  std::vector<float> same = blurred;
  deblurAlong(same.data(), n, n, 8, 0, 0);
  EXPECT_EQ(same, blurred);
  deblurAlong(same.data(), n, n, 0.5, 0.5, 10);
  EXPECT_EQ(same, blurred);
  EXPECT_THROW(deblurAlong(same.data(), 0, n, 8, 0, 10), Error);
  EXPECT_THROW(deblurAlong(same.data(), n, n, 8, 0, -1), Error);
  EXPECT_THROW(deblurAlong(same.data(), n, n, 30, 0, 10), Error);
  EXPECT_THROW(deblurAlong(same.data(), n, n, std::nan(""), 0, 10), Error);
}

TEST(CnnPatch, UnsharpMaskSteepensEdgesAndLeavesFlatPatchesAlone) {
  std::vector<float> flat(26 * 26, 90.0f);
  unsharpMask(flat.data(), 26, 26, 2.0, 4.0);
  for (const float v : flat) EXPECT_NEAR(v, 90.0f, 1e-3f);
  // A step from 50 to 150 across columns 12 | 13, blurred: a logistic ramp some 6 px wide.
  std::vector<float> step(26 * 26);
  for (int y = 0; y < 26; ++y) {
    for (int x = 0; x < 26; ++x)
      step[y * 26 + x] = 50.0f + 100.0f / (1.0f + std::exp(-(x - 12.5f) / 1.5f));
  }
  std::vector<float> sharp = step;
  unsharpMask(sharp.data(), 26, 26, 3.0, 2.0);
  const auto slope = [](const std::vector<float>& v) { return v[10 * 26 + 13] - v[10 * 26 + 12]; };
  EXPECT_GT(slope(sharp), 1.5f * slope(step));
  float lo = 1e9f, hi = -1e9f, sum = 0, sum_step = 0;
  for (int i = 0; i < 26 * 26; ++i) {
    lo = std::min(lo, sharp[i]);
    hi = std::max(hi, sharp[i]);
    sum += sharp[i];
    sum_step += step[i];
  }
  EXPECT_LT(lo, 48.0f);
  EXPECT_GT(hi, 152.0f);
  EXPECT_NEAR(lo - 50.0f, 150.0f - hi, 1e-2f);
  EXPECT_NEAR(sum / (26 * 26), sum_step / (26 * 26), 0.5f);
  // One bright pixel far from the border: the blur's centre weight is 1 / (sum of the 1-D
  // weights)^2.
  std::vector<float> dot(21 * 21, 0.0f);
  dot[10 * 21 + 10] = 100.0f;
  unsharpMask(dot.data(), 21, 21, 1.0, 3.0);
  double w = 0;
  for (int i = -3; i <= 3; ++i) w += std::exp(-0.5 * i * i);
  EXPECT_NEAR(dot[10 * 21 + 10], 100.0 + 3.0 * (100.0 - 100.0 / (w * w)), 1e-3);
  EXPECT_NEAR(dot[10 * 21 + 11], -3.0 * 100.0 * std::exp(-0.5) / (w * w), 1e-3);
  EXPECT_THROW(unsharpMask(dot.data(), 0, 21, 1.0, 1.0), Error);
  EXPECT_THROW(unsharpMask(dot.data(), 21, 300, 1.0, 1.0), Error);
  EXPECT_THROW(unsharpMask(dot.data(), 21, 21, 0.0, 1.0), Error);
  EXPECT_THROW(unsharpMask(dot.data(), 21, 21, 1.0, -1.0), Error);
  EXPECT_THROW(unsharpMask(dot.data(), 21, 21, std::nan(""), 1.0), Error);
}

TEST(CnnClassifier, SinglePatchesAndBatchesGiveTheSameProbabilities) {
  Net net = readDarknetCfg(model("ori_net.cfg"));
  net.initialise(2);
  const Classifier classifier(net);
  const int n = net.input().size(), k = net.classes(), count = 37;
  std::vector<float> inputs(static_cast<std::size_t>(count) * n);
  for (std::size_t i = 0; i < inputs.size(); ++i) inputs[i] = std::sin(0.37f * i);
  std::vector<float> batch(count * k), single(k);
  classifier.run(inputs.data(), count, batch.data());
  for (int b = 0; b < count; ++b) {
    classifier.run(inputs.data() + b * n, 1, single.data());
    float sum = 0.0f;
    for (int c = 0; c < k; ++c) {
      EXPECT_NEAR(single[c], batch[b * k + c], 1e-6f);
      sum += single[c];
    }
    EXPECT_NEAR(sum, 1.0f, 1e-5f);
  }
}

}  // namespace
}  // namespace colorfree::cnn
