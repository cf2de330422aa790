#include "colorfree/perception/noise.h"

#include <cmath>
#include <cstddef>

#include "colorfree/perception/error.h"

namespace colorfree {

double DifferenceNoise::sigma() const {
  if (n_ == 0) return 0;
  std::uint32_t seen = 0;
  for (int v = 0; v < 256; ++v) {
    seen += histogram_[v];
    if (2 * seen >= n_) return (v + 0.5) / 0.6745;
  }
  return 255;
}

double pixelNoiseGray(const GrayView& image, const IgnoreMask& ignore, int row_step,
                      int column_step) {
  if (ignore.width != image.width || ignore.height != image.height) {
    throw Error("pixel noise: ignore mask size does not match the image");
  }
  if (row_step < 1 || column_step < 1) throw Error("pixel noise: steps must be positive");
  DifferenceNoise noise;
  bool any = false;
  for (int y = row_step / 2; y < image.height; y += row_step) {
    const std::uint8_t* row = image.data + static_cast<std::ptrdiff_t>(y) * image.stride;
    for (int x = column_step / 2 + 1; x < image.width; x += column_step) {
      if (!ignore.looked(x, y) || !ignore.looked(x - 1, y)) continue;
      noise.add(int(row[x]) - int(row[x - 1]));
      any = true;
    }
  }
  return any ? noise.sigma() / std::sqrt(2.0) : 0;
}

double frameLightGray(const GrayView& image, const IgnoreMask& ignore) {
  std::uint32_t hist[256] = {};
  std::uint32_t n = 0;
  for (int pass = 0; pass < 2 && n == 0; ++pass) {
    for (int y = 2; y < image.height; y += 4) {
      const std::uint8_t* row = image.row(y);
      for (int x = 2; x < image.width; x += 4) {
        if (pass == 0 && !ignore.looked(x, y)) continue;
        ++hist[row[x]];
        ++n;
      }
    }
  }
  std::uint32_t acc = 0;
  for (int g = 0; g < 256; ++g) {
    acc += hist[g];
    if (2 * acc >= n) return g;
  }
  return 255;
}

}  // namespace colorfree
