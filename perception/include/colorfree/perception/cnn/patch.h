#pragma once

#include "colorfree/perception/image.h"

namespace colorfree::cnn {

/// An axis-aligned box in image pixels: top-left corner and size (pixel centres at integer + 0.5).
struct PatchBox {
  float x_px = 0.0f;
  float y_px = 0.0f;
  float width_px = 0.0f;
  float height_px = 0.0f;
};

/// How grey values (0..255) become the net's input.
enum class PatchNormalization {
  kUnitRange,    ///< v / 255
  kStandardize,  ///< (v − patch mean) / max(patch standard deviation, kMinStddev):
                 ///< lighting-invariant
};

/// How a box becomes width × height samples.
enum class PatchResampling {
  kBilinear,  ///< each sample interpolated between the four pixels about its centre: a box many
              ///< times the patch's size is read at a few pixels only (aliasing)
  kArea,      ///< each sample the mean of the box's pixels under its footprint (its share of the
              ///< box, at least one pixel wide; a one-pixel footprint is the bilinear sample)
};

/// Floor of the standard deviation in kStandardize, in grey levels, so flat patches stay bounded.
inline constexpr float kMinStddev = 4.0f;

/// Crops `box` from `image`, resamples it to width × height (pixels outside the image repeat the
/// border) and normalises it into `out` (width × height floats, rows top-down). Bilinear: no
/// allocation; area: buffers per thread that grow to the largest image seen. Throws
/// colorfree::Error for an empty image, an empty box or a size > 256.
void extractPatch(const GrayView& image, const PatchBox& box, int width, int height,
                  PatchNormalization normalization, float* out,
                  PatchResampling resampling = PatchResampling::kBilinear);

/// The width × height patch `in` (rows top-down) mirrored left to right into `out` (not `in`).
void mirrorPatch(const float* in, int width, int height, float* out);

/// Normalises `count` grey values (0..255) in place.
void normalizePatch(float* values, int count, PatchNormalization normalization);

/// Unsharp mask in place on a width × height patch (rows top-down): v + amount × (v − G_σ v), with
/// G_σ a Gaussian blur of standard deviation `sigma_px` (patch pixels; the border repeated). It
/// undoes part of a soft lens's blur; a flat patch stays as it is. Throws colorfree::Error for an
/// empty or oversized patch, sigma_px <= 0 or amount < 0.
void unsharpMask(float* values, int width, int height, double sigma_px, double amount);

/// Richardson–Lucy deconvolution in place on a width × height patch of grey values (rows top-down,
/// 0..255) blurred by a straight motion: the mean of the sharp patch over the segment from −(dx, dy)/2
/// to +(dx, dy)/2 (patch pixels; a camera turning during the exposure). `iterations` steps
/// x ← x · Bᵀ(observed / B x), B that blur (bilinear, the border repeated): the smear's length is
/// taken back in part, the more the more steps, noise rising with them. A segment shorter than a
/// pixel, or 0 iterations, leaves the patch as it is. Throws colorfree::Error for an empty or
/// oversized patch, a negative iteration count or a segment longer than the patch.
void deblurAlong(float* values, int width, int height, double dx_px, double dy_px, int iterations);

}  // namespace colorfree::cnn
