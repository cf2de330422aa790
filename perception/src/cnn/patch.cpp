#include "colorfree/perception/cnn/patch.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

#include "colorfree/perception/error.h"

namespace colorfree::cnn {

namespace {
constexpr int kMaxPatchSide = 256;
// The widest stretch of a row (pixels) the fast path of extractPatch blends in one buffer.
constexpr int kMaxSpan = 1024;
// The resampling reads two neighbouring pixels as one little-endian 16-bit word.
static_assert(std::endian::native == std::endian::little);
}  // namespace

namespace {
constexpr int kParts = 16;
typedef float Parts __attribute__((vector_size(kParts * sizeof(float))));

// sum[k] and sum_sq[k] over values[k], values[k + 16], ... of the first count / 16 * 16 values,
// each square rounded before it is added (no fused multiply-add: the sums the nets were judged
// with). Whole vectors of 16 partial sums: GCC's vectorisation of the loop over k moved most of
// them through scalar registers, at five times the time.
__attribute__((noinline, optimize("fp-contract=off"))) int partialSums(const float* values,
                                                                       int count, float* sum,
                                                                       float* sum_sq) {
  Parts s = {}, q = {};
  int i = 0;
  for (; i + kParts <= count; i += kParts) {
    Parts v;
    std::memcpy(&v, values + i, sizeof v);
    s += v;
    q += v * v;
  }
  std::memcpy(sum, &s, sizeof s);
  std::memcpy(sum_sq, &q, sizeof q);
  return i;
}
}  // namespace

void mirrorPatch(const float* in, int width, int height, float* out) {
  for (int y = 0; y < height; ++y) {
    std::reverse_copy(in + y * width, in + (y + 1) * width, out + y * width);
  }
}

void normalizePatch(float* values, int count, PatchNormalization normalization) {
  if (normalization == PatchNormalization::kUnitRange) {
    constexpr float kScale = 1.0f / 255.0f;
    for (int i = 0; i < count; ++i) values[i] *= kScale;
    return;
  }
  // Partial sums in a fixed order: vectorisable, and the same result on every machine.
  float sum[kParts], sum_sq[kParts];
  int i = partialSums(values, count, sum, sum_sq);
  for (; i < count; ++i) {
    sum[0] += values[i];
    sum_sq[0] += values[i] * values[i];
  }
  float total = 0.0f, total_sq = 0.0f;
  for (int k = 0; k < kParts; ++k) {
    total += sum[k];
    total_sq += sum_sq[k];
  }
  const float mean = total / static_cast<float>(count);
  const float var = std::max(0.0f, total_sq / static_cast<float>(count) - mean * mean);
  const float inv = 1.0f / std::max(std::sqrt(var), kMinStddev);
  for (int j = 0; j < count; ++j) values[j] = (values[j] - mean) * inv;
}

void unsharpMask(float* values, int width, int height, double sigma_px, double amount) {
  if (width <= 0 || height <= 0 || width > kMaxPatchSide || height > kMaxPatchSide) {
    throw Error("unsharpMask: patch size " + std::to_string(width) + "x" + std::to_string(height) +
                " outside 1..256");
  }
  if (!(sigma_px > 0) || !(amount >= 0)) {
    throw Error("unsharpMask: sigma " + std::to_string(sigma_px) + " px and amount " +
                std::to_string(amount) + " (need sigma > 0, amount >= 0)");
  }
  const int reach = std::max(1, static_cast<int>(std::ceil(3 * sigma_px)));
  std::vector<float> kernel(2 * reach + 1);
  float total = 0;
  for (int i = -reach; i <= reach; ++i) {
    total += kernel[i + reach] = static_cast<float>(std::exp(-0.5 * i * i / (sigma_px * sigma_px)));
  }
  for (float& k : kernel) k /= total;
  const auto clamp = [](int i, int n) { return std::min(n - 1, std::max(0, i)); };
  std::vector<float> rows(static_cast<std::size_t>(width) * height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      float s = 0;
      for (int i = -reach; i <= reach; ++i) {
        s += kernel[i + reach] * values[y * width + clamp(x + i, width)];
      }
      rows[y * width + x] = s;
    }
  }
  const float a = static_cast<float>(amount);
  std::vector<float> blurred(rows.size());
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      float s = 0;
      for (int i = -reach; i <= reach; ++i) {
        s += kernel[i + reach] * rows[clamp(y + i, height) * width + x];
      }
      blurred[y * width + x] = s;
    }
  }
  for (std::size_t i = 0; i < blurred.size(); ++i) values[i] += a * (values[i] - blurred[i]);
}

