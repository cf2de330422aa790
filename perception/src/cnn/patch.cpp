#include "colorfree/perception/cnn/patch.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "colorfree/perception/error.h"

namespace colorfree::cnn {

namespace {
constexpr int kMaxPatchSide = 256;
}

void normalizePatch(float* values, int count, PatchNormalization normalization) {
  if (normalization == PatchNormalization::kUnitRange) {
    constexpr float kScale = 1.0f / 255.0f;
    for (int i = 0; i < count; ++i) values[i] *= kScale;
    return;
  }
  float sum = 0.0f, sum_sq = 0.0f;
  for (int i = 0; i < count; ++i) {
    sum += values[i];
    sum_sq += values[i] * values[i];
  }
  const float mean = sum / static_cast<float>(count);
  const float var = std::max(0.0f, sum_sq / static_cast<float>(count) - mean * mean);
  const float inv = 1.0f / std::max(std::sqrt(var), kMinStddev);
  for (int i = 0; i < count; ++i) values[i] = (values[i] - mean) * inv;
}

void extractPatch(const GrayView& image, const PatchBox& box, int width, int height,
                  PatchNormalization normalization, float* out) {
  if (image.empty()) throw Error("extractPatch: empty image");
  if (width <= 0 || height <= 0 || width > kMaxPatchSide || height > kMaxPatchSide) {
    throw Error("extractPatch: patch size " + std::to_string(width) + "x" + std::to_string(height) +
                " outside 1..256");
  }
  if (!(box.width_px > 0.0f) || !(box.height_px > 0.0f) || !std::isfinite(box.x_px) ||
      !std::isfinite(box.y_px) || !std::isfinite(box.width_px) || !std::isfinite(box.height_px)) {
    throw Error("extractPatch: box must have a finite position and a positive size");
  }
  int x0[kMaxPatchSide], x1[kMaxPatchSide];
  float fx[kMaxPatchSide];
  const float sx = box.width_px / static_cast<float>(width);
  const float sy = box.height_px / static_cast<float>(height);
  const float max_x = static_cast<float>(image.width - 1), max_y = static_cast<float>(image.height - 1);
  for (int u = 0; u < width; ++u) {
    const float x = std::clamp(box.x_px + (static_cast<float>(u) + 0.5f) * sx - 0.5f, 0.0f, max_x);
    x0[u] = static_cast<int>(x);
    x1[u] = std::min(x0[u] + 1, image.width - 1);
    fx[u] = x - static_cast<float>(x0[u]);
  }
  for (int v = 0; v < height; ++v) {
    const float y = std::clamp(box.y_px + (static_cast<float>(v) + 0.5f) * sy - 0.5f, 0.0f, max_y);
    const int y0 = static_cast<int>(y);
    const int y1 = std::min(y0 + 1, image.height - 1);
    const float fy = y - static_cast<float>(y0);
    const std::uint8_t* r0 = image.row(y0);
    const std::uint8_t* r1 = image.row(y1);
    float* o = out + static_cast<std::size_t>(v) * width;
    for (int u = 0; u < width; ++u) {
      const float top = r0[x0[u]] + fx[u] * (static_cast<float>(r0[x1[u]]) - r0[x0[u]]);
      const float bottom = r1[x0[u]] + fx[u] * (static_cast<float>(r1[x1[u]]) - r1[x0[u]]);
      o[u] = top + fy * (bottom - top);
    }
  }
  normalizePatch(out, width * height, normalization);
}

}  // namespace colorfree::cnn
