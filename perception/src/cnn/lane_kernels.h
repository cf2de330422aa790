#pragma once

// The kernels of the engine and the trainer. Activations are stored "batch in lanes":
// element (y, x, c) of sample b lives at [((y * W + x) * C + c) * kLanes + b], so every
// operation is one vector operation over kLanes samples whatever the layer's shape, and the
// compiler maps a Vec to one AVX-512 register, two AVX registers or four SSE registers.

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "colorfree/perception/cnn/net.h"

namespace colorfree::cnn::detail {

// One native vector register per Vec: 16 floats with AVX-512, 8 with AVX, 4 with SSE.
#if defined(__AVX512F__)
inline constexpr int kLanes = 16;
#elif defined(__AVX__)
inline constexpr int kLanes = 8;
#else
inline constexpr int kLanes = 4;
#endif
typedef float Vec __attribute__((vector_size(kLanes * sizeof(float))));

// Output channels per register block: 8 accumulators fit beside the operands in 16 registers.
inline constexpr int kBlock = 8;

// v − 0 is v for every float (v + 0 is not, for −0), so this folds into a plain broadcast.
inline Vec splat(float v) {
  const Vec zero = {};
  return v - zero;
}

inline Vec activate(Vec v, Activation a) {
  if (a == Activation::kLeaky) return v > 0.0f ? v : v * kLeakySlope;
  return v;
}

// With AVX a multiply-add broadcasts a scalar weight from memory for free; SSE has no such
// operand, so there the packed weights are stored already broadcast, one Vec per weight.
#if defined(__AVX__)
inline constexpr int kWeightWidth = 1;
inline Vec weight(const float* p) { return splat(*p); }
#else
inline constexpr int kWeightWidth = kLanes;
inline Vec weight(const float* p) {
  Vec v;
  std::memcpy(&v, p, sizeof(Vec));
  return v;
}
#endif

/// Weights reordered for the loops: convolution [o][ky][kx][c]; connected [o][y][x][c].
void packWeights(const Layer& l, const float* params, float* packed);

// ---- forward ----------------------------------------------------------------------------------

// Packed weights come in blocks of kBlock output channels (the last block may be smaller), the
// channels of a block interleaved innermost: convolution [block][ky][kx][c][j], connected
// [block][i][j], so one pointer walks all weights a register block needs.
// Pre-activation sums of output channels o0..o0+NB from the taps ky0..ky1-1 × kx0..kx1-1 of the
// kernel window whose top-left input pixel is (iy0, ix0); the taps outside the input are left
// out, not added as zeros. K > 0: the kernel side as a compile-time constant (and, when CF > 0,
// the input channels too), in loops the compiler unrolls; K = 0: the layer's side at run time.
// Every caller sums the same products in the same order.
template <int NB, int K, int CF>
__attribute__((always_inline)) inline void convTaps(const Layer& l, const float* wb,
                                                    const float* bias, int o0, const Vec* in,
                                                    int iy0, int ix0, int ky0, int ky1, int kx0,
                                                    int kx1, Vec* acc) {
  const int C = CF > 0 ? CF : l.in.channels, Win = l.in.width;
  const int k = K > 0 ? K : l.size;
  for (int j = 0; j < NB; ++j) acc[j] = splat(bias[o0 + j]);
  for (int ky = 0; ky < k; ++ky) {
    if (ky < ky0 || ky >= ky1) continue;
    const Vec* row = in + (static_cast<std::ptrdiff_t>(iy0 + ky) * Win + ix0) * C;
    const float* wrow = wb + static_cast<std::size_t>(ky * k) * C * NB * kWeightWidth;
    for (int kx = 0; kx < k; ++kx) {
      if (kx < kx0 || kx >= kx1) continue;
      const Vec* px = row + kx * C;
      const float* wk = wrow + kx * C * NB * kWeightWidth;
      for (int c = 0; c < C; ++c) {
        const Vec v = px[c];
        for (int j = 0; j < NB; ++j) acc[j] += weight(wk + (c * NB + j) * kWeightWidth) * v;
      }
    }
  }
}

// Pre-activation sums of output channels o0..o0+NB at output pixel (oy, ox). Where a kernel of
// a constant side lies wholly inside the input, the taps' bounds are constants too: no checks.
template <int NB, int K, int CF>
inline void convAt(const Layer& l, const float* wb, const float* bias, int o0, const Vec* in,
                   int oy, int ox, Vec* acc) {
  const int k = K > 0 ? K : l.size, Hin = l.in.height, Win = l.in.width;
  const int iy0 = oy * l.stride - l.pad, ix0 = ox * l.stride - l.pad;
  if constexpr (K > 0) {
    if (iy0 >= 0 && ix0 >= 0 && iy0 + K <= Hin && ix0 + K <= Win) {
      convTaps<NB, K, CF>(l, wb, bias, o0, in, iy0, ix0, 0, K, 0, K, acc);
      return;
    }
  }
  convTaps<NB, K, CF>(l, wb, bias, o0, in, iy0, ix0, std::max(0, -iy0), std::min(k, Hin - iy0),
                      std::max(0, -ix0), std::min(k, Win - ix0), acc);
}

// Calls f.template operator()<K, CF>() with the layer's kernel side as a constant where it is one
// of the shipped nets' (1, 3, 5; one input channel as well for 3), else with K = 0.
template <typename F>
inline void withKernel(const Layer& l, F&& f) {
  if (l.size == 3 && l.in.channels == 1) return f.template operator()<3, 1>();
  if (l.size == 3) return f.template operator()<3, 0>();
  if (l.size == 1) return f.template operator()<1, 0>();
  if (l.size == 5) return f.template operator()<5, 0>();
  f.template operator()<0, 0>();
}

// `out` may be a slice of a wider buffer (a route's concatenation): `O` channels per pixel.
template <int NB>
inline void convBlock(const Layer& l, const float* w, const float* bias, int o0, const Vec* in,
                      Vec* out, int O) {
  const float* wb =
      w + static_cast<std::size_t>(o0) * l.size * l.size * l.in.channels * kWeightWidth;
  withKernel(l, [&]<int K, int CF>() {
    for (int oy = 0; oy < l.out.height; ++oy) {
      for (int ox = 0; ox < l.out.width; ++ox) {
        Vec acc[NB];
        convAt<NB, K, CF>(l, wb, bias, o0, in, oy, ox, acc);
        Vec* po = out + (static_cast<std::size_t>(oy) * l.out.width + ox) * O + o0;
        for (int j = 0; j < NB; ++j) po[j] = activate(acc[j], l.activation);
      }
    }
  });
}

// A convolution followed by a max pool, without storing the convolution's output: the
// activation is monotonic, so the maximum of the pre-activations is taken and activated once.
template <int NB>
inline void convPoolBlock(const Layer& l, const Layer& pool, const float* w, const float* bias,
                          int o0, const Vec* in, Vec* out, int O) {
  const float* wb =
      w + static_cast<std::size_t>(o0) * l.size * l.size * l.in.channels * kWeightWidth;
  const int off = -pool.pad / 2;
  withKernel(l, [&]<int K, int CF>() {
    for (int py = 0; py < pool.out.height; ++py) {
      const int cy0 = py * pool.stride + off;
      const int y0 = std::max(0, cy0), y1 = std::min(l.out.height, cy0 + pool.size);
      for (int px = 0; px < pool.out.width; ++px) {
        const int cx0 = px * pool.stride + off;
        const int x0 = std::max(0, cx0), x1 = std::min(l.out.width, cx0 + pool.size);
        Vec best[NB];
        for (int j = 0; j < NB; ++j) best[j] = splat(-std::numeric_limits<float>::infinity());
        for (int y = y0; y < y1; ++y) {
          for (int x = x0; x < x1; ++x) {
            Vec acc[NB];
            convAt<NB, K, CF>(l, wb, bias, o0, in, y, x, acc);
            for (int j = 0; j < NB; ++j) best[j] = acc[j] > best[j] ? acc[j] : best[j];
          }
        }
        Vec* po = out + (static_cast<std::size_t>(py) * pool.out.width + px) * O + o0;
        for (int j = 0; j < NB; ++j) po[j] = activate(best[j], l.activation);
      }
    }
  });
}

template <int NB>
inline void connectedBlock(const Layer& l, const float* w, const float* bias, int o0, const Vec* in,
                           Vec* out) {
  const int n = l.in.size();
  Vec acc[NB];
  for (int j = 0; j < NB; ++j) acc[j] = splat(bias[o0 + j]);
  const float* wb = w + static_cast<std::size_t>(o0) * n * kWeightWidth;
  for (int i = 0; i < n; ++i) {
    const Vec v = in[i];
    for (int j = 0; j < NB; ++j) acc[j] += weight(wb + (i * NB + j) * kWeightWidth) * v;
  }
  for (int j = 0; j < NB; ++j) out[o0 + j] = activate(acc[j], l.activation);
}

// Calls F<kBlock> on each full block of output channels and F<rest> once on the last block.
template <template <int> class F, int NB = kBlock, typename... Args>
inline void lastBlock(int rest, int o, Args&&... args) {
  if constexpr (NB > 0) {
    if (rest == NB) return F<NB>::run(o, args...);
    lastBlock<F, NB - 1>(rest, o, args...);
  }
}

template <template <int> class F, typename... Args>
inline void forBlocks(int count, Args&&... args) {
  int o = 0;
  for (; o + kBlock <= count; o += kBlock) F<kBlock>::run(o, args...);
  if (o < count) lastBlock<F>(count - o, o, args...);
}

template <int NB>
struct ConvRun {
  static void run(int o, const Layer& l, const float* w, const float* b, const Vec* in, Vec* out,
                  int out_stride) {
    convBlock<NB>(l, w, b, o, in, out, out_stride);
  }
};
template <int NB>
struct ConvPoolRun {
  static void run(int o, const Layer& l, const Layer& pool, const float* w, const float* b,
                  const Vec* in, Vec* out, int out_stride) {
    convPoolBlock<NB>(l, pool, w, b, o, in, out, out_stride);
  }
};
template <int NB>
struct ConnectedRun {
  static void run(int o, const Layer& l, const float* w, const float* b, const Vec* in, Vec* out) {
    connectedBlock<NB>(l, w, b, o, in, out);
  }
};

inline void convForward(const Layer& l, const float* w, const float* b, const Vec* in, Vec* out,
                        int out_stride) {
  forBlocks<ConvRun>(l.out.channels, l, w, b, in, out, out_stride);
}

inline void convPoolForward(const Layer& l, const Layer& pool, const float* w, const float* b,
                            const Vec* in, Vec* out, int out_stride) {
  forBlocks<ConvPoolRun>(l.out.channels, l, pool, w, b, in, out, out_stride);
}

inline void connectedForward(const Layer& l, const float* w, const float* b, const Vec* in,
                             Vec* out) {
  forBlocks<ConnectedRun>(l.out.channels, l, w, b, in, out);
}

// Darknet's max pool: windows start at -padding/2; values outside the input are ignored.
inline void maxPoolForward(const Layer& l, const Vec* in, Vec* out, int out_stride) {
  const int C = l.in.channels, Hin = l.in.height, Win = l.in.width;
  const int off = -l.pad / 2;
  for (int oy = 0; oy < l.out.height; ++oy) {
    const int iy0 = oy * l.stride + off;
    const int y0 = std::max(0, iy0), y1 = std::min(Hin, iy0 + l.size);
    for (int ox = 0; ox < l.out.width; ++ox) {
      const int ix0 = ox * l.stride + off;
      const int x0 = std::max(0, ix0), x1 = std::min(Win, ix0 + l.size);
      Vec* po = out + (static_cast<std::size_t>(oy) * l.out.width + ox) * out_stride;
      for (int c = 0; c < C; ++c) po[c] = splat(-std::numeric_limits<float>::infinity());
      for (int y = y0; y < y1; ++y) {
        for (int x = x0; x < x1; ++x) {
          const Vec* pi = in + (static_cast<std::size_t>(y) * Win + x) * C;
          for (int c = 0; c < C; ++c) po[c] = pi[c] > po[c] ? pi[c] : po[c];
        }
      }
    }
  }
}

inline void globalAvgPoolForward(const Layer& l, const Vec* in, Vec* out) {
  const int C = l.in.channels, n = l.in.height * l.in.width;
  for (int c = 0; c < C; ++c) out[c] = splat(0.0f);
  for (int p = 0; p < n; ++p) {
    for (int c = 0; c < C; ++c) out[c] += in[static_cast<std::size_t>(p) * C + c];
  }
  const float scale = 1.0f / static_cast<float>(n);
  for (int c = 0; c < C; ++c) out[c] *= scale;
}

inline void softmaxForward(const Layer& l, const Vec* in, Vec* out) {
  const int C = l.in.channels;
  for (int b = 0; b < kLanes; ++b) {
    float m = in[0][b];
    for (int c = 1; c < C; ++c) m = std::max(m, in[c][b]);
    float sum = 0.0f;
    for (int c = 0; c < C; ++c) {
      const float e = std::exp(in[c][b] - m);
      out[c][b] = e;
      sum += e;
    }
    const float inv = 1.0f / sum;
    for (int c = 0; c < C; ++c) out[c][b] *= inv;
  }
}

/// Copies the routed layers' channels side by side. `sources[k]` is the output of inputs[k].
inline void routeForward(const Layer& l, const std::vector<const Vec*>& sources,
                         const std::vector<int>& source_channels, Vec* out) {
  const int n = l.out.height * l.out.width, C = l.out.channels;
  for (int p = 0; p < n; ++p) {
    Vec* po = out + static_cast<std::size_t>(p) * C;
    for (std::size_t k = 0; k < sources.size(); ++k) {
      const int ck = source_channels[k];
      std::memcpy(static_cast<void*>(po), sources[k] + static_cast<std::size_t>(p) * ck,
                  sizeof(Vec) * ck);
      po += ck;
    }
  }
}

}  // namespace colorfree::cnn::detail
