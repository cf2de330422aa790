#pragma once

#include <memory>
#include <string>
#include <vector>

#include "colorfree/perception/cnn/net.h"
#include "colorfree/perception/cnn/patch.h"
#include "colorfree/perception/image.h"

namespace colorfree::cnn {

/// Runs a net on patches. All buffers are made in the constructor; run() allocates nothing.
/// The scratch buffers make one Classifier usable by one thread at a time.
class Classifier {
 public:
  Classifier();
  explicit Classifier(Net net);
  /// Reads a Darknet cfg and weights; throws colorfree::Error naming the file on bad input.
  static Classifier load(const std::string& cfg_path, const std::string& weights_path);
  Classifier(const Classifier& other);
  Classifier& operator=(const Classifier& other);
  Classifier(Classifier&&) noexcept;
  Classifier& operator=(Classifier&&) noexcept;
  ~Classifier();

  const Net& net() const;
  int classes() const { return net().classes(); }
  const Shape& input() const { return net().input(); }

  /// Class probabilities (count × classes, row per patch) of `count` input tensors of
  /// input().size() floats each (channel-major, rows top-down: the cv::dnn blob order).
  /// Batches of 16 use the vector lanes fully; single patches take a dedicated path.
  void run(const float* inputs, int count, float* probabilities) const;

  /// The net's input for `box` of `image` into `out` (input().size() floats): extractPatch with
  /// the net's size, normalisation and resampling.
  void extract(const GrayView& image, const PatchBox& box, float* out) const;

  /// Extracts the boxes from `image` (see extract) and classifies them; `probabilities` gets
  /// boxes.size() × classes values.
  void classify(const GrayView& image, const std::vector<PatchBox>& boxes,
                std::vector<float>& probabilities) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace colorfree::cnn
