#include "plane_runner.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "colorfree/perception/error.h"
#include "lane_kernels.h"

namespace colorfree::cnn::detail {

namespace {

inline Vec loadu(const float* p) {
  Vec v;
  std::memcpy(&v, p, sizeof(Vec));
  return v;
}

typedef int IVec __attribute__((vector_size(kLanes * sizeof(int))));

IVec stepMask(int first) {
  IVec m;
  for (int i = 0; i < kLanes; ++i) m[i] = first + 2 * i;
  return m;
}
const IVec kEven = stepMask(0);
const IVec kOdd = stepMask(1);
const IVec kIota = stepMask(0) / 2;

inline float activateScalar(float v, Activation a) {
  return a == Activation::kLeaky && v < 0.0f ? v * kLeakySlope : v;
}

// Sums of NB output channels over `vectors` × kLanes flattened positions; see the header.
// Sums of NB output channels over `vectors` × kLanes flattened positions; see the header.
// Without `mask`: raw sums into dst[j]. With it: activated, multiplied by the mask (0 on
// positions that fall into margin columns, so the margins stay zero), into dst[j].
template <int NB>
void convPlanes(int C, int K, const int* offsets, const float* const* planes, const float* w,
                const float* bias, int vectors, float* const* dst, const float* mask,
                Activation a) {
  for (int t = 0; t < vectors; ++t) {
    Vec acc[NB];
    for (int j = 0; j < NB; ++j) acc[j] = splat(bias[j]);
    const float* wk = w;
    for (int c = 0; c < C; ++c) {
      const float* src = planes[c] + t * kLanes;
      for (int k = 0; k < K * K; ++k) {
        const Vec v = loadu(src + offsets[k]);
        for (int j = 0; j < NB; ++j) acc[j] += weight(wk + j * kWeightWidth) * v;
        wk += NB * kWeightWidth;
      }
    }
    if (mask != nullptr) {
      const Vec m = loadu(mask + t * kLanes);
      for (int j = 0; j < NB; ++j) acc[j] = activate(acc[j], a) * m;
    }
    for (int j = 0; j < NB; ++j) std::memcpy(dst[j] + t * kLanes, &acc[j], sizeof(Vec));
  }
}

template <int NB>
struct ConvPlanesRun {
  static void run(int o, int C, int K, const int* offsets, const float* const* planes,
                  const float* w, const float* bias, int vectors, float* const* dst,
                  const float* mask, Activation a) {
    convPlanes<NB>(C, K, offsets, planes,
                   w + static_cast<std::size_t>(o) * C * K * K * kWeightWidth, bias + o, vectors,
                   dst + o, mask, a);
  }
};

// Max over Darknet pool windows of a plane (origin `src`, rows `stride` apart, h × w valid),
// activated, written to `dst` (rows `dst_stride` apart).
void maxPoolPlane(const Layer& pool, const float* src, int stride, int h, int w, Activation a,
                  float* dst, int dst_stride) {
  const int off = -pool.pad / 2, S = pool.stride, K = pool.size;
  for (int oy = 0; oy < pool.out.height; ++oy) {
    const int y0 = oy * S + off;
    float* out = dst + static_cast<std::size_t>(oy) * dst_stride;
    if (K == 2 && S == 2 && off == 0 && y0 + 1 < h) {
      const float* r0 = src + static_cast<std::size_t>(y0) * stride;
      const float* r1 = r0 + stride;
      const int full = std::min(pool.out.width, w / 2);
      int ox = 0;
      // kLanes outputs at a time: even and odd columns of two rows, by shuffles. Reads may run
      // past the row (into the margin or the slack).
      for (; ox < full; ox += kLanes) {
        const Vec a0 = loadu(r0 + 2 * ox), a1 = loadu(r0 + 2 * ox + kLanes);
        const Vec b0 = loadu(r1 + 2 * ox), b1 = loadu(r1 + 2 * ox + kLanes);
        const Vec ra = __builtin_shuffle(a0, a1, kEven), rb = __builtin_shuffle(a0, a1, kOdd);
        const Vec sa = __builtin_shuffle(b0, b1, kEven), sb = __builtin_shuffle(b0, b1, kOdd);
        Vec m = ra > rb ? ra : rb;
        const Vec n = sa > sb ? sa : sb;
        m = activate(m > n ? m : n, a);
        // Lanes past the row become 0 and land in the margin, the next row (written after
        // this one) or the gap after the plane.
        const Vec zero = {};
        m = kIota < (full - ox) ? m : zero;
        std::memcpy(out + ox, &m, sizeof(Vec));
      }
      for (int ox = full; ox < pool.out.width; ++ox) {
        float m = -std::numeric_limits<float>::infinity();
        for (int x = 2 * ox; x < std::min(w, 2 * ox + 2); ++x) m = std::max({m, r0[x], r1[x]});
        out[ox] = activateScalar(m, a);
      }
      continue;
    }
    const int ya = std::max(0, y0), yb = std::min(h, y0 + K);
    for (int ox = 0; ox < pool.out.width; ++ox) {
      const int x0 = ox * S + off;
      const int xa = std::max(0, x0), xb = std::min(w, x0 + K);
      float m = -std::numeric_limits<float>::infinity();
      for (int y = ya; y < yb; ++y) {
        for (int x = xa; x < xb; ++x)
          m = std::max(m, src[static_cast<std::size_t>(y) * stride + x]);
      }
      out[ox] = activateScalar(m, a);
    }
  }
}

}  // namespace

PlaneRunner::PlaneRunner(const Net& net) : net_(net) {
  const auto& layers = net.layers();
  for (const Layer& l : layers) {
    if (l.type == LayerType::kConvolution && l.filters > kMaxChannels) {
      throw Error("cnn: a convolution with more than " + std::to_string(kMaxChannels) + " filters");
    }
  }
  for (const Layer& l : layers) {
    if (l.type == LayerType::kConvolution) {
      margin_ = std::max(margin_, l.pad);
    }
  }
  const Shape& s = net.input();
  input_ = makeTensor(s.height, s.width, s.channels);
  outputs_.resize(layers.size());
  packed_.resize(layers.size());
  std::size_t scratch = 0;
  for (std::size_t i = 0; i < layers.size(); ++i) {
    const Layer& l = layers[i];
    if (l.type == LayerType::kRoute) {
      outputs_[i].height = l.out.height;
      outputs_[i].width = l.out.width;
      for (int j : l.inputs) {
        outputs_[i].stride = outputs_[j].stride;
        outputs_[i].rows = outputs_[j].rows;
        outputs_[i].planes.insert(outputs_[i].planes.end(), outputs_[j].planes.begin(),
                                  outputs_[j].planes.end());
      }
    } else {
      outputs_[i] = makeTensor(l.out.height, l.out.width, l.out.channels);
    }
    if (l.type == LayerType::kConvolution) {
      packed_[i].assign((l.param_count - l.filters) * kWeightWidth, 0.0f);
      const int in_stride = l.in.width + 2 * margin_;
      const int vectors = (l.out.height * in_stride + kLanes - 1) / kLanes;
      scratch = std::max(scratch, static_cast<std::size_t>(vectors) * kLanes * l.filters);
    }
  }
  scratch_.assign(scratch + 4 * kLanes, 0.0f);  // slack for the pooling's vector reads
  masks_.resize(layers.size());
  for (std::size_t i = 0; i < layers.size(); ++i) {
    const Layer& l = layers[i];
    if (l.type != LayerType::kConvolution || l.stride != 1 || !(l.out.height == l.in.height) ||
        !(l.out.width == l.in.width)) {
      continue;
    }
    const int stride = l.in.width + 2 * margin_;
    const int vectors = (l.out.height * stride + kLanes - 1) / kLanes;
    masks_[i].assign(static_cast<std::size_t>(vectors) * kLanes, 0.0f);
    for (int t = 0; t < vectors * kLanes; ++t) {
      masks_[i][t] = (t % stride < l.out.width && t / stride < l.out.height) ? 1.0f : 0.0f;
    }
  }
  fused_.assign(layers.size(), false);
  std::vector<bool> routed(layers.size(), false);
  for (const Layer& l : layers) {
    for (int j : l.inputs) routed[j] = true;
  }
  for (std::size_t i = 0; i + 1 < layers.size(); ++i) {
    fused_[i] = layers[i].type == LayerType::kConvolution && layers[i].stride == 1 &&
                layers[i].size * layers[i].size <= kMaxTaps &&
                layers[i + 1].type == LayerType::kMaxPool && !routed[i];
  }
  result_.assign(net.output().size(), 0.0f);
  repack();
}

PlaneRunner::Tensor PlaneRunner::makeTensor(int height, int width, int channels) {
  Tensor t;
  t.height = height;
  t.width = width;
  t.stride = width + 2 * margin_;
  t.rows = height + 2 * margin_;
  // A gap after every plane takes the masked zeros a vector writes past a plane's end.
  const std::size_t plane = static_cast<std::size_t>(t.rows) * t.stride + 2 * kLanes + margin_;
  // Slack after the last plane: a vector of flattened positions may read past the valid rows.
  const std::size_t slack = static_cast<std::size_t>(4 * margin_ + 8) * t.stride + 4 * kLanes;
  storage_.emplace_back(plane * channels + slack, 0.0f);
  float* base = storage_.back().data();
  for (int c = 0; c < channels; ++c) t.planes.push_back(base + plane * c);
  return t;
}

void PlaneRunner::repack() {
  const auto& layers = net_.layers();
  for (std::size_t i = 0; i < layers.size(); ++i) {
    const Layer& l = layers[i];
    if (l.type != LayerType::kConvolution) continue;
    const float* w = net_.params().data() + l.param_offset + l.filters;
    const int C = l.in.channels, K = l.size, O = l.filters;
    for (int o0 = 0; o0 < O; o0 += kBlock) {
      const int nb = std::min(kBlock, O - o0);
      float* block = packed_[i].data() + static_cast<std::size_t>(o0) * C * K * K * kWeightWidth;
      for (int j = 0; j < nb; ++j) {
        for (int c = 0; c < C; ++c) {
          for (int k = 0; k < K * K; ++k) {
            float* dst =
                block + ((static_cast<std::size_t>(c) * K * K + k) * nb + j) * kWeightWidth;
            std::fill(dst, dst + kWeightWidth,
                      w[(static_cast<std::size_t>(o0 + j) * C + c) * K * K + k]);
          }
        }
      }
    }
  }
}

void PlaneRunner::convScalar(int i, const Tensor& in, Tensor& out) {
  const Layer& l = net_.layers()[i];
  const float* w = net_.params().data() + l.param_offset + l.filters;
  const float* b = net_.params().data() + l.param_offset;
  const int C = l.in.channels, K = l.size;
  for (int o = 0; o < l.filters; ++o) {
    for (int oy = 0; oy < l.out.height; ++oy) {
      for (int ox = 0; ox < l.out.width; ++ox) {
        float acc = b[o];
        for (int c = 0; c < C; ++c) {
          for (int ky = 0; ky < K; ++ky) {
            const int iy = oy * l.stride - l.pad + ky;
            if (iy < 0 || iy >= l.in.height) continue;
            for (int kx = 0; kx < K; ++kx) {
              const int ix = ox * l.stride - l.pad + kx;
              if (ix < 0 || ix >= l.in.width) continue;
              acc += w[((static_cast<std::size_t>(o) * C + c) * K + ky) * K + kx] *
                     *valueAt(in, c, iy, ix);
            }
          }
        }
        *valueAt(out, o, oy, ox) = activateScalar(acc, l.activation);
      }
    }
  }
}

void PlaneRunner::conv(int i, const Tensor& in, Tensor& out) {
  const Layer& l = net_.layers()[i];
  const int K = l.size, P = l.pad, M = margin_;
  // Offsets of the kernel taps from an output position, in the input's flattened padded plane.
  int offsets[kMaxTaps];
  for (int ky = 0; ky < K; ++ky) {
    for (int kx = 0; kx < K; ++kx) offsets[ky * K + kx] = (ky - P + M) * in.stride + (kx - P + M);
  }
  const int vectors = (l.out.height * in.stride + kLanes - 1) / kLanes;
  const int scratch_stride = vectors * kLanes;
  // Planes start at their corner (the margin included): position t = y * stride + x.
  const float* const* planes = in.planes.data();
  const float* bias = net_.params().data() + l.param_offset;
  float* dst[kMaxChannels];
  if (fused_[i] || masks_[i].empty()) {
    for (int o = 0; o < l.filters; ++o)
      dst[o] = scratch_.data() + static_cast<std::size_t>(o) * scratch_stride;
    forBlocks<ConvPlanesRun>(l.filters, l.in.channels, K, offsets, planes, packed_[i].data(), bias,
                             vectors, dst, nullptr, l.activation);
  } else {
    // Same plane size in and out: position t of the input is position t of the output.
    for (int o = 0; o < l.filters; ++o) dst[o] = valueAt(out, o, 0, 0);
    forBlocks<ConvPlanesRun>(l.filters, l.in.channels, K, offsets, planes, packed_[i].data(), bias,
                             vectors, dst, masks_[i].data(), l.activation);
    return;
  }
  if (fused_[i]) {
    // Straight from the sums into the max pool's output: activation after the maximum.
    const Layer& pool = net_.layers()[i + 1];
    Tensor& pooled = outputs_[i + 1];
    for (int o = 0; o < l.filters; ++o) {
      maxPoolPlane(pool, scratch_.data() + static_cast<std::size_t>(o) * scratch_stride, in.stride,
                   l.out.height, l.out.width, l.activation, valueAt(pooled, o, 0, 0),
                   pooled.stride);
    }
    return;
  }
  for (int o = 0; o < l.filters; ++o) {
    const float* src = scratch_.data() + static_cast<std::size_t>(o) * scratch_stride;
    for (int y = 0; y < l.out.height; ++y) {
      const float* row = src + static_cast<std::size_t>(y) * in.stride;
      float* d = valueAt(out, o, y, 0);
      for (int x = 0; x < l.out.width; ++x) d[x] = activateScalar(row[x], l.activation);
    }
  }
}

void PlaneRunner::maxPool(int i, const Tensor& in, Tensor& out) {
  const Layer& l = net_.layers()[i];
  for (int c = 0; c < l.in.channels; ++c) {
    maxPoolPlane(l, valueAt(in, c, 0, 0), in.stride, l.in.height, l.in.width, Activation::kLinear,
                 valueAt(out, c, 0, 0), out.stride);
  }
}

const float* PlaneRunner::run(const float* input) {
  const Shape& s = net_.input();
  for (int c = 0; c < s.channels; ++c) {
    for (int y = 0; y < s.height; ++y) {
      std::memcpy(valueAt(input_, c, y, 0),
                  input + (static_cast<std::size_t>(c) * s.height + y) * s.width,
                  sizeof(float) * s.width);
    }
  }
  const auto& layers = net_.layers();
  const float* params = net_.params().data();
  for (std::size_t i = 0; i < layers.size(); ++i) {
    const Layer& l = layers[i];
    const Tensor& in = i == 0 ? input_ : outputs_[i - 1];
    Tensor& out = outputs_[i];
    switch (l.type) {
      case LayerType::kConvolution:
        if (l.stride == 1 && l.size * l.size <= kMaxTaps) {
          conv(static_cast<int>(i), in, out);
          if (fused_[i]) ++i;
        } else {
          convScalar(static_cast<int>(i), in, out);
        }
        break;
      case LayerType::kMaxPool:
        maxPool(static_cast<int>(i), in, out);
        break;
      case LayerType::kGlobalAvgPool: {
        const float scale = 1.0f / static_cast<float>(l.in.height * l.in.width);
        for (int c = 0; c < l.in.channels; ++c) {
          float sum = 0.0f;
          for (int y = 0; y < l.in.height; ++y) {
            const float* row = valueAt(in, c, y, 0);
            for (int x = 0; x < l.in.width; ++x) sum += row[x];
          }
          *valueAt(out, c, 0, 0) = sum * scale;
        }
        break;
      }
      case LayerType::kConnected: {
        const float* b = params + l.param_offset;
        const float* w = b + l.filters;
        const int n = l.in.size();
        for (int o = 0; o < l.filters; ++o) {
          float acc = b[o];
          const float* wo = w + static_cast<std::size_t>(o) * n;
          for (int c = 0; c < l.in.channels; ++c) {
            for (int y = 0; y < l.in.height; ++y) {
              const float* row = valueAt(in, c, y, 0);
              const float* wr = wo + (c * l.in.height + y) * l.in.width;
              for (int x = 0; x < l.in.width; ++x) acc += wr[x] * row[x];
            }
          }
          *valueAt(out, o, 0, 0) = activateScalar(acc, l.activation);
        }
        break;
      }
      case LayerType::kSoftmax: {
        const int C = l.in.channels;
        float m = *valueAt(in, 0, 0, 0);
        for (int c = 1; c < C; ++c) m = std::max(m, *valueAt(in, c, 0, 0));
        float sum = 0.0f;
        for (int c = 0; c < C; ++c) {
          const float e = std::exp(*valueAt(in, c, 0, 0) - m);
          *valueAt(out, c, 0, 0) = e;
          sum += e;
        }
        for (int c = 0; c < C; ++c) *valueAt(out, c, 0, 0) /= sum;
        break;
      }
      case LayerType::kRoute:
        break;  // its planes are its inputs' planes
    }
  }
  const Tensor& last = outputs_.back();
  for (int c = 0; c < net_.output().channels; ++c) result_[c] = *valueAt(last, c, 0, 0);
  return result_.data();
}

}  // namespace colorfree::cnn::detail
