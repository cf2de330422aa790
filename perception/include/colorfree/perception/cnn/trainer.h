#pragma once

#include <cstdint>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "colorfree/perception/cnn/dataset.h"
#include "colorfree/perception/cnn/net.h"

namespace colorfree::cnn {

/// Augmentation of grayscale patches, drawn afresh for every sample in every epoch.
struct AugmentationParams {
  float brightness = 0.1f;        ///< added offset, uniform in ±brightness × 255 grey levels
  float contrast = 0.2f;          ///< gain around the patch mean, uniform in 1 ± contrast
  float noise_stddev = 3.0f;      ///< Gaussian pixel noise, grey levels (σ uniform in [0, this])
  float blur_probability = 0.2f;  ///< chance of a [1 2 1]/4 blur in x and y
  float shift_px = 1.0f;          ///< translation, uniform in ±shift_px (patch pixels)
  float scale = 0.08f;            ///< zoom, uniform in 1 ± scale
  /// Chance of an image-border cut: one side of the patch, from a depth uniform in
  /// (0, border_cut_max_fraction] of the patch, is replaced by the last row or column before it,
  /// the way `extractPatch` fills what lies beyond the image (an object cut by the border).
  /// 0 draws nothing (the other augmentations' random draws stay as they were).
  float border_cut_probability = 0.0f;
  float border_cut_max_fraction = 0.5f;
  /// Of the cut patches, the share cut on a second, adjacent side too (an image corner).
  float border_cut_corner_probability = 0.0f;
  /// Per class (label order): may a patch of this class be mirrored left-right and keep its
  /// label? Empty = every class may.
  std::vector<bool> flip_allowed;
};

enum class Optimizer { kSgd, kAdam };

/// Training settings. The same settings, data and seed give the same weights, byte for byte.
struct TrainerParams {
  Optimizer optimizer = Optimizer::kAdam;
  float learning_rate = 0.005f;  ///< step size (Adam's α, or SGD's rate)
  float momentum = 0.9f;         ///< SGD momentum; Adam's β1
  float adam_beta2 = 0.999f;
  float weight_decay = 1e-4f;  ///< L2 on weights (not biases), added to the gradient
  int batch_size = 64;         ///< samples per step (any size; run 16 at a time)
  int max_epochs = 30;
  int patience_epochs = 6;  ///< stop after this many epochs without a better validation score
  float validation_fraction = 0.15f;  ///< held out per class when no validation set is given
  bool balance_classes = true;        ///< weight the loss by 1 / class frequency
  bool augment = true;
  AugmentationParams augmentation;
  std::uint64_t seed = 1;
};

/// Loss and accuracy of a net on a set of samples; confusion[truth][predicted].
struct Evaluation {
  double loss = 0.0;
  double accuracy = 0.0;
  int samples = 0;
  std::vector<std::vector<int>> confusion;
  std::vector<int> wrong;  ///< indices (into the evaluated samples) of the misclassified ones
};

struct EpochReport {
  int epoch = 0;
  double train_loss = 0.0;
  double train_accuracy = 0.0;
  Evaluation validation;
  double seconds = 0.0;
  bool best = false;  ///< this epoch's weights are the ones kept so far
};

struct TrainResult {
  Net net;  ///< the weights of the best epoch (highest validation accuracy, then lowest loss)
  std::vector<EpochReport> epochs;
  int best_epoch = 0;
  Evaluation validation;  ///< of the returned net
  int train_samples = 0;
  double seconds = 0.0;
};

using EpochCallback = std::function<void(const EpochReport&)>;

/// Trains `net` from its current weights (call Net::initialise first for a fresh net) on `data`,
/// holding out `params.validation_fraction` per class for validation and early stopping.
/// Throws colorfree::Error when the data do not fit the net (patch size, class count) or a class
/// has no sample.
TrainResult train(Net net, const Dataset& data, const TrainerParams& params,
                  const EpochCallback& on_epoch = {});
/// The same with an explicit validation set (e.g. from scenarios not used for training).
TrainResult train(Net net, const Dataset& data, const Dataset& validation,
                  const TrainerParams& params, const EpochCallback& on_epoch = {});

/// Classifies every sample of `data` (no augmentation) and scores it against the labels.
Evaluation evaluate(const Net& net, const Dataset& data);

/// One augmented copy of `patch` (grey values, width × height floats into `out`), drawn from `rng`
/// exactly as training draws it; `flip_ok`: may it be mirrored. For looking at and testing the
/// augmentation; training does the same without allocating.
void augmentPatch(const GrayImage& patch, const AugmentationParams& params, bool flip_ok,
                  std::mt19937_64& rng, float* out);

/// Mean weighted softmax cross-entropy of `count` input tensors (net input layout) with their
/// labels and weights, and its gradient with respect to every parameter (Net::params() order)
/// and, if `input_gradient` is given, every input value. The net must end in [softmax].
/// Exposed for the numerical gradient checks.
double lossAndGradient(const Net& net, const float* inputs, const int* labels, const float* weights,
                       int count, std::vector<float>& param_gradient,
                       std::vector<float>* input_gradient = nullptr);

}  // namespace colorfree::cnn
