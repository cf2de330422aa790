#include "colorfree/perception/cnn/trainer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <random>

#include "colorfree/perception/error.h"
#include "lane_runner.h"

namespace colorfree::cnn {

using detail::kLanes;
using detail::splat;
using detail::Vec;

namespace {

// ---- backward kernels (batch in lanes, like the forward ones)
// ------------------------------------

// Turns dL/d(output) into dL/d(pre-activation), in place.
inline void activationBackward(Activation a, const Vec* out, Vec* grad, int n) {
  if (a != Activation::kLeaky) return;
  for (int i = 0; i < n; ++i) grad[i] = out[i] > 0.0f ? grad[i] : grad[i] * kLeakySlope;
}

// Weights as [o][ky][kx][c], gradients the same way with one Vec per weight.
void convBackward(const Layer& l, const float* w, const Vec* in, const Vec* out, Vec* dout,
                  Vec* din, Vec* gw, Vec* gb) {
  const int C = l.in.channels, Hin = l.in.height, Win = l.in.width;
  const int K = l.size, S = l.stride, P = l.pad, O = l.out.channels;
  const int ws = K * K * C;
  for (int oy = 0; oy < l.out.height; ++oy) {
    const int iy0 = oy * S - P;
    const int ky0 = std::max(0, -iy0), ky1 = std::min(K, Hin - iy0);
    for (int ox = 0; ox < l.out.width; ++ox) {
      const int ix0 = ox * S - P;
      const int kx0 = std::max(0, -ix0), kx1 = std::min(K, Win - ix0);
      const std::size_t po = (static_cast<std::size_t>(oy) * l.out.width + ox) * O;
      Vec* g = dout + po;
      activationBackward(l.activation, out + po, g, O);
      for (int o = 0; o < O; ++o) gb[o] += g[o];
      for (int ky = ky0; ky < ky1; ++ky) {
        for (int kx = kx0; kx < kx1; ++kx) {
          const std::size_t pi = (static_cast<std::size_t>(iy0 + ky) * Win + (ix0 + kx)) * C;
          const Vec* px = in + pi;
          const int tap = (ky * K + kx) * C;
          for (int o = 0; o < O; ++o) {
            const Vec go = g[o];
            Vec* gwk = gw + static_cast<std::size_t>(o) * ws + tap;
            for (int c = 0; c < C; ++c) gwk[c] += go * px[c];
          }
          if (din != nullptr) {
            Vec* dpx = din + pi;
            for (int o = 0; o < O; ++o) {
              const Vec go = g[o];
              const float* wk = w + static_cast<std::size_t>(o) * ws + tap;
              for (int c = 0; c < C; ++c) dpx[c] += wk[c] * go;
            }
          }
        }
      }
    }
  }
}

// Weights as [o][i] with i in the lanes' (y, x, c) order.
void connectedBackward(const Layer& l, const float* w, const Vec* in, const Vec* out, Vec* dout,
                       Vec* din, Vec* gw, Vec* gb) {
  const int n = l.in.size(), O = l.out.channels;
  activationBackward(l.activation, out, dout, O);
  for (int o = 0; o < O; ++o) {
    const Vec g = dout[o];
    gb[o] += g;
    Vec* gwo = gw + static_cast<std::size_t>(o) * n;
    for (int i = 0; i < n; ++i) gwo[i] += g * in[i];
    if (din != nullptr) {
      const float* wo = w + static_cast<std::size_t>(o) * n;
      for (int i = 0; i < n; ++i) din[i] += wo[i] * g;
    }
  }
}

// The gradient goes to the first input of the window that equals the maximum (per lane).
void maxPoolBackward(const Layer& l, const Vec* in, const Vec* out, const Vec* dout, Vec* din) {
  typedef int IVec __attribute__((vector_size(kLanes * sizeof(int))));
  const int C = l.in.channels, Hin = l.in.height, Win = l.in.width;
  const int off = -l.pad / 2;
  const Vec zero = {};
  for (int oy = 0; oy < l.out.height; ++oy) {
    const int iy0 = oy * l.stride + off;
    const int y0 = std::max(0, iy0), y1 = std::min(Hin, iy0 + l.size);
    for (int ox = 0; ox < l.out.width; ++ox) {
      const int ix0 = ox * l.stride + off;
      const int x0 = std::max(0, ix0), x1 = std::min(Win, ix0 + l.size);
      const std::size_t po = (static_cast<std::size_t>(oy) * l.out.width + ox) * C;
      for (int c = 0; c < C; ++c) {
        const Vec m = out[po + c], g = dout[po + c];
        IVec pending = {};
        pending = ~pending;
        for (int y = y0; y < y1; ++y) {
          for (int x = x0; x < x1; ++x) {
            const std::size_t pi = (static_cast<std::size_t>(y) * Win + x) * C + c;
            const IVec hit = (in[pi] == m) & pending;
            din[pi] += hit ? g : zero;
            pending &= ~hit;
          }
        }
      }
    }
  }
}

void globalAvgPoolBackward(const Layer& l, const Vec* dout, Vec* din) {
  const int C = l.in.channels, n = l.in.height * l.in.width;
  const float scale = 1.0f / static_cast<float>(n);
  for (int p = 0; p < n; ++p) {
    for (int c = 0; c < C; ++c) din[static_cast<std::size_t>(p) * C + c] += dout[c] * scale;
  }
}

void routeBackward(const Layer& l, const Vec* dout, const std::vector<Vec*>& dsources,
                   const std::vector<int>& channels) {
  const int n = l.out.height * l.out.width, C = l.out.channels;
  for (int p = 0; p < n; ++p) {
    const Vec* g = dout + static_cast<std::size_t>(p) * C;
    for (std::size_t k = 0; k < dsources.size(); ++k) {
      Vec* d = dsources[k] + static_cast<std::size_t>(p) * channels[k];
      for (int c = 0; c < channels[k]; ++c) d[c] += g[c];
      g += channels[k];
    }
  }
}

// ---- one net's forward and backward over kLanes samples ---------------------------------------

class Backprop {
 public:
  explicit Backprop(const Net& net) : net_(net), runner_(net) {
    const auto& layers = net.layers();
    if (layers.size() < 2 || layers.back().type != LayerType::kSoftmax) {
      throw Error("trainer: the net must end in [softmax] after at least one other layer");
    }
    for (std::size_t i = 0; i + 1 < layers.size(); ++i) {
      if (layers[i].type == LayerType::kSoftmax) {
        throw Error("trainer: [softmax] is only supported as the last layer");
      }
    }
    grads_.resize(layers.size());
    weights_.resize(layers.size());
    gw_.resize(layers.size());
    gb_.resize(layers.size());
    for (std::size_t i = 0; i < layers.size(); ++i) {
      grads_[i].assign(layers[i].out.size(), splat(0.0f));
      if (layers[i].param_count > 0) {
        weights_[i].assign(layers[i].param_count - layers[i].filters, 0.0f);
        gw_[i].assign(weights_[i].size(), splat(0.0f));
        gb_[i].assign(layers[i].filters, splat(0.0f));
      }
    }
    dinput_.assign(net.input().size(), splat(0.0f));
    route_grads_.resize(layers.size());
    route_channels_.resize(layers.size());
    for (std::size_t i = 0; i < layers.size(); ++i) {
      for (int j : layers[i].inputs) {
        route_grads_[i].push_back(grads_[j].data());
        route_channels_[i].push_back(layers[j].out.channels);
      }
    }
    repack();
  }

