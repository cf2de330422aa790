#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "colorfree/perception/ignore_regions.h"
#include "colorfree/perception/image.h"
#include "colorfree/perception/percepts.h"

namespace colorfree {

/// Parameters of the high-contrast region detector (perception/params/high_contrast.yaml).
struct HighContrastParams {
  int window_px = 16;  ///< window side (the paper: 16 × 16)
  /// Minimum contrast of a window: the between-class standard deviation at Otsu's threshold,
  /// sqrt(w0 · w1) · (mean1 − mean0), in gray levels. It is at most the window's standard
  /// deviation, so windows below it are skipped before their histogram is built.
  double min_contrast = 22;
  /// ... or this × the frame's light (`frameLightGray`) where that is lower: in a dark hall or
  /// behind a soft lens a robot's or a ball's edges fall under the absolute value (in a frame whose
  /// median gray is above min_contrast / this nothing changes). 0: the absolute value only.
  double light_contrast_fraction = 0.3;
  /// ... but never below this (gray levels): a black or a flat frame marks nothing.
  double light_min_contrast = 8;
  /// A frame in which fewer than this fraction of the looked-at windows pass (a soft lens, where
  /// every edge is spread over more than a window) is marked with sparse_light_contrast_fraction
  /// instead of light_contrast_fraction (light_min_contrast still the floor). 0: never.
  double sparse_max_seed_fraction = 0.1;
  double sparse_light_contrast_fraction = 0.2;
  /// A window counts as looked at when its centre pixel is outside the ignored regions.
  int row_step_px = 2;        ///< a window's statistics and histogram use every this-th row
  int dilation_windows = 1;  ///< the marked set is dilated by this many windows in every direction

  bool operator==(const HighContrastParams&) const = default;
  static HighContrastParams load(const std::string& path);
  static HighContrastParams loadDefault();
};

/// A connected set of high-contrast windows.
struct ContrastRegion {
  PixelBox box;          ///< pixel box of its windows
  int window_count = 0;  ///< after dilation
};

/// The windows with high contrast (after dilation) and their connected regions.
struct ContrastRegions {
  int window_px = 16;
  int columns = 0;  ///< windows per row
  int rows = 0;     ///< windows per column
  /// Row-major, 1 where marked (after dilation).
  std::vector<std::uint8_t> mask;
  /// Row-major, 1 where the window itself passed the contrast test (before dilation).
  std::vector<std::uint8_t> seeds;
  /// Row-major: the window's contrast, 0 for windows not looked at or skipped by the pre-test.
  std::vector<float> contrast;
  std::vector<ContrastRegion> regions;

  bool marked(int column, int row) const { return mask[row * columns + column] != 0; }
  int markedCount() const;
};

/// Scans the image in windows, thresholds each window's histogram (32 bins of 8 gray levels) with
/// Otsu's method and keeps the windows whose two classes are far enough apart (paper 2.2).
class HighContrastDetector {
 public:
  explicit HighContrastDetector(HighContrastParams params = {});
  /// `light_gray`: the frame's frameLightGray(image, ignore) when the caller has it (the pipeline's
  /// Frame does); estimated here when absent and light_contrast_fraction asks for it.
  ContrastRegions run(const GrayView& image, const IgnoreMask& ignore,
                      std::optional<double> light_gray = std::nullopt) const;
  const HighContrastParams& params() const { return params_; }

 private:
  HighContrastParams params_;
};

/// Otsu's threshold of a 256-bin histogram, with the separation of the two classes there.
/// Exposed for the tests.
struct OtsuResult {
  int threshold = 0;          ///< class 0 holds the values <= threshold
  double between_std = 0;     ///< sqrt(w0 w1) (mean1 − mean0)
  double mean0 = 0, mean1 = 0;
};
OtsuResult otsu(const std::uint32_t* histogram256);
/// The same over `bins` bins, each with its count and the sum of its values; `threshold` is then
/// the last bin of class 0. The detector uses 32 bins of 8 gray levels.
OtsuResult otsuBinned(const std::uint32_t* count, const std::uint32_t* value_sum, int bins);

}  // namespace colorfree
