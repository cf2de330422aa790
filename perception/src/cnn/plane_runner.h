#pragma once

// The engine for one patch at a time. Each channel is a plane with a zero margin of M pixels on
// every side (M = the largest convolution padding), rows Wp = W + 2M floats apart. A stride-1
// convolution then computes 16 consecutive positions of the flattened plane per vector (the
// few positions that fall into the margin columns are computed and dropped), with the same
// register blocking over output channels as the batch engine. A route is a list of plane
// pointers: concatenation copies nothing.

#include <vector>

#include "colorfree/perception/cnn/net.h"

namespace colorfree::cnn::detail {

class PlaneRunner {
 public:
  explicit PlaneRunner(const Net& net);
  void repack();
  /// Runs one input tensor (channel-major, rows top-down); returns the net's output (classes).
  const float* run(const float* input);

 private:
  struct Tensor {
    int height = 0, width = 0, stride = 0, rows = 0;  // stride = width + 2M, rows = height + 2M
    std::vector<float*> planes;  // one per channel, pointing at the margin corner
  };
  float* valueAt(const Tensor& t, int c, int y, int x) const {
    return t.planes[c] + static_cast<std::size_t>(y + margin_) * t.stride + x + margin_;
  }
  Tensor makeTensor(int height, int width, int channels);
  void conv(int i, const Tensor& in, Tensor& out);
  void convScalar(int i, const Tensor& in, Tensor& out);
  void maxPool(int i, const Tensor& in, Tensor& out);

  static constexpr int kMaxTaps = 121;       // kernels up to 11x11 take the vector path
  static constexpr int kMaxChannels = 1024;  // filters of one convolution

  const Net& net_;
  int margin_ = 0;
  std::vector<bool> fused_;  // convolution i feeds max pool i + 1 directly from the sums
  std::vector<std::vector<float>> storage_;
  Tensor input_;
  std::vector<Tensor> outputs_;
  std::vector<std::vector<float>> packed_;  // convolution: [block][c][ky][kx][j]
  std::vector<float> scratch_;              // flattened convolution result before activation
  std::vector<std::vector<float>>
      masks_;  // same-size convolutions: 1 on real positions, 0 in margins
  std::vector<float> result_;
};

}  // namespace colorfree::cnn::detail