  void repack() {
    runner_.repack();
    const auto& layers = net_.layers();
    for (std::size_t i = 0; i < layers.size(); ++i) {
      const Layer& l = layers[i];
      if (l.param_count == 0) continue;
      forEachWeight(l, [&](std::size_t lane_index, std::size_t darknet_index) {
        weights_[i][lane_index] = net_.params()[darknet_index];
      });
    }
  }

  detail::LaneRunner& runner() { return runner_; }

  // Backward pass after runner().forward(): label < 0 or weight 0 marks an unused lane. Adds to
  // the lane gradient accumulators; returns the sum of weighted losses and counts correct lanes.
  double backward(const int* labels, const float* weights, bool want_input_grad, int* correct) {
    const auto& layers = net_.layers();
    const int last = static_cast<int>(layers.size()) - 1;
    for (int i = 0; i < last; ++i) std::fill(grads_[i].begin(), grads_[i].end(), splat(0.0f));
    if (want_input_grad) std::fill(dinput_.begin(), dinput_.end(), splat(0.0f));
    const Vec* p = runner_.output(last);
    Vec* dlogits = grads_[last - 1].data();
    const int K = layers[last].out.channels;
    double loss = 0.0;
    for (int b = 0; b < kLanes; ++b) {
      if (labels[b] < 0) continue;
      const float w = weights[b];
      int best = 0;
      for (int c = 0; c < K; ++c) {
        dlogits[c][b] = w * (p[c][b] - (c == labels[b] ? 1.0f : 0.0f));
        if (p[c][b] > p[best][b]) best = c;
      }
      if (correct != nullptr && best == labels[b]) ++*correct;
      loss -= w * std::log(std::max(p[labels[b]][b], 1e-30f));
    }
    for (int i = last - 1; i >= 0; --i) {
      const Layer& l = layers[i];
      const Vec* in = runner_.inputOf(i);
      Vec* din = i > 0 ? grads_[i - 1].data() : (want_input_grad ? dinput_.data() : nullptr);
      Vec* dout = grads_[i].data();
      const Vec* out = runner_.output(i);
      switch (l.type) {
        case LayerType::kConvolution:
          convBackward(l, weights_[i].data(), in, out, dout, din, gw_[i].data(), gb_[i].data());
          break;
        case LayerType::kConnected:
          connectedBackward(l, weights_[i].data(), in, out, dout, din, gw_[i].data(),
                            gb_[i].data());
          break;
        case LayerType::kMaxPool:
          if (din != nullptr) maxPoolBackward(l, in, out, dout, din);
          break;
        case LayerType::kGlobalAvgPool:
          if (din != nullptr) globalAvgPoolBackward(l, dout, din);
          break;
        case LayerType::kRoute:
          routeBackward(l, dout, route_grads_[i], route_channels_[i]);
          break;
        case LayerType::kSoftmax:
          break;  // only as the last layer, folded into the loss above
      }
    }
    return loss;
  }

