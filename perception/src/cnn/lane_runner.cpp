#include "lane_runner.h"

namespace colorfree::cnn::detail {

void packWeights(const Layer& l, const float* params, float* packed) {
  const float* w = params + l.param_offset + l.filters;
  const int O = l.filters;
  for (int o0 = 0; o0 < O; o0 += kBlock) {
    const int nb = std::min(kBlock, O - o0);
    if (l.type == LayerType::kConvolution) {
      const int C = l.in.channels, K = l.size;
      float* block = packed + static_cast<std::size_t>(o0) * K * K * C;
      for (int j = 0; j < nb; ++j) {
        for (int c = 0; c < C; ++c) {
          for (int ky = 0; ky < K; ++ky) {
            for (int kx = 0; kx < K; ++kx) {
              block[((static_cast<std::size_t>(ky) * K + kx) * C + c) * nb + j] =
                  w[((static_cast<std::size_t>(o0 + j) * C + c) * K + ky) * K + kx];
            }
          }
        }
      }
    } else if (l.type == LayerType::kConnected) {
      const int C = l.in.channels, H = l.in.height, W = l.in.width, n = l.in.size();
      float* block = packed + static_cast<std::size_t>(o0) * n;
      for (int j = 0; j < nb; ++j) {
        for (int c = 0; c < C; ++c) {
          for (int y = 0; y < H; ++y) {
            for (int x = 0; x < W; ++x) {
              block[static_cast<std::size_t>((y * W + x) * C + c) * nb + j] =
                  w[static_cast<std::size_t>(o0 + j) * n + (c * H + y) * W + x];
            }
          }
        }
      }
    }
  }
}

LaneRunner::LaneRunner(const Net& net, bool fuse) : net_(net) {
  const auto& layers = net.layers();
  input_.assign(net.input().size(), splat(0.0f));
  outputs_.resize(layers.size());
  packed_.resize(layers.size());
  route_sources_.resize(layers.size());
  route_channels_.resize(layers.size());
  for (std::size_t i = 0; i < layers.size(); ++i) {
    const Layer& l = layers[i];
    outputs_[i].assign(l.out.size(), splat(0.0f));
    if (l.param_count > 0) packed_[i].assign(l.param_count - l.filters, 0.0f);
  }
  for (std::size_t i = 0; i < layers.size(); ++i) {
    for (int j : layers[i].inputs) {
      route_sources_[i].push_back(outputs_[j].data());
      route_channels_[i].push_back(layers[j].out.channels);
    }
  }
  fused_.assign(layers.size(), false);
  if (fuse) {
    std::vector<bool> routed(layers.size(), false);
    for (const Layer& l : layers) {
      for (int j : l.inputs) routed[j] = true;
    }
    for (std::size_t i = 0; i + 1 < layers.size(); ++i) {
      fused_[i] = layers[i].type == LayerType::kConvolution && layers[i + 1].type == LayerType::kMaxPool &&
                  !routed[i];
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

void LaneRunner::setInput(const float* samples, int count) {
  const Shape& s = net_.input();
  const int plane = s.height * s.width, C = s.channels, n = s.size();
  for (int b = 0; b < kLanes; ++b) {
    if (b < count) {
      const float* src = samples + static_cast<std::size_t>(b) * n;
      for (int c = 0; c < C; ++c) {
        for (int p = 0; p < plane; ++p) input_[static_cast<std::size_t>(p) * C + c][b] = src[c * plane + p];
      }
    } else {
      for (int i = 0; i < n; ++i) input_[i][b] = 0.0f;
    }
  }
}

void LaneRunner::forward() {
  const auto& layers = net_.layers();
  const float* params = net_.params().data();
  for (std::size_t i = 0; i < layers.size(); ++i) {
    const Layer& l = layers[i];
    const Vec* in = i == 0 ? input_.data() : outputs_[i - 1].data();
    Vec* out = outputs_[i].data();
    switch (l.type) {
      case LayerType::kConvolution:
        if (fused_[i]) {
          convPoolForward(l, layers[i + 1], packed_[i].data(), params + l.param_offset, in,
                          outputs_[i + 1].data());
          ++i;
        } else {
          convForward(l, packed_[i].data(), params + l.param_offset, in, out);
        }
        break;
      case LayerType::kConnected:
        connectedForward(l, packed_[i].data(), params + l.param_offset, in, out);
        break;
      case LayerType::kMaxPool:
        maxPoolForward(l, in, out);
        break;
      case LayerType::kGlobalAvgPool:
        globalAvgPoolForward(l, in, out);
        break;
      case LayerType::kSoftmax:
        softmaxForward(l, in, out);
        break;
      case LayerType::kRoute:
        routeForward(l, route_sources_[i], route_channels_[i], out);
        break;
    }
  }
}

}  // namespace colorfree::cnn::detail
