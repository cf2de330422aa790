#pragma once

#include <vector>

#include "lane_kernels.h"

namespace colorfree::cnn::detail {

/// Runs a net forward on kLanes samples at once, keeping every layer's output (the trainer's
/// backward pass reads them). All buffers are allocated once, in the constructor.
class LaneRunner {
 public:
  /// `inference`: run a convolution and the max pool after it as one step, let layers write
  /// straight into the route that concatenates them, and let a one-input route share its
  /// input's buffer. Not for the trainer, which reads every layer's own output.
  explicit LaneRunner(const Net& net, bool inference = false);

  /// Re-reads the weights from the net's parameters (after a training step).
  void repack();
  /// Input of kLanes samples, batch in lanes, layout of the net's input shape.
  Vec* input() { return input_.data(); }
  const Vec* input() const { return input_.data(); }
  /// Fills the input from `count` ≤ kLanes samples of input().size() floats each (channel-major,
  /// then rows: the Darknet / cv::dnn order); unused lanes are zero.
  void setInput(const float* samples, int count);
  void forward();
  const Vec* output(int layer) const { return out_ptr_[layer]; }
  Vec* output(int layer) { return out_ptr_[layer]; }
  const Vec* inputOf(int layer) const { return layer == 0 ? input_.data() : out_ptr_[layer - 1]; }
  const float* packed(int layer) const { return packed_[layer].data(); }
  const Net& net() const { return net_; }

 private:
  const Net& net_;
  std::vector<Vec> input_;
  std::vector<std::vector<Vec>> outputs_;
  std::vector<std::vector<float>> packed_;
  std::vector<std::vector<const Vec*>> route_sources_;
  std::vector<std::vector<int>> route_channels_;
  std::vector<bool> fused_;      ///< layer i is a convolution fused with the max pool i + 1
  std::vector<Vec*> out_ptr_;    ///< where layer i writes (its buffer or a slice of a route's)
  std::vector<int> out_stride_;  ///< channels per pixel there
  std::vector<bool> skip_;       ///< a route whose inputs already wrote its concatenation
};

}  // namespace colorfree::cnn::detail
