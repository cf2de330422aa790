#include "lane_runner.h"

#include <cstring>

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace colorfree::cnn::detail {

void packWeights(const Layer& l, const float* params, float* packed) {
  const float* w = params + l.param_offset + l.filters;
  const int O = l.filters;
  for (int o0 = 0; o0 < O; o0 += kBlock) {
    const int nb = std::min(kBlock, O - o0);
    if (l.type == LayerType::kConvolution) {
      const int C = l.in.channels, K = l.size;
      float* block = packed + static_cast<std::size_t>(o0) * K * K * C * kWeightWidth;
      for (int j = 0; j < nb; ++j) {
        for (int c = 0; c < C; ++c) {
          for (int ky = 0; ky < K; ++ky) {
            for (int kx = 0; kx < K; ++kx) {
              float* dst = block + (((static_cast<std::size_t>(ky) * K + kx) * C + c) * nb + j) *
                                       kWeightWidth;
              std::fill(dst, dst + kWeightWidth,
                        w[((static_cast<std::size_t>(o0 + j) * C + c) * K + ky) * K + kx]);
            }
          }
        }
      }
    } else if (l.type == LayerType::kConnected) {
      const int C = l.in.channels, H = l.in.height, W = l.in.width, n = l.in.size();
      float* block = packed + static_cast<std::size_t>(o0) * n * kWeightWidth;
      for (int j = 0; j < nb; ++j) {
        for (int c = 0; c < C; ++c) {
          for (int y = 0; y < H; ++y) {
            for (int x = 0; x < W; ++x) {
              float* dst =
                  block + (static_cast<std::size_t>((y * W + x) * C + c) * nb + j) * kWeightWidth;
              std::fill(dst, dst + kWeightWidth,
                        w[static_cast<std::size_t>(o0 + j) * n + (c * H + y) * W + x]);
            }
          }
        }
      }
    }
  }
}

LaneRunner::LaneRunner(const Net& net, bool inference) : net_(net) {
  const auto& layers = net.layers();
  input_.assign(net.input().size(), splat(0.0f));
  outputs_.resize(layers.size());
  packed_.resize(layers.size());
  route_sources_.resize(layers.size());
  route_channels_.resize(layers.size());
  for (std::size_t i = 0; i < layers.size(); ++i) {
    const Layer& l = layers[i];
    outputs_[i].assign(l.out.size(), splat(0.0f));
    if (l.param_count > 0) packed_[i].assign((l.param_count - l.filters) * kWeightWidth, 0.0f);
  }
  const std::size_t n = layers.size();
  out_ptr_.resize(n);
  out_stride_.resize(n);
  skip_.assign(n, false);
  fused_.assign(n, false);
  for (std::size_t i = 0; i < n; ++i) {
    out_ptr_[i] = outputs_[i].data();
    out_stride_[i] = layers[i].out.channels;
  }
  if (inference) {
    // consumers[j]: the layers that read layer j's output.
    std::vector<std::vector<int>> consumers(n);
    for (std::size_t i = 0; i < n; ++i) {
      if (layers[i].type == LayerType::kRoute) {
        for (int j : layers[i].inputs) consumers[j].push_back(static_cast<int>(i));
      } else if (i > 0) {
        consumers[i - 1].push_back(static_cast<int>(i));
      }
    }
    for (std::size_t i = 0; i + 1 < n; ++i) {
      fused_[i] = layers[i].type == LayerType::kConvolution &&
                  layers[i + 1].type == LayerType::kMaxPool && consumers[i].size() == 1;
    }
    // A layer that writes its output itself (a convolution, a max pool or a convolution fused
    // with the max pool after it) can write into the one route that is its only reader.
    const auto writesDirectly = [&](int j) {
      return (layers[j].type == LayerType::kConvolution && !fused_[j]) ||
             layers[j].type == LayerType::kMaxPool;
    };
    for (std::size_t r = 0; r < n; ++r) {
      const Layer& l = layers[r];
      if (l.type != LayerType::kRoute) continue;
      if (l.inputs.size() == 1) {
        const int j = l.inputs[0];
        if (out_stride_[j] == layers[j].out.channels) {
          out_ptr_[r] = out_ptr_[j];
          skip_[r] = true;
        }
        continue;
      }
      bool all = true;
      for (int j : l.inputs) {
        all = all && writesDirectly(j) && consumers[j].size() == 1 &&
              consumers[j][0] == static_cast<int>(r) &&
              std::count(l.inputs.begin(), l.inputs.end(), j) == 1;
      }
      if (!all) continue;
      int offset = 0;
      for (int j : l.inputs) {
        out_ptr_[j] = out_ptr_[r] + offset;
        out_stride_[j] = l.out.channels;
        offset += layers[j].out.channels;
      }
      skip_[r] = true;
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    for (int j : layers[i].inputs) {
      route_sources_[i].push_back(out_ptr_[j]);
      route_channels_[i].push_back(layers[j].out.channels);
    }
  }
  repack();
}

void LaneRunner::repack() {
  const auto& layers = net_.layers();
  for (std::size_t i = 0; i < layers.size(); ++i) {
    if (layers[i].param_count > 0) packWeights(layers[i], net_.params().data(), packed_[i].data());
  }
}

#if defined(__AVX512F__)
namespace {
// r[i][j] becomes r[j][i].
inline void transpose16(__m512* r) {
  __m512 t[16];
  for (int i = 0; i < 16; i += 2) {
    t[i] = _mm512_unpacklo_ps(r[i], r[i + 1]);
    t[i + 1] = _mm512_unpackhi_ps(r[i], r[i + 1]);
  }
  for (int i = 0; i < 16; i += 4) {
    for (int k = 0; k < 2; ++k) {
      r[i + 2 * k] = _mm512_castpd_ps(
          _mm512_unpacklo_pd(_mm512_castps_pd(t[i + k]), _mm512_castps_pd(t[i + 2 + k])));
      r[i + 2 * k + 1] = _mm512_castpd_ps(
          _mm512_unpackhi_pd(_mm512_castps_pd(t[i + k]), _mm512_castps_pd(t[i + 2 + k])));
    }
  }
  // Now r[4g + m] holds, in its 128-bit lane L, column 4L + m of rows 4g .. 4g + 3.
  for (int i = 0; i < 16; i += 8) {
    for (int k = 0; k < 4; ++k) {
      t[i + k] = _mm512_shuffle_f32x4(r[i + k], r[i + 4 + k], 0x88);
      t[i + 4 + k] = _mm512_shuffle_f32x4(r[i + k], r[i + 4 + k], 0xdd);
    }
  }
  for (int k = 0; k < 8; ++k) {
    r[k] = _mm512_shuffle_f32x4(t[k], t[k + 8], 0x88);
    r[k + 8] = _mm512_shuffle_f32x4(t[k], t[k + 8], 0xdd);
  }
}
}  // namespace
#endif

void LaneRunner::setInput(const float* samples, int count) {
  const Shape& s = net_.input();
  const int plane = s.height * s.width, C = s.channels, n = s.size();
  // Built a whole vector at a time (scalar stores into vectors stall the loads that follow).
  const float* src[kLanes];
  for (int b = 0; b < kLanes; ++b)
    src[b] = samples + static_cast<std::size_t>(std::min(b, count - 1)) * n;
  for (int c = 0; c < C; ++c) {
    int p = 0;
#if defined(__AVX512F__)
    // 16 positions of the 16 samples at a time: a 16x16 transpose in registers.
    if constexpr (kLanes == 16) {
      for (; p + 16 <= plane; p += 16) {
        __m512 r[16];
        for (int b = 0; b < 16; ++b) {
          r[b] = b < count ? _mm512_loadu_ps(src[b] + c * plane + p) : _mm512_setzero_ps();
        }
        transpose16(r);
        for (int k = 0; k < 16; ++k) {
          std::memcpy(static_cast<void*>(&input_[static_cast<std::size_t>(p + k) * C + c]), &r[k],
                      sizeof(Vec));
        }
      }
    }
#endif
    for (; p < plane; ++p) {
      Vec v;
      for (int b = 0; b < kLanes; ++b) v[b] = b < count ? src[b][c * plane + p] : 0.0f;
      input_[static_cast<std::size_t>(p) * C + c] = v;
    }
  }
}

void LaneRunner::forward() {
  const auto& layers = net_.layers();
  const float* params = net_.params().data();
  for (std::size_t i = 0; i < layers.size(); ++i) {
    const Layer& l = layers[i];
    const Vec* in = i == 0 ? input_.data() : out_ptr_[i - 1];
    Vec* out = out_ptr_[i];
    switch (l.type) {
      case LayerType::kConvolution:
        if (fused_[i]) {
          convPoolForward(l, layers[i + 1], packed_[i].data(), params + l.param_offset, in,
                          out_ptr_[i + 1], out_stride_[i + 1]);
          ++i;
        } else {
          convForward(l, packed_[i].data(), params + l.param_offset, in, out, out_stride_[i]);
        }
        break;
      case LayerType::kConnected:
        connectedForward(l, packed_[i].data(), params + l.param_offset, in, out);
        break;
      case LayerType::kMaxPool:
        maxPoolForward(l, in, out, out_stride_[i]);
        break;
      case LayerType::kGlobalAvgPool:
        globalAvgPoolForward(l, in, out);
        break;
      case LayerType::kSoftmax:
        softmaxForward(l, in, out);
        break;
      case LayerType::kRoute:
        if (!skip_[i]) routeForward(l, route_sources_[i], route_channels_[i], out);
        break;
    }
  }
}

}  // namespace colorfree::cnn::detail
