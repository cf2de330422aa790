// Numerical gradient checks: for every layer type, the trainer's backward pass matches central
// differences of the loss, for the parameters and for the input.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "colorfree/perception/cnn/net.h"
#include "colorfree/perception/cnn/trainer.h"

namespace colorfree::cnn {
namespace {

constexpr float kStep = 1e-3f;
// Central differences of a float32 forward pass: absolute part from rounding, relative part.
constexpr double kAbsTolerance = 1e-3;
constexpr double kRelTolerance = 1e-2;

struct Case {
  const char* name;
  const char* cfg;
};

const Case kCases[] = {
    {"convolution_stride_padding_leaky",
     "[net]\nwidth=7\nheight=6\nchannels=2\n"
     "[convolutional]\nfilters=3\nsize=3\nstride=2\npadding=1\nactivation=leaky\n"
     "[convolutional]\nfilters=4\nsize=2\nstride=1\nactivation=linear\n"
     "[avgpool]\n[softmax]\n"},
    {"maxpool_padded_and_connected",
     "[net]\nwidth=6\nheight=5\nchannels=1\n"
     "[convolutional]\nfilters=2\nsize=3\npad=1\nactivation=leaky\n"
     "[maxpool]\nsize=3\nstride=2\n"
     "[connected]\noutput=3\nactivation=linear\n[softmax]\n"},
    {"fire_module_route",
     "[net]\nwidth=5\nheight=5\nchannels=1\n"
     "[convolutional]\nfilters=3\nsize=3\npad=1\nactivation=leaky\n"
     "[convolutional]\nfilters=2\nsize=1\nactivation=leaky\n"
     "[convolutional]\nfilters=2\nsize=1\nactivation=leaky\n"
     "[route]\nlayers=-2\n"
     "[convolutional]\nfilters=3\nsize=3\npad=1\nactivation=leaky\n"
     "[route]\nlayers=-3,-1\n"
     "[maxpool]\nsize=2\nstride=2\n"
     "[convolutional]\nfilters=2\nsize=1\nactivation=linear\n"
     "[avgpool]\n[softmax]\n"},
    {"connected_leaky_on_a_plane",
     "[net]\nwidth=4\nheight=3\nchannels=2\n"
     "[connected]\noutput=5\nactivation=leaky\n"
     "[connected]\noutput=3\nactivation=linear\n[softmax]\n"},
};

void PrintTo(const Case& c, std::ostream* os) { *os << c.name; }

class CnnGradient : public ::testing::TestWithParam<Case> {};

TEST_P(CnnGradient, MatchesCentralDifferences) {
  Net net = parseDarknetCfg(GetParam().cfg, GetParam().name);
  net.initialise(17);
  std::mt19937_64 rng(23);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  // Biases away from zero so that they matter, and 18 samples: one full and one ragged lane batch.
  for (const Layer& l : net.layers()) {
    for (int o = 0; o < (l.param_count ? l.filters : 0); ++o)
      net.params()[l.param_offset + o] = 0.3f * normal(rng);
  }
  const int count = 18, n = net.input().size();
  std::vector<float> inputs(static_cast<std::size_t>(count) * n);
  for (float& v : inputs) v = normal(rng);
  std::vector<int> labels(count);
  std::vector<float> weights(count);
  std::uniform_real_distribution<float> weight(0.5f, 2.0f);
  for (int i = 0; i < count; ++i) {
    labels[i] = static_cast<int>(rng() % net.classes());
    weights[i] = weight(rng);
  }
  std::vector<float> grad, input_grad, scratch;
  const double loss =
      lossAndGradient(net, inputs.data(), labels.data(), weights.data(), count, grad, &input_grad);
  EXPECT_GT(loss, 0.0);
  const auto lossAt = [&]() {
    return lossAndGradient(net, inputs.data(), labels.data(), weights.data(), count, scratch);
  };
  double largest = 0.0;
  for (std::size_t i = 0; i < net.parameterCount(); ++i) {
    float& p = net.params()[i];
    const float saved = p;
    p = saved + kStep;
    const double up = lossAt();
    p = saved - kStep;
    const double down = lossAt();
    p = saved;
    const double numeric = (up - down) / (2.0 * kStep);
    largest = std::max(largest, std::abs(numeric));
    EXPECT_NEAR(grad[i], numeric, kAbsTolerance + kRelTolerance * std::abs(numeric))
        << "parameter " << i;
  }
  EXPECT_GT(largest, 1e-2);  // the check is not vacuous
  for (std::size_t i = 0; i < inputs.size(); ++i) {
    const float saved = inputs[i];
    inputs[i] = saved + kStep;
    const double up = lossAt();
    inputs[i] = saved - kStep;
    const double down = lossAt();
    inputs[i] = saved;
    const double numeric = (up - down) / (2.0 * kStep);
    EXPECT_NEAR(input_grad[i], numeric, kAbsTolerance + kRelTolerance * std::abs(numeric))
        << "input " << i;
  }
}

INSTANTIATE_TEST_SUITE_P(EveryLayerType, CnnGradient, ::testing::ValuesIn(kCases),
                         [](const auto& info) { return std::string(info.param.name); });

}  // namespace
}  // namespace colorfree::cnn