  // Sums the lanes of the accumulated gradients, scaled, into `grad` (Net::params() order) and
  // clears the accumulators.
  void reduce(float scale, std::vector<float>& grad) {
    const auto& layers = net_.layers();
    for (std::size_t i = 0; i < layers.size(); ++i) {
      const Layer& l = layers[i];
      if (l.param_count == 0) continue;
      for (int o = 0; o < l.filters; ++o) grad[l.param_offset + o] += scale * laneSum(gb_[i][o]);
      forEachWeight(l, [&](std::size_t lane_index, std::size_t darknet_index) {
        grad[darknet_index] += scale * laneSum(gw_[i][lane_index]);
      });
      std::fill(gb_[i].begin(), gb_[i].end(), splat(0.0f));
      std::fill(gw_[i].begin(), gw_[i].end(), splat(0.0f));
    }
  }

  const Vec* inputGradient() const { return dinput_.data(); }

 private:
  static float laneSum(const Vec& v) {
    float s = 0.0f;
    for (int b = 0; b < kLanes; ++b) s += v[b];
    return s;
  }

  // Calls f(index in the backward layout, index in Net::params()) for every weight of `l`.
  template <typename F>
  static void forEachWeight(const Layer& l, F&& f) {
    const std::size_t base = l.param_offset + l.filters;
    if (l.type == LayerType::kConvolution) {
      const int C = l.in.channels, K = l.size;
      for (int o = 0; o < l.filters; ++o) {
        for (int c = 0; c < C; ++c) {
          for (int ky = 0; ky < K; ++ky) {
            for (int kx = 0; kx < K; ++kx) {
              f(((static_cast<std::size_t>(o) * K + ky) * K + kx) * C + c,
                base + ((static_cast<std::size_t>(o) * C + c) * K + ky) * K + kx);
            }
          }
        }
      }
    } else if (l.type == LayerType::kConnected) {
      const int C = l.in.channels, H = l.in.height, W = l.in.width, n = l.in.size();
      for (int o = 0; o < l.filters; ++o) {
        for (int c = 0; c < C; ++c) {
          for (int y = 0; y < H; ++y) {
            for (int x = 0; x < W; ++x) {
              f(static_cast<std::size_t>(o) * n + (y * W + x) * C + c,
                base + static_cast<std::size_t>(o) * n + (c * H + y) * W + x);
            }
          }
        }
      }
    }
  }

