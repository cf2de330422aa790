// Time per patch of every shipped net: this engine and cv::dnn on the same cfg and weights files,
// single patches and batches of 16, on one core. Run: build/bin/bench_cnn
#include <benchmark/benchmark.h>

#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>
#include <random>

#include "colorfree/perception/cnn/classifier.h"
#include "colorfree/perception/cnn/net.h"
#include "colorfree/perception/cnn/patch.h"

namespace colorfree::cnn {
namespace {

// The shipped weights when they exist, else seeded random weights (speed does not depend on them).
struct Files {
  std::string cfg, weights;
};
Files files(const std::string& name) {
  Files f{defaultModelDir() + "/" + name + ".cfg", defaultModelDir() + "/" + name + ".weights"};
  if (!std::filesystem::exists(f.weights)) {
    Net net = readDarknetCfg(f.cfg);
    net.initialise(1);
    f.weights = std::filesystem::temp_directory_path().string() + "/bench_cnn_" + name + ".weights";
    writeDarknetWeights(net, f.weights);
  }
  return f;
}

std::vector<float> randomInputs(const Shape& s, int count) {
  std::vector<float> v(static_cast<std::size_t>(s.size()) * count);
  std::mt19937_64 rng(42);
  std::normal_distribution<float> normal(0.0f, 1.0f);
  for (float& x : v) x = normal(rng);
  return v;
}

void perPatch(benchmark::State& state, int batch) {
  state.counters["us_per_patch"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * batch * 1e-6,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

void ours(benchmark::State& state, const std::string& name) {
  const Files f = files(name);
  const Classifier classifier = Classifier::load(f.cfg, f.weights);
  const int batch = static_cast<int>(state.range(0));
  const auto inputs = randomInputs(classifier.input(), batch);
  std::vector<float> probs(static_cast<std::size_t>(batch) * classifier.classes());
  for (auto _ : state) {
    classifier.run(inputs.data(), batch, probs.data());
    benchmark::DoNotOptimize(probs.data());
  }
  perPatch(state, batch);
  state.counters["params"] = static_cast<double>(classifier.net().parameterCount());
  state.counters["madds"] = static_cast<double>(classifier.net().multiplyAdds());
}

void opencv(benchmark::State& state, const std::string& name) {
  cv::setNumThreads(1);
  const Files f = files(name);
  const Net net = readDarknetCfg(f.cfg);
  cv::dnn::Net dnn = cv::dnn::readNetFromDarknet(f.cfg, f.weights);
  dnn.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
  dnn.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  const int batch = static_cast<int>(state.range(0));
  auto inputs = randomInputs(net.input(), batch);
  const int sizes[4] = {batch, net.input().channels, net.input().height, net.input().width};
  const cv::Mat blob(4, sizes, CV_32F, inputs.data());
  for (auto _ : state) {
    dnn.setInput(blob);
    cv::Mat out = dnn.forward();
    benchmark::DoNotOptimize(out.data);
  }
  perPatch(state, batch);
}

// Crop, resize and normalise 16 boxes of a 640x480 frame to side x side: arguments side,
// resampling (0 bilinear, 1 area) and the box (0: 60x80, a robot proposal's size; 1: 180x290, a
// robot 1.2 m away).
void extraction(benchmark::State& state) {
  GrayImage image(640, 480);
  std::mt19937_64 rng(3);
  for (int y = 0; y < 480; ++y) {
    for (int x = 0; x < 640; ++x) image.at(x, y) = static_cast<std::uint8_t>(rng() & 0xff);
  }
  const int side = static_cast<int>(state.range(0));
  std::vector<float> out(static_cast<std::size_t>(side) * side);
  const auto resampling = state.range(1) ? PatchResampling::kArea : PatchResampling::kBilinear;
  const bool near = state.range(2) != 0;
  std::uniform_real_distribution<float> pos(0.0f, near ? 400.0f : 500.0f);
  std::vector<PatchBox> boxes;
  for (int i = 0; i < 16; ++i) {
    boxes.push_back(
        {pos(rng), pos(rng) * (near ? 0.4f : 0.7f), near ? 180.0f : 60.0f, near ? 290.0f : 80.0f});
  }
  for (auto _ : state) {
    for (const PatchBox& b : boxes) {
      extractPatch(image.view(), b, side, side, PatchNormalization::kStandardize, out.data(),
                   resampling);
      benchmark::DoNotOptimize(out.data());
    }
  }
  perPatch(state, 16);
}

const char* const kNets[] = {"robot_net", "boost_ball_net", "ball_net", "ori_boost_net", "ori_net"};

int registerAll() {
  for (const char* name : kNets) {
    const std::string n = name;
    benchmark::RegisterBenchmark(("colorfree/" + n).c_str(),
                                 [n](benchmark::State& s) { ours(s, n); })
        ->Arg(1)
        ->Arg(16);
    benchmark::RegisterBenchmark(("cv_dnn/" + n).c_str(),
                                 [n](benchmark::State& s) { opencv(s, n); })
        ->Arg(1)
        ->Arg(16);
  }
  benchmark::RegisterBenchmark("extract_patch", extraction)
      ->ArgNames({"side", "area", "near"})
      ->Args({12, 0, 0})
      ->Args({24, 0, 0})
      ->Args({24, 1, 0})
      ->Args({24, 0, 1})
      ->Args({24, 1, 1});
  return 0;
}
const int kRegistered = registerAll();

}  // namespace
}  // namespace colorfree::cnn

BENCHMARK_MAIN();
