#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "colorfree/perception/cnn/patch.h"

namespace colorfree::cnn {

/// Height × width × channels of one activation tensor of one sample.
struct Shape {
  int height = 0;
  int width = 0;
  int channels = 0;
  int size() const { return height * width * channels; }
  bool operator==(const Shape&) const = default;
};

/// The layer types of Darknet that this engine runs (and OpenCV 4.6's Darknet importer reads).
enum class LayerType {
  kConvolution,    ///< [convolutional]: k×k, stride, zero padding, bias, activation
  kMaxPool,        ///< [maxpool]: size, stride, Darknet padding (total, outside values ignored)
  kGlobalAvgPool,  ///< [avgpool]: mean over the whole plane, per channel
  kRoute,          ///< [route]: channel concatenation of earlier layers' outputs
  kConnected,      ///< [connected]: fully connected, bias, activation
  kSoftmax,        ///< [softmax]: over the channels of a 1×1 input
};

enum class Activation { kLinear, kLeaky };

/// Darknet's leaky ReLU slope (fixed in Darknet and in OpenCV's importer).
inline constexpr float kLeakySlope = 0.1f;

/// One layer, as described in a cfg file, with its shapes and where its parameters live.
struct Layer {
  LayerType type = LayerType::kConvolution;
  int filters = 0;  ///< convolution: output channels; connected: outputs
  int size = 1;     ///< kernel / window size
  int stride = 1;
  int pad = 0;  ///< convolution: zero padding on each side; maxpool: Darknet 'padding' (total)
  Activation activation = Activation::kLinear;
  std::vector<int> inputs;  ///< route: absolute indices of the concatenated layers (-1 = net input)
  Shape in;                 ///< input shape (route: unused)
  Shape out;
  std::size_t param_offset = 0;  ///< into Net::params(): biases first, then weights (Darknet order)
  std::size_t param_count = 0;
};

/// A network: its architecture and its float parameters, laid out exactly as in a Darknet
/// weights file (per layer: biases, then weights [out][in][ky][kx]; connected: [out][C·H·W]).
class Net {
 public:
  Net() = default;
  /// Builds the layers' shapes and parameter slots; throws colorfree::Error naming `origin` when
  /// the architecture is impossible (e.g. a route of mismatched planes, a kernel larger than its
  /// input).
  Net(Shape input, std::vector<Layer> layers, const std::string& origin = "net");

  const Shape& input() const { return input_; }
  const std::vector<Layer>& layers() const { return layers_; }
  const Shape& output() const { return layers_.back().out; }
  int classes() const { return output().size(); }

  std::vector<float>& params() { return params_; }
  const std::vector<float>& params() const { return params_; }
  std::size_t parameterCount() const { return params_.size(); }
  /// Multiply-adds of one forward pass of one sample (convolutions and connected layers).
  std::int64_t multiplyAdds() const;

  /// How patches are normalised before this net (stored in the cfg as the comment
  /// "# colorfree normalization=standardize|unit", which Darknet and cv::dnn skip).
  PatchNormalization normalization() const { return normalization_; }
  void setNormalization(PatchNormalization n) { normalization_ = n; }
  /// How boxes are resampled to this net's input (the cfg comment
  /// "# colorfree resampling=bilinear|area"; bilinear without it).
  PatchResampling resampling() const { return resampling_; }
  void setResampling(PatchResampling r) { resampling_ = r; }

  /// He-normal weights (for leaky ReLU), zero biases, from a seeded generator.
  void initialise(std::uint64_t seed);

 private:
  Shape input_;
  std::vector<Layer> layers_;
  std::vector<float> params_;
  PatchNormalization normalization_ = PatchNormalization::kStandardize;
  PatchResampling resampling_ = PatchResampling::kBilinear;
};

/// Parses a Darknet cfg file (only the layers above); throws colorfree::Error naming the file
/// and line for unknown sections, unknown or bad keys and impossible architectures.
Net readDarknetCfg(const std::string& cfg_path);
/// The same from text; `origin` names it in errors.
Net parseDarknetCfg(const std::string& text, const std::string& origin);
/// Reads the weights file for `net` (header major, minor, revision, seen; then the floats).
/// Throws colorfree::Error naming the file when it is truncated or longer than the cfg needs.
void readDarknetWeights(Net& net, const std::string& weights_path);
/// Reads cfg and weights together.
Net readDarknet(const std::string& cfg_path, const std::string& weights_path);

/// The cfg text of `net` (readable by Darknet and cv::dnn::readNetFromDarknet).
std::string darknetCfgText(const Net& net);
/// Writes cfg / weights through a temporary file renamed at the end.
void writeDarknetCfg(const Net& net, const std::string& cfg_path);
void writeDarknetWeights(const Net& net, const std::string& weights_path);

/// The directory of the shipped nets (perception/models in the source tree).
std::string defaultModelDir();

}  // namespace colorfree::cnn
