#include "colorfree/sim/camera_effects.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "colorfree/perception/error.h"

namespace colorfree::sim {

FloatImage toFloat(const GrayImage& image) {
  FloatImage f;
  f.width = image.width();
  f.height = image.height();
  f.pixels.assign(image.pixels().begin(), image.pixels().end());
  return f;
}

ExposurePlan::ExposurePlan(const EffectsSpec& effects, int height_px) {
  if (height_px <= 0) throw Error("exposure plan: image height must be positive");
  const bool blur = effects.blur_subframes > 1 && effects.exposure_s > 0;
  const double exposure = blur ? effects.exposure_s : 0.0;
  exposure_s_ = exposure;
  const double readout = effects.rolling_shutter ? effects.readout_s : 0.0;
  readout_s_ = readout;
  const double span = exposure + readout;
  rows_.resize(static_cast<std::size_t>(height_px));
  if (span <= 0) {
    times_s_ = {0.0};
    for (auto& row : rows_) row = {{0, 1.0f}};
    return;
  }
  int count = effects.rolling_shutter ? std::max(1, effects.rolling_shutter_bands) : 1;
  if (blur) {
    const double step = exposure / effects.blur_subframes;
    count = std::max(count, static_cast<int>(std::ceil(span / step - 1e-9)));
  }
  count = std::min(count, kMaxSubframes);
  const double length = span / count;
  const double start = -span / 2;
  for (int j = 0; j < count; ++j) times_s_.push_back(start + (j + 0.5) * length);

  for (int r = 0; r < height_px; ++r) {
    const double centre = readout * ((r + 0.5) / height_px - 0.5);
    auto& weights = rows_[static_cast<std::size_t>(r)];
    if (exposure <= 0) {
      const int j =
          std::clamp(static_cast<int>(std::floor((centre - start) / length)), 0, count - 1);
      weights = {{j, 1.0f}};
      continue;
    }
    const double a = centre - exposure / 2;
    const double b = centre + exposure / 2;
    double total = 0;
    for (int j = 0; j < count; ++j) {
      const double lo = std::max(a, start + j * length);
      const double hi = std::min(b, start + (j + 1) * length);
      if (hi - lo > 1e-12 * span) {
        weights.push_back({j, static_cast<float>(hi - lo)});
        total += hi - lo;
      }
    }
    for (auto& w : weights) w.second = static_cast<float>(w.second / total);
  }
}

FloatImage composeSubframes(const std::vector<GrayImage>& subframes, const ExposurePlan& plan) {
  if (subframes.size() != plan.subframeTimes().size()) {
    throw Error("camera effects: " + std::to_string(subframes.size()) +
                " sub-frames for a plan of " + std::to_string(plan.subframeTimes().size()));
  }
  const int width = subframes.front().width();
  const int height = subframes.front().height();
  for (const GrayImage& s : subframes) {
    if (s.width() != width || s.height() != height) {
      throw Error("camera effects: sub-frames of different sizes");
    }
  }
  if (height != plan.height()) {
    throw Error("camera effects: sub-frames of height " + std::to_string(height) +
                " for a plan of height " + std::to_string(plan.height()));
  }
  FloatImage out;
  out.width = width;
  out.height = height;
  out.pixels.assign(static_cast<std::size_t>(width) * height, 0.0f);
  for (int y = 0; y < height; ++y) {
    float* dst = out.pixels.data() + static_cast<std::size_t>(y) * width;
    for (const auto& [j, w] : plan.rowWeights(y)) {
      const std::uint8_t* src =
          subframes[static_cast<std::size_t>(j)].data() + static_cast<std::size_t>(y) * width;
      for (int x = 0; x < width; ++x) dst[x] += w * static_cast<float>(src[x]);
    }
  }
  return out;
}

FloatImage smearAlong(const FloatImage& image, double step_x_px, double step_y_px) {
  if (!std::isfinite(step_x_px) || !std::isfinite(step_y_px)) {
    throw Error("camera effects: the smear step must be finite");
  }
  const double length = std::hypot(step_x_px, step_y_px);
  if (length < 1.0 || image.width == 0 || image.height == 0) return image;
  // The midpoints of equal parts of [-step/2, step/2], half a pixel long or less; bilinear.
  const int samples = static_cast<int>(std::ceil(2.0 * length));
  FloatImage out;
  out.width = image.width;
  out.height = image.height;
  out.pixels.assign(image.pixels.size(), 0.0f);
  const float max_x = static_cast<float>(image.width - 1), max_y = static_cast<float>(image.height - 1);
  const float weight = 1.0f / static_cast<float>(samples);
  for (int k = 0; k < samples; ++k) {
    const double f = (k + 0.5) / samples - 0.5;
    const float ox = static_cast<float>(f * step_x_px), oy = static_cast<float>(f * step_y_px);
    for (int y = 0; y < image.height; ++y) {
      const float sy = std::clamp(static_cast<float>(y) + oy, 0.0f, max_y);
      const int y0 = static_cast<int>(sy), y1 = std::min(y0 + 1, image.height - 1);
      const float fy = sy - static_cast<float>(y0);
      const float* r0 = image.pixels.data() + static_cast<std::size_t>(y0) * image.width;
      const float* r1 = image.pixels.data() + static_cast<std::size_t>(y1) * image.width;
      float* dst = out.pixels.data() + static_cast<std::size_t>(y) * image.width;
      for (int x = 0; x < image.width; ++x) {
        const float sx = std::clamp(static_cast<float>(x) + ox, 0.0f, max_x);
        const int x0 = static_cast<int>(sx), x1 = std::min(x0 + 1, image.width - 1);
        const float fx = sx - static_cast<float>(x0);
        const float top = r0[x0] + fx * (r0[x1] - r0[x0]);
        const float bottom = r1[x0] + fx * (r1[x1] - r1[x0]);
        dst[x] += weight * (top + fy * (bottom - top));
      }
    }
  }
  return out;
}

namespace {

// One pass of a normalised Gaussian kernel along x (stride 1) or y (stride width); the edge repeats.
void gaussianPass(const FloatImage& in, FloatImage& out, const std::vector<float>& kernel, bool along_x) {
  const int radius = static_cast<int>(kernel.size() / 2);
  const int n = along_x ? in.width : in.height;
  for (int y = 0; y < in.height; ++y) {
    for (int x = 0; x < in.width; ++x) {
      const int at = along_x ? x : y;
      float sum = 0;
      for (int k = -radius; k <= radius; ++k) {
        const int j = std::clamp(at + k, 0, n - 1);
        sum += kernel[k + radius] * (along_x ? in.at(j, y) : in.at(x, j));
      }
      out.pixels[static_cast<std::size_t>(y) * in.width + x] = sum;
    }
  }
}

}  // namespace

FloatImage applyOptics(FloatImage image, const EffectsSpec& effects) {
  const double sigma = effects.defocus_px, glare = effects.veiling_glare;
  if (!std::isfinite(sigma) || sigma < 0 || sigma > 20 || !std::isfinite(glare) || glare < 0 || glare > 0.9) {
    throw Error("camera effects: defocus_px must be in [0, 20] and veiling_glare in [0, 0.9]");
  }
  if (image.pixels.empty() || (sigma == 0 && glare == 0)) return image;  // no copy when off
  if (sigma > 0) {
    const int radius = std::max(1, static_cast<int>(std::ceil(3 * sigma)));
    std::vector<float> kernel(2 * radius + 1);
    double total = 0;
    for (int k = -radius; k <= radius; ++k) total += kernel[k + radius] = static_cast<float>(std::exp(-0.5 * k * k / (sigma * sigma)));
    for (float& v : kernel) v = static_cast<float>(v / total);
    FloatImage tmp = image;
    gaussianPass(image, tmp, kernel, true);
    gaussianPass(tmp, image, kernel, false);
  }
  if (glare > 0) {
    double mean = 0;
    for (float v : image.pixels) mean += v;
    mean /= static_cast<double>(image.pixels.size());
    const float keep = static_cast<float>(1 - glare), lift = static_cast<float>(glare * mean);
    for (float& v : image.pixels) v = keep * v + lift;
  }
  return image;
}

GrayImage applySensor(const FloatImage& exposure, const EffectsSpec& effects, std::uint64_t seed) {
  if (!std::isfinite(effects.gain) || effects.gain < 0 || !std::isfinite(effects.noise_sigma) ||
      effects.noise_sigma < 0 || !std::isfinite(effects.shot_noise) || effects.shot_noise < 0) {
    throw Error("camera effects: gain and noise must be finite and not negative");
  }
  GrayImage out(exposure.width, exposure.height);
  const bool noisy = effects.noise_sigma > 0 || effects.shot_noise > 0;
  std::mt19937_64 rng(seed);
  // Box-Muller on the generator's raw bits, so the noise is the same wherever it runs.
  constexpr double kScale = 1.0 / 9007199254740992.0;  // 2^-53
  bool have_spare = false;
  double spare = 0;
  auto gaussian = [&]() {
    if (have_spare) {
      have_spare = false;
      return spare;
    }
    const double u1 = (static_cast<double>(rng() >> 11) + 1.0) * kScale;  // (0, 1]
    const double u2 = static_cast<double>(rng() >> 11) * kScale;
    const double radius = std::sqrt(-2.0 * std::log(u1));
    const double angle = 2.0 * std::numbers::pi * u2;
    spare = radius * std::sin(angle);
    have_spare = true;
    return radius * std::cos(angle);
  };
  const double read_var = effects.noise_sigma * effects.noise_sigma;
  for (std::size_t i = 0; i < exposure.pixels.size(); ++i) {
    double v = static_cast<double>(exposure.pixels[i]) * effects.gain;
    if (noisy) v += std::sqrt(read_var + effects.shot_noise * std::max(0.0, v)) * gaussian();
    out.data()[i] = static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
  }
  return out;
}

std::uint64_t frameSeed(std::uint64_t scenario_seed, int frame_index) {
  // splitmix64 of the pair: neighbouring seeds and frames give unrelated streams.
  std::uint64_t z = scenario_seed * 0x9E3779B97F4A7C15ULL +
                    static_cast<std::uint64_t>(frame_index) + 0x632BE59BD9B4E019ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

}  // namespace colorfree::sim