void deblurAlong(float* values, int width, int height, double dx_px, double dy_px, int iterations) {
  if (width <= 0 || height <= 0 || width > kMaxPatchSide || height > kMaxPatchSide) {
    throw Error("deblurAlong: patch size " + std::to_string(width) + "x" + std::to_string(height) +
                " outside 1..256");
  }
  const double length = std::hypot(dx_px, dy_px);
  if (iterations < 0 || !(length <= std::max(width, height))) {
    throw Error("deblurAlong: " + std::to_string(iterations) + " iterations and a smear of " +
                std::to_string(length) + " px on a " + std::to_string(width) + "x" +
                std::to_string(height) + " patch (need iterations >= 0, a smear within the patch)");
  }
  if (iterations == 0 || length < 1) return;
  // The blur as a small kernel of whole-pixel offsets: the mean of taps one pixel or less apart
  // along the segment, each read bilinearly (its four neighbours' weights the same at every pixel).
  const int taps = static_cast<int>(std::ceil(length)) + 1;
  std::vector<std::pair<std::pair<int, int>, float>> kernel;  // ((dx, dy), weight)
  for (int k = 0; k < taps; ++k) {
    const double t = static_cast<double>(k) / (taps - 1) - 0.5;
    const double x = t * dx_px, y = t * dy_px;
    const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
    const double fx = x - x0, fy = y - y0;
    const double w[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
    const int ox[4] = {x0, x0 + 1, x0, x0 + 1}, oy[4] = {y0, y0, y0 + 1, y0 + 1};
    for (int c = 0; c < 4; ++c) {
      if (w[c] <= 0) continue;
      auto it = std::find_if(kernel.begin(), kernel.end(),
                             [&](const auto& e) { return e.first == std::make_pair(ox[c], oy[c]); });
      if (it == kernel.end()) {
        kernel.push_back({{ox[c], oy[c]}, 0.0f});
        it = kernel.end() - 1;
      }
      it->second += static_cast<float>(w[c] / taps);
    }
  }
  // Each blur reads a copy with `pad` pixels of repeated border round it (no bounds in the loop).
  int pad = 0;
  for (const auto& e : kernel) pad = std::max({pad, std::abs(e.first.first), std::abs(e.first.second)});
  const int pw = width + 2 * pad;
  const std::size_t n = static_cast<std::size_t>(width) * height;
  std::vector<float> padded(static_cast<std::size_t>(pw) * (height + 2 * pad));
  // (the segment is symmetric about its middle: the blur is its own adjoint, up to the sampling)
  const auto blur = [&](const std::vector<float>& in, std::vector<float>& out) {
    for (int y = -pad; y < height + pad; ++y) {
      const float* src = &in[static_cast<std::size_t>(std::clamp(y, 0, height - 1)) * width];
      float* dst = &padded[static_cast<std::size_t>(y + pad) * pw];
      for (int x = -pad; x < width + pad; ++x) dst[x + pad] = src[std::clamp(x, 0, width - 1)];
    }
    std::fill(out.begin(), out.end(), 0.0f);
    for (const auto& [d, w] : kernel) {
      for (int y = 0; y < height; ++y) {
        const float* src = &padded[static_cast<std::size_t>(y + pad + d.second) * pw + pad + d.first];
        float* dst = &out[static_cast<std::size_t>(y) * width];
        for (int x = 0; x < width; ++x) dst[x] += w * src[x];
      }
    }
  };
  // Grey levels kept away from 0 (the ratio's denominator); the floor taken off at the end.
  constexpr float kFloor = 1.0f;
  std::vector<float> observed(values, values + n), estimate(n), blurred(n), ratio(n), back(n);
  for (float& v : observed) v = std::max(v, 0.0f) + kFloor;
  estimate = observed;
  for (int it = 0; it < iterations; ++it) {
    blur(estimate, blurred);
    for (std::size_t i = 0; i < n; ++i) ratio[i] = observed[i] / std::max(blurred[i], 1e-3f);
    blur(ratio, back);
    for (std::size_t i = 0; i < n; ++i) estimate[i] *= back[i];
  }
  for (std::size_t i = 0; i < n; ++i) values[i] = estimate[i] - kFloor;
}

namespace {

// The pixels one axis's samples average: sample k reads the source pixels start[k] ..
// start[k] + taps - 1 with the weights weight[j * samples + k] (j = 0 .. taps - 1: a sample
// with fewer pixels has zero weights after them), in 1/256 steps that add up to 256. The
// footprint of sample k is max(step, 1) pixels wide about its centre origin + (k + 0.5) step; a
// pixel i covers [i, i + 1) and weighs its overlap with the footprint over the footprint's width
// (rounded so that the running sum of weights is the rounded running sum of overlaps). Pixels
// outside 0..size-1 are the border pixel: a footprint reaching past the border is moved inside
// it, its outer weight joining the border pixel.
struct AxisTaps {
  int taps = 0;
  std::vector<int> start, weight;
};

void axisTaps(float origin, float step, int samples, int size, AxisTaps& out) {
  const double f = std::max(static_cast<double>(step), 1.0), n = size;
  // At most ceil(f) + 1 pixels per footprint, fewer where it is clamped.
  const int max_taps = std::min(static_cast<int>(std::ceil(f)) + 1, size);
  out.start.assign(static_cast<std::size_t>(samples), 0);
  out.weight.assign(static_cast<std::size_t>(samples) * max_taps, 0);
  out.taps = 1;
  for (int k = 0; k < samples; ++k) {
    const double centre = static_cast<double>(origin) + (k + 0.5) * static_cast<double>(step);
    const double a = centre - f / 2, b = centre + f / 2;
    // The footprint's pixels inside the image; the parts beyond it go to the border pixels.
    const double lo = std::clamp(a, 0.0, n), hi = std::clamp(b, 0.0, n);
    const int first = std::min(static_cast<int>(lo), size - 1);
    int last = std::max(first, static_cast<int>(std::ceil(hi)) - 1);
    last = std::min(last, size - 1);
    out.start[k] = first;
    double covered = std::max(0.0, std::min(b, 0.0) - a);  // left of (above) the image
    long given = 0;
    for (int i = first; i <= last; ++i) {
      covered += std::max(0.0, std::min(hi, i + 1.0) - std::max(lo, static_cast<double>(i)));
      if (i == size - 1) covered += std::max(0.0, b - std::max(a, n));  // right of (below) it
      const auto upto =
          i == last ? 256L : static_cast<long>(256.0 * std::min(covered / f, 1.0) + 0.5);
      out.weight[static_cast<std::size_t>(i - first) * samples + k] =
          static_cast<int>(upto - given);
      given = upto;
    }
    out.taps = std::max(out.taps, last - first + 1);
  }
}

// Separable, in integers: each patch row blends its source rows over the columns its samples
// read (at most 255 x 256 per column: 16 bits, vectorised), then each sample its columns.
void extractArea(const GrayView& image, const PatchBox& box, int width, int height, float* out) {
  thread_local AxisTaps xs, ys;
  thread_local std::vector<std::uint16_t> mid;
  axisTaps(box.x_px, box.width_px / static_cast<float>(width), width, image.width, xs);
  axisTaps(box.y_px, box.height_px / static_cast<float>(height), height, image.height, ys);
  // The columns the samples read (those past the image's right border have zero weights).
  const int x_lo = xs.start.front(), span = xs.start.back() + xs.taps - x_lo;
  const int inside = std::min(span, image.width - x_lo);
  mid.resize(static_cast<std::size_t>(span));
  std::uint16_t* __restrict m = mid.data();
  int column[kMaxPatchSide];
  for (int u = 0; u < width; ++u) column[u] = xs.start[u] - x_lo;
  constexpr float kScale = 1.0f / 65536.0f;
  for (int v = 0; v < height; ++v) {
    std::fill(m, m + span, std::uint16_t{0});
    for (int j = 0; j < ys.taps; ++j) {
      const auto w =
          static_cast<std::uint16_t>(ys.weight[static_cast<std::size_t>(j) * height + v]);
      if (w == 0) continue;
      const std::uint8_t* __restrict r = image.row(ys.start[v] + j) + x_lo;
      for (int i = 0; i < inside; ++i) m[i] = static_cast<std::uint16_t>(m[i] + w * r[i]);
    }
    float* o = out + static_cast<std::size_t>(v) * width;
    for (int u = 0; u < width; ++u) {
      int sum = 0;
      for (int j = 0; j < xs.taps; ++j) {
        sum += xs.weight[static_cast<std::size_t>(j) * width + u] * m[column[u] + j];
      }
      o[u] = static_cast<float>(sum) * kScale;
    }
  }
}

}  // namespace

void extractPatch(const GrayView& image, const PatchBox& box, int width, int height,
                  PatchNormalization normalization, float* out, PatchResampling resampling) {
  if (image.empty()) throw Error("extractPatch: empty image");
  if (width <= 0 || height <= 0 || width > kMaxPatchSide || height > kMaxPatchSide) {
    throw Error("extractPatch: patch size " + std::to_string(width) + "x" + std::to_string(height) +
                " outside 1..256");
  }
  if (!(box.width_px > 0.0f) || !(box.height_px > 0.0f) || !std::isfinite(box.x_px) ||
      !std::isfinite(box.y_px) || !std::isfinite(box.width_px) || !std::isfinite(box.height_px)) {
    throw Error("extractPatch: box must have a finite position and a positive size");
  }
  if (resampling == PatchResampling::kArea) {
    extractArea(image, box, width, height, out);
    normalizePatch(out, width * height, normalization);
    return;
  }
  // Bilinear weights in 1/256 steps: integer arithmetic per pixel, one conversion at the end.
  int x0[kMaxPatchSide], fx[kMaxPatchSide];
  const float sx = box.width_px / static_cast<float>(width);
  const float sy = box.height_px / static_cast<float>(height);
  const float max_x = static_cast<float>(image.width - 1),
              max_y = static_cast<float>(image.height - 1);
  for (int u = 0; u < width; ++u) {
    const float x = std::clamp(box.x_px + (static_cast<float>(u) + 0.5f) * sx - 0.5f, 0.0f, max_x);
    x0[u] = static_cast<int>(x);
    fx[u] = static_cast<int>((x - static_cast<float>(x0[u])) * 256.0f + 0.5f);
    // Both neighbours always inside the row, so one 16-bit read fetches the pair.
    if (x0[u] + 1 >= image.width) {
      x0[u] = std::max(0, image.width - 2);
      fx[u] = image.width >= 2 ? 256 : 0;
    }
  }
  // A one-pixel-wide image has no pair: read single bytes.
  const bool pairs = image.width >= 2;
  constexpr float kScale = 1.0f / 65536.0f;
  // The columns the samples read (x0 never decreases along the row).
  const int x_lo = x0[0], span = x0[width - 1] + 2 - x_lo;
  if (pairs && span <= kMaxSpan) {
    // Each row blends its two source rows vertically over the span (contiguous: vectorised),
    // then every sample the two columns it falls between. Vertical first gives the very
    // integers of horizontal first: both are 65536 a + 256 fx (b - a) + 256 fy (c - a) +
    // fx fy (a - b - c + d) for the pixels a b (upper row), c d (lower row). A vertical blend
    // 256 a + fy (c - a) lies in 0..65280: 16 bits hold it (the arithmetic is exact modulo
    // 2^16), so one 32-bit read fetches a sample's two columns.
    int column[kMaxPatchSide];
    for (int u = 0; u < width; ++u) column[u] = x0[u] - x_lo;
    std::uint16_t mid[kMaxSpan];
    for (int v = 0; v < height; ++v) {
      const float y =
          std::clamp(box.y_px + (static_cast<float>(v) + 0.5f) * sy - 0.5f, 0.0f, max_y);
      const int y0 = static_cast<int>(y);
      const int y1 = std::min(y0 + 1, image.height - 1);
      const int fy = static_cast<int>((y - static_cast<float>(y0)) * 256.0f + 0.5f);
      const std::uint8_t* r0 = image.row(y0) + x_lo;
      const std::uint8_t* r1 = image.row(y1) + x_lo;
      int i = 0;
#if defined(__SSE2__)
      // 16 columns a step, the last step ending at the span's end (overlapping the one before
      // it: the same values again), so no column is read beyond the span.
      if (span >= 16) {
        const __m128i zero = _mm_setzero_si128(), f = _mm_set1_epi16(static_cast<short>(fy));
        for (;; i += 16) {
          if (i + 16 > span) i = span - 16;
          const __m128i p0 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(r0 + i));
          const __m128i p1 = _mm_loadu_si128(reinterpret_cast<const __m128i*>(r1 + i));
          const __m128i a_lo = _mm_unpacklo_epi8(p0, zero), a_hi = _mm_unpackhi_epi8(p0, zero);
          const __m128i c_lo = _mm_unpacklo_epi8(p1, zero), c_hi = _mm_unpackhi_epi8(p1, zero);
          const __m128i m_lo =
              _mm_add_epi16(_mm_slli_epi16(a_lo, 8), _mm_mullo_epi16(_mm_sub_epi16(c_lo, a_lo), f));
          const __m128i m_hi =
              _mm_add_epi16(_mm_slli_epi16(a_hi, 8), _mm_mullo_epi16(_mm_sub_epi16(c_hi, a_hi), f));
          _mm_storeu_si128(reinterpret_cast<__m128i*>(mid + i), m_lo);
          _mm_storeu_si128(reinterpret_cast<__m128i*>(mid + i + 8), m_hi);
          if (i + 16 >= span) break;
        }
        i = span;
      }
#endif
      for (; i < span; ++i) {
        mid[i] = static_cast<std::uint16_t>(r0[i] * 256 + (r1[i] - r0[i]) * fy);
      }
      float* o = out + static_cast<std::size_t>(v) * width;
      int u = 0;
#if defined(__AVX2__)
      const __m256i low16 = _mm256_set1_epi32(0xffff);
      const __m256 scale = _mm256_set1_ps(kScale);
      for (; u + 8 <= width; u += 8) {
        const __m256i idx = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(column + u));
        const __m256i pair = _mm256_i32gather_epi32(reinterpret_cast<const int*>(mid), idx, 2);
        const __m256i a = _mm256_and_si256(pair, low16), b = _mm256_srli_epi32(pair, 16);
        const __m256i f = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(fx + u));
        const __m256i value = _mm256_add_epi32(_mm256_slli_epi32(a, 8),
                                               _mm256_mullo_epi32(_mm256_sub_epi32(b, a), f));
        _mm256_storeu_ps(o + u, _mm256_mul_ps(_mm256_cvtepi32_ps(value), scale));
      }
#endif
      for (; u < width; ++u) {
        const int a = mid[column[u]], b = mid[column[u] + 1];
        o[u] = static_cast<float>(a * 256 + (b - a) * fx[u]) * kScale;
      }
    }
    normalizePatch(out, width * height, normalization);
    return;
  }
  for (int v = 0; v < height; ++v) {
    const float y = std::clamp(box.y_px + (static_cast<float>(v) + 0.5f) * sy - 0.5f, 0.0f, max_y);
    const int y0 = static_cast<int>(y);
    const int y1 = std::min(y0 + 1, image.height - 1);
    const int fy = static_cast<int>((y - static_cast<float>(y0)) * 256.0f + 0.5f);
    const std::uint8_t* r0 = image.row(y0);
    const std::uint8_t* r1 = image.row(y1);
    float* o = out + static_cast<std::size_t>(v) * width;
    if (!pairs) {
      for (int u = 0; u < width; ++u)
        o[u] = static_cast<float>(r0[0] * 65536 + (r1[0] - r0[0]) * fy * 256) * kScale;
      continue;
    }
    for (int u = 0; u < width; ++u) {
      std::uint16_t p0, p1;
      std::memcpy(&p0, r0 + x0[u], 2);
      std::memcpy(&p1, r1 + x0[u], 2);
      const int a0 = p0 & 0xff, b0 = p0 >> 8, a1 = p1 & 0xff, b1 = p1 >> 8;
      const int top = a0 * 256 + (b0 - a0) * fx[u];
      const int bottom = a1 * 256 + (b1 - a1) * fx[u];
      o[u] = static_cast<float>(top * 256 + (bottom - top) * fy) * kScale;
    }
  }
  normalizePatch(out, width * height, normalization);
}

}  // namespace colorfree::cnn
