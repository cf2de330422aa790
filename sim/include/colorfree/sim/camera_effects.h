#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "colorfree/perception/image.h"
#include "colorfree/sim/scenario.h"

namespace colorfree::sim {

/// Luma in grey levels as floats (0..255, not yet rounded), rows top-down.
struct FloatImage {
  int width = 0;
  int height = 0;
  std::vector<float> pixels;

  float at(int x, int y) const { return pixels[static_cast<std::size_t>(y) * width + x]; }
};
FloatImage toFloat(const GrayImage& image);

/// When the sub-frames of one frame are rendered and how each image row mixes them.
///
/// Row r is exposed during [c_r - E/2, c_r + E/2] around the frame time, where E is the exposure
/// time (0 without motion blur) and c_r = 0 with a global shutter, or spreads the readout time
/// evenly from the first row to the last with a rolling shutter (the middle row at 0). The
/// exposures of all rows are covered by sub-frames of equal length; a row averages the
/// sub-frames weighted by how much of its exposure falls into each (a box filter in time).
class ExposurePlan {
 public:
  ExposurePlan(const EffectsSpec& effects, int height_px);

  /// Sub-frame times relative to the frame time, seconds, ascending.
  const std::vector<double>& subframeTimes() const { return times_s_; }
  /// (sub-frame, weight) pairs of one row; the weights add up to 1.
  const std::vector<std::pair<int, float>>& rowWeights(int row) const { return rows_[row]; }
  int height() const { return static_cast<int>(rows_.size()); }
  /// True when a single render at the frame time is the whole exposure.
  bool isInstant() const { return times_s_.size() == 1 && times_s_[0] == 0.0; }
  /// E, the time one row is exposed (0 without motion blur), seconds.
  double exposureS() const { return exposure_s_; }
  /// The time from the first row's exposure to the last's (0 with a global shutter), seconds.
  double readoutS() const { return readout_s_; }

 private:
  double exposure_s_ = 0;
  double readout_s_ = 0;
  std::vector<double> times_s_;
  std::vector<std::vector<std::pair<int, float>>> rows_;
};

/// Most sub-frames one frame may take.
inline constexpr int kMaxSubframes = 256;

/// Mixes the sub-frames (rendered at plan.subframeTimes()) row by row. Throws colorfree::Error
/// when the count or the sizes do not match the plan.
FloatImage composeSubframes(const std::vector<GrayImage>& subframes, const ExposurePlan& plan);

/// Box blur along `step_px` over its length (centred): what the gap between two consecutive
/// sub-frames, `step_px` apart in the image, would have been filled with had the exposure been
/// rendered continuously. composeSubframes' average of K sub-frames shifted by the step, smeared so,
/// is a continuous smear of K steps instead of K ghost copies. Steps under a pixel change nothing;
/// pixels beyond the image repeat the edge. Throws colorfree::Error for a non-finite step.
FloatImage smearAlong(const FloatImage& image, double step_x_px, double step_y_px);

/// The lens, before the sensor: a Gaussian point spread of σ = `defocus_px` (separable, pixels
/// beyond the image repeat the edge; 0 leaves the image as it is), then veiling glare, the share
/// `veiling_glare` of the light scattered evenly over the frame: value × (1 − g) + g × the frame's
/// mean. Both keep the frame's mean light (up to the edge repeat); glare lifts the blacks and
/// flattens contrast as a real lens in a dim hall does. Throws colorfree::Error for a value out of
/// range (σ not in [0, 20], g not in [0, 0.9], or not finite).
FloatImage applyOptics(FloatImage image, const EffectsSpec& effects);

/// Exposure/gain and sensor noise: value × gain, plus Gaussian noise of variance
/// noise_sigma² + shot_noise × value, rounded and clipped to 0..255. `seed` fixes the noise.
GrayImage applySensor(const FloatImage& exposure, const EffectsSpec& effects, std::uint64_t seed);

/// The noise seed of one frame, from the scenario seed and the frame index.
std::uint64_t frameSeed(std::uint64_t scenario_seed, int frame_index);

}  // namespace colorfree::sim
