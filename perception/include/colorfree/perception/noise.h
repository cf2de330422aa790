#pragma once

#include <cstdint>

#include "colorfree/perception/ignore_regions.h"
#include "colorfree/perception/image.h"

namespace colorfree {

/// The spread of differences of neighbouring pixels, from their median absolute value (edges of
/// lines and robots are a small share of the samples): the standard deviation they would have as
/// Gaussian noise.
class DifferenceNoise {
 public:
  void add(int difference) {
    ++histogram_[difference < 0 ? -difference : difference];
    ++n_;
  }
  double sigma() const;

 private:
  std::uint32_t histogram_[256] = {};
  std::uint32_t n_ = 0;
};

/// A frame's pixel noise (gray levels): the spread of the differences of horizontally
/// neighbouring pixels inside the looked-at area, on every row_step-th row and column_step-th
/// column (rows are read in memory order), over sqrt(2). 0 where nothing is looked at.
double pixelNoiseGray(const GrayView& image, const IgnoreMask& ignore, int row_step = 16,
                      int column_step = 8);

/// A frame's light (gray levels): the median of the looked-at pixels (every 4th pixel of every 4th
/// row); of the whole image when nothing is looked at.
double frameLightGray(const GrayView& image, const IgnoreMask& ignore);

}  // namespace colorfree