  const Net& net_;
  detail::LaneRunner runner_;
  std::vector<std::vector<Vec>> grads_;
  std::vector<std::vector<float>> weights_;
  std::vector<std::vector<Vec>> gw_, gb_;
  std::vector<Vec> dinput_;
  std::vector<std::vector<Vec*>> route_grads_;
  std::vector<std::vector<int>> route_channels_;
};

// ---- augmentation -----------------------------------------------------------------------------

// splitmix64: a small, fast, seeded generator for per-pixel noise.
inline std::uint64_t nextRandom(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// Zero mean, unit variance, bell-shaped: the sum of four uniforms (Irwin-Hall), scaled.
inline float approxNormal(std::uint64_t& state) {
  const std::uint64_t r = nextRandom(state);
  float sum = 0.0f;
  for (int k = 0; k < 4; ++k)
    sum += static_cast<float>((r >> (16 * k)) & 0xffff) * (1.0f / 65536.0f);
  return (sum - 2.0f) * 1.7320508f;
}

class Augmenter {
 public:
  Augmenter(int width, int height, const AugmentationParams& p)
      : w_(width), h_(height), p_(p), tmp_(static_cast<std::size_t>(width) * height) {}

  // Writes an augmented copy of `patch` (grey values) into `out`.
  void apply(const GrayImage& patch, bool flip_ok, std::mt19937_64& rng, float* out) {
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    const auto sym = [&](float a) { return a * (2.0f * unit(rng) - 1.0f); };
    const float scale = 1.0f + sym(p_.scale);
    const float dx = sym(p_.shift_px), dy = sym(p_.shift_px);
    const bool flip = flip_ok && unit(rng) < 0.5f;
    const float brightness = sym(p_.brightness) * 255.0f;
    const float contrast = 1.0f + sym(p_.contrast);
    const bool blur = unit(rng) < p_.blur_probability;
    const float sigma = p_.noise_stddev * unit(rng);
    std::uint64_t noise_state = rng();
    // Border cut: keep rows/columns [lo, hi] on one side, replicate the edge one beyond them.
    int u_lo = 0, u_hi = w_ - 1, v_lo = 0, v_hi = h_ - 1;
    if (p_.border_cut_probability > 0.0f && unit(rng) < p_.border_cut_probability) {
      const auto cut = [&](int side) {
        const float depth = p_.border_cut_max_fraction * (1.0f - unit(rng));  // (0, max]
        const int cut_u = std::clamp(static_cast<int>(depth * w_ + 0.5f), 1, w_ - 1);
        const int cut_v = std::clamp(static_cast<int>(depth * h_ + 0.5f), 1, h_ - 1);
        if (side == 0) u_lo = cut_u;
        if (side == 1) u_hi = w_ - 1 - cut_u;
        if (side == 2) v_lo = cut_v;
        if (side == 3) v_hi = h_ - 1 - cut_v;
      };
      const int side = static_cast<int>(unit(rng) * 4.0f) & 3;
      cut(side);
      if (p_.border_cut_corner_probability > 0.0f && unit(rng) < p_.border_cut_corner_probability) {
        // The adjacent side: a left/right cut gets a top/bottom one and the other way round.
        const int other = (side < 2 ? 2 : 0) + (unit(rng) < 0.5f ? 0 : 1);
        cut(other);
      }
    }
    const float cx = 0.5f * (w_ - 1), cy = 0.5f * (h_ - 1);
    const std::uint8_t* src = patch.data();
    for (int v = 0; v < h_; ++v) {
      const float y = std::clamp(cy + (v - cy) / scale + dy, 0.0f, static_cast<float>(h_ - 1));
      const int y0 = static_cast<int>(y), y1 = std::min(y0 + 1, h_ - 1);
      const float fy = y - y0;
      for (int u = 0; u < w_; ++u) {
        const float su = flip ? static_cast<float>(w_ - 1 - u) : static_cast<float>(u);
        const float x = std::clamp(cx + (su - cx) / scale + dx, 0.0f, static_cast<float>(w_ - 1));
        const int x0 = static_cast<int>(x), x1 = std::min(x0 + 1, w_ - 1);
        const float fx = x - x0;
        const float top = src[y0 * w_ + x0] + fx * (src[y0 * w_ + x1] - src[y0 * w_ + x0]);
        const float bottom = src[y1 * w_ + x0] + fx * (src[y1 * w_ + x1] - src[y1 * w_ + x0]);
        out[v * w_ + u] = top + fy * (bottom - top);
      }
    }
    if (u_lo > 0 || u_hi < w_ - 1 || v_lo > 0 || v_hi < h_ - 1) {
      for (int v = v_lo; v <= v_hi; ++v) {  // columns first, on the rows kept ...
        float* dst = out + v * w_;
        for (int u = 0; u < u_lo; ++u) dst[u] = dst[u_lo];
        for (int u = u_hi + 1; u < w_; ++u) dst[u] = dst[u_hi];
      }
      for (int v = 0; v < h_; ++v) {  // ... then the rows beyond the cut copy the nearest kept one
        const float* row = out + std::clamp(v, v_lo, v_hi) * w_;
        if (v < v_lo || v > v_hi) std::copy(row, row + w_, out + v * w_);
      }
    }
    const int n = w_ * h_;
    if (blur) {
      for (int v = 0; v < h_; ++v) {
        for (int u = 0; u < w_; ++u) {
          const float* r = out + v * w_;
          tmp_[v * w_ + u] =
              0.25f * r[std::max(u - 1, 0)] + 0.5f * r[u] + 0.25f * r[std::min(u + 1, w_ - 1)];
        }
      }
      for (int v = 0; v < h_; ++v) {
        for (int u = 0; u < w_; ++u) {
          out[v * w_ + u] = 0.25f * tmp_[std::max(v - 1, 0) * w_ + u] + 0.5f * tmp_[v * w_ + u] +
                            0.25f * tmp_[std::min(v + 1, h_ - 1) * w_ + u];
        }
      }
    }
    float mean = 0.0f;
    for (int i = 0; i < n; ++i) mean += out[i];
    mean /= static_cast<float>(n);
    for (int i = 0; i < n; ++i) {
      float value = (out[i] - mean) * contrast + mean + brightness;
      if (sigma > 0.0f) value += sigma * approxNormal(noise_state);
      out[i] = std::clamp(value, 0.0f, 255.0f);
    }
  }

 private:
  int w_, h_;
  AugmentationParams p_;
  std::vector<float> tmp_;
};

void patchToFloats(const GrayImage& patch, float* out) {
  const std::uint8_t* src = patch.data();
  const int n = patch.width() * patch.height();
  for (int i = 0; i < n; ++i) out[i] = src[i];
}

void checkData(const Net& net, const Dataset& data, const char* what) {
  if (net.input().channels != 1)
    throw Error("trainer: the net's input must be grayscale (1 channel)");
  if (data.width != net.input().width || data.height != net.input().height) {
    throw Error(std::string("trainer: ") + what + " patches are " + std::to_string(data.width) +
                "x" + std::to_string(data.height) + ", the net needs " +
                std::to_string(net.input().width) + "x" + std::to_string(net.input().height));
  }
  if (static_cast<int>(data.class_names.size()) != net.classes()) {
    throw Error(std::string("trainer: ") + what + " has " +
                std::to_string(data.class_names.size()) + " classes, the net " +
                std::to_string(net.classes()));
  }
  for (const Sample& s : data.samples) {
    if (s.label < 0 || s.label >= net.classes()) {
      throw Error(std::string("trainer: ") + what + " sample " + s.origin.file + " has label " +
                  std::to_string(s.label) + " out of range");
    }
    if (s.patch.width() != data.width || s.patch.height() != data.height) {
      throw Error(std::string("trainer: ") + what + " sample " + s.origin.file +
                  " has the wrong size");
    }
  }
}

Evaluation evaluateSamples(Backprop& bp, const Net& net,
                           const std::vector<const Sample*>& samples) {
  Evaluation e;
  const int K = net.classes(), n = net.input().size();
  e.confusion.assign(K, std::vector<int>(K, 0));
  e.samples = static_cast<int>(samples.size());
  std::vector<float> inputs(static_cast<std::size_t>(kLanes) * n);
  detail::LaneRunner& r = bp.runner();
  const int last = static_cast<int>(net.layers().size()) - 1;
  int correct = 0;
  for (std::size_t start = 0; start < samples.size(); start += kLanes) {
    const int m = static_cast<int>(std::min<std::size_t>(kLanes, samples.size() - start));
    for (int b = 0; b < m; ++b) {
      float* dst = inputs.data() + static_cast<std::size_t>(b) * n;
      patchToFloats(samples[start + b]->patch, dst);
      normalizePatch(dst, n, net.normalization());
    }
    r.setInput(inputs.data(), m);
    r.forward();
    const Vec* p = r.output(last);
    for (int b = 0; b < m; ++b) {
      const int label = samples[start + b]->label;
      int best = 0;
      for (int c = 1; c < K; ++c) {
        if (p[c][b] > p[best][b]) best = c;
      }
      ++e.confusion[label][best];
      if (best == label) {
        ++correct;
      } else {
        e.wrong.push_back(static_cast<int>(start) + b);
      }
      e.loss -= std::log(std::max(p[label][b], 1e-30f));
    }
  }
  if (e.samples > 0) {
    e.loss /= e.samples;
    e.accuracy = static_cast<double>(correct) / e.samples;
  }
  return e;
}

// Is `a` better than `b` for early stopping: accuracy first, then loss.
bool better(const Evaluation& a, const Evaluation& b) {
  if (a.accuracy != b.accuracy) return a.accuracy > b.accuracy;
  return a.loss < b.loss;
}

TrainResult trainImpl(Net net, const std::vector<const Sample*>& train_set,
                      const std::vector<const Sample*>& validation_set, int classes,
                      const TrainerParams& params, const EpochCallback& on_epoch,
                      std::mt19937_64& rng) {
  const auto start_time = std::chrono::steady_clock::now();
  if (train_set.empty()) throw Error("trainer: no training samples");
  if (validation_set.empty()) throw Error("trainer: no validation samples");
  if (params.batch_size <= 0 || params.max_epochs <= 0 || params.patience_epochs <= 0 ||
      !(params.learning_rate > 0.0f) || params.momentum < 0.0f || params.momentum >= 1.0f ||
      params.adam_beta2 < 0.0f || params.adam_beta2 >= 1.0f || params.weight_decay < 0.0f) {
    throw Error(
        "trainer: batch size, epochs, patience and learning rate must be positive, "
        "momentum and beta2 in [0, 1), weight decay not negative");
  }
  std::vector<int> counts(classes, 0);
  for (const Sample* s : train_set) ++counts[s->label];
  std::vector<float> class_weight(classes, 1.0f);
  for (int c = 0; c < classes; ++c) {
    if (counts[c] == 0)
      throw Error("trainer: class " + std::to_string(c) + " has no training sample");
    if (params.balance_classes) {
      class_weight[c] =
          static_cast<float>(train_set.size()) / (static_cast<float>(classes) * counts[c]);
    }
  }
  std::vector<bool> flip_allowed = params.augmentation.flip_allowed;
  if (flip_allowed.empty()) flip_allowed.assign(classes, true);
  if (static_cast<int>(flip_allowed.size()) != classes) {
    throw Error("trainer: flip_allowed must have one entry per class");
  }

  // Biases are not decayed.
  std::vector<float> decay(net.parameterCount(), params.weight_decay);
  for (const Layer& l : net.layers()) {
    for (int o = 0; o < (l.param_count > 0 ? l.filters : 0); ++o) decay[l.param_offset + o] = 0.0f;
  }

  Backprop bp(net);
  const int n = net.input().size();
  Augmenter augmenter(net.input().width, net.input().height, params.augmentation);
  std::vector<float> inputs(static_cast<std::size_t>(kLanes) * n);
  std::vector<float> grad(net.parameterCount(), 0.0f), m1(grad.size(), 0.0f), m2(grad.size(), 0.0f);
  std::vector<std::size_t> order(train_set.size());
  std::iota(order.begin(), order.end(), 0);

  TrainResult result;
  result.train_samples = static_cast<int>(train_set.size());
  result.net = net;
  result.validation = evaluateSamples(bp, net, validation_set);
  result.validation.accuracy = -1.0;  // any trained epoch is better than the start
  int since_best = 0;
  std::int64_t step = 0;
  for (int epoch = 1; epoch <= params.max_epochs; ++epoch) {
    const auto epoch_start = std::chrono::steady_clock::now();
    std::shuffle(order.begin(), order.end(), rng);
    double loss_sum = 0.0, weight_sum = 0.0;
    int correct = 0;
    for (std::size_t batch_start = 0; batch_start < order.size();
         batch_start += params.batch_size) {
      const std::size_t batch_end = std::min(order.size(), batch_start + params.batch_size);
      float batch_weight = 0.0f;
      for (std::size_t chunk = batch_start; chunk < batch_end; chunk += kLanes) {
        const int m = static_cast<int>(std::min<std::size_t>(kLanes, batch_end - chunk));
        int labels[kLanes];
        float weights[kLanes];
        for (int b = 0; b < kLanes; ++b) {
          labels[b] = -1;
          weights[b] = 0.0f;
        }
        for (int b = 0; b < m; ++b) {
          const Sample& s = *train_set[order[chunk + b]];
          float* dst = inputs.data() + static_cast<std::size_t>(b) * n;
          if (params.augment) {
            augmenter.apply(s.patch, flip_allowed[s.label], rng, dst);
          } else {
            patchToFloats(s.patch, dst);
          }
          normalizePatch(dst, n, net.normalization());
          labels[b] = s.label;
          weights[b] = class_weight[s.label];
          batch_weight += weights[b];
        }
        bp.runner().setInput(inputs.data(), m);
        bp.runner().forward();
        loss_sum += bp.backward(labels, weights, false, &correct);
      }
      weight_sum += batch_weight;
      std::fill(grad.begin(), grad.end(), 0.0f);
      bp.reduce(1.0f / batch_weight, grad);
      ++step;
      std::vector<float>& w = net.params();
      if (params.optimizer == Optimizer::kSgd) {
        for (std::size_t i = 0; i < w.size(); ++i) {
          const float g = grad[i] + decay[i] * w[i];
          m1[i] = params.momentum * m1[i] + g;
          w[i] -= params.learning_rate * m1[i];
        }
      } else {
        const float b1 = params.momentum, b2 = params.adam_beta2;
        const float c1 = 1.0f - std::pow(b1, static_cast<float>(step));
        const float c2 = 1.0f - std::pow(b2, static_cast<float>(step));
        const float rate = params.learning_rate * std::sqrt(c2) / c1;
        for (std::size_t i = 0; i < w.size(); ++i) {
          const float g = grad[i] + decay[i] * w[i];
          m1[i] = b1 * m1[i] + (1.0f - b1) * g;
          m2[i] = b2 * m2[i] + (1.0f - b2) * g * g;
          w[i] -= rate * m1[i] / (std::sqrt(m2[i]) + 1e-7f);
        }
      }
      bp.repack();
    }
    EpochReport report;
    report.epoch = epoch;
    report.train_loss = loss_sum / weight_sum;
    report.train_accuracy = static_cast<double>(correct) / train_set.size();
    report.validation = evaluateSamples(bp, net, validation_set);
    report.best = better(report.validation, result.validation);
    if (report.best) {
      result.net = net;
      result.validation = report.validation;
      result.best_epoch = epoch;
      since_best = 0;
    } else {
      ++since_best;
    }
    report.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - epoch_start).count();
    result.epochs.push_back(report);
    if (on_epoch) on_epoch(report);
    if (since_best >= params.patience_epochs) break;
  }
  result.seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start_time).count();
  return result;
}

}  // namespace

