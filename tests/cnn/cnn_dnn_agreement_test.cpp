// Every shipped net, with seeded random weights, gives the same probabilities here and in
// OpenCV's Darknet importer (cv::dnn) reading the very same cfg and weights files.
#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/dnn.hpp>
#include <random>

#include "colorfree/perception/cnn/classifier.h"
#include "colorfree/perception/cnn/net.h"
#include "test_support.h"

namespace colorfree::cnn {
namespace {

std::vector<std::string> shippedCfgs() {
  std::vector<std::string> out;
  for (const auto& e : std::filesystem::directory_iterator(defaultModelDir())) {
    if (e.path().extension() == ".cfg") out.push_back(e.path().string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

// Runs `net` through both engines on `count` seeded random inputs; returns the largest difference.
float maxDifference(Net net, int count, std::uint64_t seed, const std::string& tag) {
  const std::string dir = ::testing::TempDir();
  const std::string cfg = dir + "/" + tag + ".cfg", weights = dir + "/" + tag + ".weights";
  writeDarknetCfg(net, cfg);
  writeDarknetWeights(net, weights);
  cv::dnn::Net dnn = cv::dnn::readNetFromDarknet(cfg, weights);
  dnn.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  dnn.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  const Shape in = net.input();
  const int sizes[4] = {count, in.channels, in.height, in.width};
  cv::Mat blob(4, sizes, CV_32F);
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  float* p = blob.ptr<float>();
  for (std::size_t i = 0; i < blob.total(); ++i) p[i] = normal(rng);
  dnn.setInput(blob);
  cv::Mat theirs = dnn.forward().reshape(1, count);
  EXPECT_EQ(theirs.cols, net.classes());

  Classifier ours(readDarknet(cfg, weights));
  std::vector<float> probs(static_cast<std::size_t>(count) * net.classes());
  ours.run(p, count, probs.data());
  float worst = 0.0f;
  for (int b = 0; b < count; ++b) {
    for (int c = 0; c < net.classes(); ++c) {
      worst = std::max(worst, std::abs(probs[b * net.classes() + c] - theirs.at<float>(b, c)));
    }
  }
  return worst;
}

TEST(CnnDnnAgreement, EveryShippedNetAgreesWithOpenCv) {
  const auto cfgs = shippedCfgs();
  ASSERT_GE(cfgs.size(), 5u);
  std::uint64_t seed = 11;
  for (const std::string& cfg : cfgs) {
    SCOPED_TRACE(cfg);
    Net net = readDarknetCfg(cfg);
    net.initialise(seed++);
    // Single patches (the plane engine), one full batch of lanes, and a ragged batch.
    for (int count : {1, 3, 16, 21}) {
      const float d = maxDifference(net, count, seed++, "agree");
      EXPECT_LT(d, test::kCnnTolerance) << count;
    }
  }
}

// Layers the shipped nets do not use (strided and padded convolution, padded max pool with
// stride 1, connected layers on a plane) agree as well.
TEST(CnnDnnAgreement, OtherLayerOptionsAgree) {
  const char* cfg = R"(
[net]
width=11
height=9
channels=2

[convolutional]
filters=5
size=3
stride=2
padding=2
activation=leaky

[maxpool]
size=3
stride=1

[route]
layers=-1,-2

[convolutional]
filters=3
size=2
stride=1
activation=linear

[connected]
output=7
activation=leaky

[connected]
output=4
activation=linear

[softmax]
)";
  Net net = parseDarknetCfg(cfg, "inline");
  net.initialise(5);
  for (int count : {1, 17})
    EXPECT_LT(maxDifference(net, count, 3, "options"), test::kCnnTolerance) << count;
}

}  // namespace
}  // namespace colorfree::cnn
