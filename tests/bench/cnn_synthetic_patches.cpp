// Writes a dataset folder of synthetic grayscale patches (class "disc": a dark disc of random
// size near the centre; class "none": a dark straight edge; random brightness, contrast, noise),
// for measuring the trainer's speed: cnn_synthetic_patches DIR SIDE COUNT [SEED]
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>

#include "colorfree/perception/cnn/dataset.h"
#include "colorfree/perception/error.h"

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: %s DIR SIDE COUNT [SEED]\n", argv[0]);
    return 2;
  }
  using namespace colorfree;
  const int side = std::atoi(argv[2]), count = std::atoi(argv[3]);
  const std::uint64_t seed = argc > 4 ? std::strtoull(argv[4], nullptr, 10) : 1;
  if (side < 4 || count < 2) {
    std::fprintf(stderr, "SIDE must be >= 4 and COUNT >= 2\n");
    return 2;
  }
  cnn::Dataset d;
  d.width = d.height = side;
  d.class_names = {"none", "disc"};
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::normal_distribution<float> noise(0.0f, 6.0f);
  for (int i = 0; i < count; ++i) {
    cnn::Sample s;
    s.label = i % 2;
    s.patch = GrayImage(side, side);
    const float bg = 120.0f + 100.0f * u(rng), fg = bg * (0.2f + 0.4f * u(rng));
    const float cx = side * (0.4f + 0.2f * u(rng)), cy = side * (0.4f + 0.2f * u(rng));
    const float r = side * (0.2f + 0.15f * u(rng));
    const float angle = 6.2832f * u(rng), offset = side * (u(rng) - 0.5f);
    for (int y = 0; y < side; ++y) {
      for (int x = 0; x < side; ++x) {
        const bool dark =
            s.label == 1
                ? std::hypot(x + 0.5f - cx, y + 0.5f - cy) < r
                : (x - side / 2) * std::cos(angle) + (y - side / 2) * std::sin(angle) > offset;
        s.patch.at(x, y) =
            static_cast<std::uint8_t>(std::clamp((dark ? fg : bg) + noise(rng), 0.0f, 255.0f));
      }
    }
    s.origin.scenario = "synthetic";
    s.origin.frame = i;
    d.samples.push_back(std::move(s));
  }
  try {
    cnn::writeDataset(d, argv[1]);
  } catch (const Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  return 0;
}