void augmentPatch(const GrayImage& patch, const AugmentationParams& params, bool flip_ok,
                  std::mt19937_64& rng, float* out) {
  Augmenter(patch.width(), patch.height(), params).apply(patch, flip_ok, rng, out);
}

TrainResult train(Net net, const Dataset& data, const TrainerParams& params,
                  const EpochCallback& on_epoch) {
  checkData(net, data, "dataset");
  if (!(params.validation_fraction > 0.0f && params.validation_fraction < 1.0f)) {
    throw Error("trainer: validation fraction must lie in (0, 1)");
  }
  std::mt19937_64 rng(params.seed);
  // Stratified split: the same fraction of every class is held out.
  std::vector<std::vector<const Sample*>> by_class(data.class_names.size());
  for (const Sample& s : data.samples) by_class[s.label].push_back(&s);
  std::vector<const Sample*> train_set, validation_set;
  for (std::size_t c = 0; c < by_class.size(); ++c) {
    auto& v = by_class[c];
    if (v.size() < 2) {
      throw Error("trainer: class '" + data.class_names[c] + "' needs at least 2 samples (has " +
                  std::to_string(v.size()) + ")");
    }
    std::shuffle(v.begin(), v.end(), rng);
    const std::size_t held = std::clamp<std::size_t>(
        static_cast<std::size_t>(std::lround(params.validation_fraction * v.size())), 1,
        v.size() - 1);
    validation_set.insert(validation_set.end(), v.begin(), v.begin() + held);
    train_set.insert(train_set.end(), v.begin() + held, v.end());
  }
  const int classes = net.classes();
  return trainImpl(std::move(net), train_set, validation_set, classes, params, on_epoch, rng);
}

TrainResult train(Net net, const Dataset& data, const Dataset& validation,
                  const TrainerParams& params, const EpochCallback& on_epoch) {
  checkData(net, data, "dataset");
  checkData(net, validation, "validation set");
  std::mt19937_64 rng(params.seed);
  std::vector<const Sample*> train_set, validation_set;
  for (const Sample& s : data.samples) train_set.push_back(&s);
  for (const Sample& s : validation.samples) validation_set.push_back(&s);
  const int classes = net.classes();
  return trainImpl(std::move(net), train_set, validation_set, classes, params, on_epoch, rng);
}

Evaluation evaluate(const Net& net, const Dataset& data) {
  checkData(net, data, "dataset");
  Backprop bp(net);
  std::vector<const Sample*> samples;
  for (const Sample& s : data.samples) samples.push_back(&s);
  return evaluateSamples(bp, net, samples);
}

double lossAndGradient(const Net& net, const float* inputs, const int* labels, const float* weights,
                       int count, std::vector<float>& param_gradient,
                       std::vector<float>* input_gradient) {
  Backprop bp(net);
  const int n = net.input().size();
  param_gradient.assign(net.parameterCount(), 0.0f);
  if (input_gradient != nullptr) input_gradient->assign(static_cast<std::size_t>(count) * n, 0.0f);
  double loss = 0.0;
  for (int start = 0; start < count; start += kLanes) {
    const int m = std::min(kLanes, count - start);
    int l[kLanes];
    float w[kLanes];
    for (int b = 0; b < kLanes; ++b) {
      l[b] = b < m ? labels[start + b] : -1;
      w[b] = b < m ? weights[start + b] : 0.0f;
    }
    bp.runner().setInput(inputs + static_cast<std::size_t>(start) * n, m);
    bp.runner().forward();
    loss += bp.backward(l, w, input_gradient != nullptr, nullptr);
    if (input_gradient != nullptr) {
      const Vec* d = bp.inputGradient();
      const Shape& s = net.input();
      const int plane = s.height * s.width;
      for (int b = 0; b < m; ++b) {
        for (int c = 0; c < s.channels; ++c) {
          for (int p = 0; p < plane; ++p) {
            (*input_gradient)[static_cast<std::size_t>(start + b) * n + c * plane + p] =
                d[static_cast<std::size_t>(p) * s.channels + c][b] / static_cast<float>(count);
          }
        }
      }
    }
  }
  bp.reduce(1.0f / static_cast<float>(count), param_gradient);
  return loss / count;
}

}  // namespace colorfree::cnn
