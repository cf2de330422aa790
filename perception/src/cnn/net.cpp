#include "colorfree/perception/cnn/net.h"

#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>

#include "colorfree/perception/error.h"

namespace colorfree::cnn {
namespace {

constexpr const char* kNormalizationComment = "# colorfree normalization=";
constexpr const char* kResamplingComment = "# colorfree resampling=";

std::string shapeText(const Shape& s) {
  return std::to_string(s.width) + "x" + std::to_string(s.height) + "x" +
         std::to_string(s.channels);
}

// Darknet counts output sizes with integer division; a window that does not fit is an error here.
int convOut(int in, int size, int stride, int pad) { return (in + 2 * pad - size) / stride + 1; }
int poolOut(int in, int size, int stride, int padding) {
  return (in + padding - size) / stride + 1;
}

}  // namespace

Net::Net(Shape input, std::vector<Layer> layers, const std::string& origin)
    : input_(input), layers_(std::move(layers)) {
  if (input_.width <= 0 || input_.height <= 0 || input_.channels <= 0) {
    throw Error(origin + ": input size must be positive (got " + shapeText(input_) + ")");
  }
  if (layers_.empty()) throw Error(origin + ": the net has no layers");
  std::size_t offset = 0;
  for (std::size_t i = 0; i < layers_.size(); ++i) {
    Layer& l = layers_[i];
    const std::string where = origin + ": layer " + std::to_string(i);
    l.in = i == 0 ? input_ : layers_[i - 1].out;
    l.param_offset = offset;
    l.param_count = 0;
    switch (l.type) {
      case LayerType::kConvolution: {
        if (l.filters <= 0 || l.size <= 0 || l.stride <= 0 || l.pad < 0) {
          throw Error(where + " (convolutional): filters, size and stride must be positive");
        }
        l.out = {convOut(l.in.height, l.size, l.stride, l.pad),
                 convOut(l.in.width, l.size, l.stride, l.pad), l.filters};
        if (l.in.height + 2 * l.pad < l.size || l.in.width + 2 * l.pad < l.size) {
          throw Error(where + " (convolutional): kernel " + std::to_string(l.size) +
                      " larger than its padded input " + shapeText(l.in));
        }
        l.param_count = static_cast<std::size_t>(l.filters) *
                        (1 + static_cast<std::size_t>(l.in.channels) * l.size * l.size);
        break;
      }
      case LayerType::kMaxPool: {
        if (l.size <= 0 || l.stride <= 0 || l.pad < 0) {
          throw Error(where + " (maxpool): size and stride must be positive");
        }
        if (l.in.height + l.pad < l.size || l.in.width + l.pad < l.size) {
          throw Error(where + " (maxpool): window larger than its input " + shapeText(l.in));
        }
        l.out = {poolOut(l.in.height, l.size, l.stride, l.pad),
                 poolOut(l.in.width, l.size, l.stride, l.pad), l.in.channels};
        break;
      }
      case LayerType::kGlobalAvgPool:
        l.out = {1, 1, l.in.channels};
        break;
      case LayerType::kRoute: {
        if (l.inputs.empty()) throw Error(where + " (route): no layers given");
        int channels = 0;
        for (int j : l.inputs) {
          if (j < 0 || j >= static_cast<int>(i)) {
            throw Error(where + " (route): refers to layer " + std::to_string(j) +
                        ", which is not an earlier layer");
          }
          const Shape& s = layers_[j].out;
          if (s.width != layers_[l.inputs[0]].out.width ||
              s.height != layers_[l.inputs[0]].out.height) {
            throw Error(where + " (route): layers of different plane sizes cannot be concatenated");
          }
          channels += s.channels;
        }
        const Shape& first = layers_[l.inputs[0]].out;
        l.out = {first.height, first.width, channels};
        break;
      }
      case LayerType::kConnected:
        if (l.filters <= 0) throw Error(where + " (connected): output must be positive");
        l.out = {1, 1, l.filters};
        l.param_count = static_cast<std::size_t>(l.filters) * (1 + l.in.size());
        break;
      case LayerType::kSoftmax:
        if (l.in.width != 1 || l.in.height != 1) {
          throw Error(where + " (softmax): needs a 1x1 input (after avgpool or connected), got " +
                      shapeText(l.in));
        }
        l.out = l.in;
        break;
    }
    if (l.out.width <= 0 || l.out.height <= 0) {
      throw Error(where + ": output size " + shapeText(l.out) + " is empty");
    }
    offset += l.param_count;
  }
  params_.assign(offset, 0.0f);
}

std::int64_t Net::multiplyAdds() const {
  std::int64_t total = 0;
  for (const Layer& l : layers_) {
    if (l.type == LayerType::kConvolution) {
      total += static_cast<std::int64_t>(l.out.size()) * l.in.channels * l.size * l.size;
    } else if (l.type == LayerType::kConnected) {
      total += static_cast<std::int64_t>(l.out.size()) * l.in.size();
    }
  }
  return total;
}

void Net::initialise(std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  for (const Layer& l : layers_) {
    if (l.param_count == 0) continue;
    const int biases = l.filters;
    const std::size_t weights = l.param_count - biases;
    const double fan_in = static_cast<double>(weights) / biases;
    const double gain =
        l.activation == Activation::kLeaky ? 2.0 / (1.0 + kLeakySlope * kLeakySlope) : 1.0;
    std::normal_distribution<double> normal(0.0, std::sqrt(gain / fan_in));
    float* p = params_.data() + l.param_offset;
    for (int b = 0; b < biases; ++b) p[b] = 0.0f;
    for (std::size_t w = 0; w < weights; ++w) p[biases + w] = static_cast<float>(normal(rng));
  }
}

namespace {

struct Section {
  std::string name;
  int line = 0;
  std::vector<std::pair<std::string, std::string>> keys;
  std::vector<int> key_lines;
};

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r");
  if (b == std::string::npos) return "";
  const auto e = s.find_last_not_of(" \t\r");
  return s.substr(b, e - b + 1);
}

class SectionReader {
 public:
  SectionReader(const Section& s, const std::string& origin) : s_(s), origin_(origin) {}

  std::string where(int line) const { return origin_ + ":" + std::to_string(line); }

  const std::string* find(const std::string& key) {
    used_.insert(key);
    for (const auto& [k, v] : s_.keys) {
      if (k == key) return &v;
    }
    return nullptr;
  }
  int lineOf(const std::string& key) const {
    for (std::size_t i = 0; i < s_.keys.size(); ++i) {
      if (s_.keys[i].first == key) return s_.key_lines[i];
    }
    return s_.line;
  }
  int integer(const std::string& key, int fallback) {
    const std::string* v = find(key);
    if (v == nullptr) return fallback;
    return parseInt(*v, key);
  }
  int parseInt(const std::string& text, const std::string& key) const {
    char* end = nullptr;
    errno = 0;
    const long value = std::strtol(text.c_str(), &end, 10);
    if (text.empty() || *end != '\0' || errno != 0 || value < -1000000 || value > 1000000) {
      throw Error(where(lineOf(key)) + ": [" + s_.name + "] " + key + "=" + text +
                  " is not an integer");
    }
    return static_cast<int>(value);
  }
  void ignore(std::initializer_list<const char*> keys) {
    for (const char* k : keys) used_.insert(k);
  }
  void finish() const {
    for (std::size_t i = 0; i < s_.keys.size(); ++i) {
      if (!used_.count(s_.keys[i].first)) {
        throw Error(where(s_.key_lines[i]) + ": [" + s_.name + "] has key '" + s_.keys[i].first +
                    "' that this engine does not support");
      }
    }
  }

 private:
  const Section& s_;
  const std::string& origin_;
  std::set<std::string> used_;
};

Activation parseActivation(SectionReader& r, const std::string& section) {
  const std::string* a = r.find("activation");
  if (a == nullptr || *a == "linear") return Activation::kLinear;
  if (*a == "leaky") return Activation::kLeaky;
  throw Error(r.where(r.lineOf("activation")) + ": [" + section + "] activation '" + *a +
              "' is not supported (linear, leaky)");
}

}  // namespace

Net parseDarknetCfg(const std::string& text, const std::string& origin) {
  std::vector<Section> sections;
  std::istringstream in(text);
  std::string raw;
  int line_no = 0;
  PatchNormalization normalization = PatchNormalization::kStandardize;
  PatchResampling resampling = PatchResampling::kBilinear;
  while (std::getline(in, raw)) {
    ++line_no;
    std::string line = trim(raw);
    // "# colorfree KEY=VALUE": one of the named values, or an error naming the file and line.
    const auto setting = [&](const char* comment, const char* key, auto& out, const auto& values) {
      if (line.rfind(comment, 0) != 0) return false;
      const std::string value = trim(line.substr(std::strlen(comment)));
      std::string names;
      for (const auto& [name, v] : values) {
        if (value == name) {
          out = v;
          return true;
        }
        names += (names.empty() ? "" : ", ") + std::string(name);
      }
      throw Error(origin + ":" + std::to_string(line_no) + ": unknown " + key + " '" + value +
                  "' (" + names + ")");
    };
    if (setting(kNormalizationComment, "normalization", normalization,
                std::array<std::pair<const char*, PatchNormalization>, 2>{
                    {{"standardize", PatchNormalization::kStandardize},
                     {"unit", PatchNormalization::kUnitRange}}}) ||
        setting(
            kResamplingComment, "resampling", resampling,
            std::array<std::pair<const char*, PatchResampling>, 2>{
                {{"bilinear", PatchResampling::kBilinear}, {"area", PatchResampling::kArea}}})) {
      continue;
    }
    if (line.empty() || line[0] == '#' || line[0] == ';') continue;
    if (line[0] == '[') {
      if (line.back() != ']') throw Error(origin + ":" + std::to_string(line_no) + ": bad section");
      sections.push_back({line.substr(1, line.size() - 2), line_no, {}, {}});
      continue;
    }
    const auto eq = line.find('=');
    if (eq == std::string::npos || sections.empty()) {
      throw Error(origin + ":" + std::to_string(line_no) +
                  ": expected [section] or key=value, got '" + line + "'");
    }
    sections.back().keys.emplace_back(trim(line.substr(0, eq)), trim(line.substr(eq + 1)));
    sections.back().key_lines.push_back(line_no);
  }
  if (sections.empty() || (sections[0].name != "net" && sections[0].name != "network")) {
    throw Error(origin + ": a Darknet cfg must start with a [net] section");
  }
  Shape input;
  {
    SectionReader r(sections[0], origin);
    input.width = r.integer("width", 0);
    input.height = r.integer("height", 0);
    input.channels = r.integer("channels", 0);
    // Training settings of Darknet: accepted, not used by this engine.
    r.ignore({"batch", "subdivisions", "momentum", "decay", "learning_rate", "max_batches",
              "policy", "steps", "scales", "burn_in", "angle", "saturation", "exposure", "hue"});
    r.finish();
    if (input.width <= 0 || input.height <= 0 || input.channels <= 0) {
      throw Error(origin + ": [net] needs positive width, height and channels");
    }
  }
  std::vector<Layer> layers;
  for (std::size_t si = 1; si < sections.size(); ++si) {
    const Section& s = sections[si];
    SectionReader r(s, origin);
    Layer l;
    const int index = static_cast<int>(layers.size());
    if (s.name == "convolutional" || s.name == "conv") {
      l.type = LayerType::kConvolution;
      l.filters = r.integer("filters", 1);
      l.size = r.integer("size", 1);
      l.stride = r.integer("stride", 1);
      const int pad_flag = r.integer("pad", 0);
      l.pad = pad_flag ? l.size / 2 : r.integer("padding", 0);
      if (pad_flag) r.ignore({"padding"});
      if (r.integer("batch_normalize", 0) != 0) {
        throw Error(r.where(r.lineOf("batch_normalize")) +
                    ": batch_normalize=1 is not supported; fold it into the weights");
      }
      if (r.integer("groups", 1) != 1) {
        throw Error(r.where(r.lineOf("groups")) + ": grouped convolution is not supported");
      }
      l.activation = parseActivation(r, s.name);
    } else if (s.name == "maxpool" || s.name == "max") {
      l.type = LayerType::kMaxPool;
      l.size = r.integer("size", 1);
      l.stride = r.integer("stride", 1);
      l.pad = r.integer("padding", l.size - 1);
    } else if (s.name == "avgpool" || s.name == "avg") {
      l.type = LayerType::kGlobalAvgPool;
    } else if (s.name == "route") {
      l.type = LayerType::kRoute;
      const std::string* v = r.find("layers");
      if (v == nullptr) throw Error(r.where(s.line) + ": [route] needs layers=");
      std::stringstream list(*v);
      std::string item;
      while (std::getline(list, item, ',')) {
        const int j = r.parseInt(trim(item), "layers");
        l.inputs.push_back(j < 0 ? index + j : j);
      }
    } else if (s.name == "connected") {
      l.type = LayerType::kConnected;
      l.filters = r.integer("output", 1);
      if (r.integer("batch_normalize", 0) != 0) {
        throw Error(r.where(r.lineOf("batch_normalize")) + ": batch_normalize=1 is not supported");
      }
      l.activation = parseActivation(r, s.name);
    } else if (s.name == "softmax" || s.name == "soft") {
      l.type = LayerType::kSoftmax;
      if (r.integer("groups", 1) != 1) {
        throw Error(r.where(r.lineOf("groups")) + ": softmax groups are not supported");
      }
    } else {
      throw Error(
          origin + ":" + std::to_string(s.line) + ": layer type [" + s.name +
          "] is not supported (convolutional, maxpool, avgpool, route, connected, softmax)");
    }
    r.finish();
    layers.push_back(std::move(l));
  }
  Net net(input, std::move(layers), origin);
  net.setNormalization(normalization);
  net.setResampling(resampling);
  return net;
}

Net readDarknetCfg(const std::string& cfg_path) {
  std::ifstream in(cfg_path, std::ios::binary);
  if (!in) throw Error(cfg_path + ": cannot open cfg file");
  std::stringstream text;
  text << in.rdbuf();
  return parseDarknetCfg(text.str(), cfg_path);
}

void readDarknetWeights(Net& net, const std::string& weights_path) {
  std::ifstream in(weights_path, std::ios::binary);
  if (!in) throw Error(weights_path + ": cannot open weights file");
  std::int32_t version[3];
  if (!in.read(reinterpret_cast<char*>(version), sizeof(version))) {
    throw Error(weights_path + ": truncated weights file (no header)");
  }
  const bool seen64 = version[0] * 10 + version[1] >= 2 && version[0] < 1000 && version[1] < 1000;
  char seen[8];
  if (!in.read(seen, seen64 ? 8 : 4)) throw Error(weights_path + ": truncated weights header");
  std::vector<float>& p = net.params();
  in.read(reinterpret_cast<char*>(p.data()),
          static_cast<std::streamsize>(p.size() * sizeof(float)));
  const std::size_t got = static_cast<std::size_t>(in.gcount()) / sizeof(float);
  if (got != p.size()) {
    throw Error(weights_path + ": truncated: the cfg needs " + std::to_string(p.size()) +
                " weights, the file holds " + std::to_string(got));
  }
  in.peek();
  if (!in.eof()) {
    throw Error(weights_path + ": holds more weights than the cfg needs (" +
                std::to_string(p.size()) + "): weights and cfg do not match");
  }
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!std::isfinite(p[i])) {
      throw Error(weights_path + ": weight " + std::to_string(i) + " is not a finite number");
    }
  }
}

Net readDarknet(const std::string& cfg_path, const std::string& weights_path) {
  Net net = readDarknetCfg(cfg_path);
  readDarknetWeights(net, weights_path);
  return net;
}

std::string darknetCfgText(const Net& net) {
  std::ostringstream out;
  out << kNormalizationComment
      << (net.normalization() == PatchNormalization::kStandardize ? "standardize" : "unit") << "\n";
  if (net.resampling() == PatchResampling::kArea) out << kResamplingComment << "area\n";
  out << "[net]\nwidth=" << net.input().width << "\nheight=" << net.input().height
      << "\nchannels=" << net.input().channels << "\n";
  const auto activation = [](Activation a) { return a == Activation::kLeaky ? "leaky" : "linear"; };
  for (std::size_t i = 0; i < net.layers().size(); ++i) {
    const Layer& l = net.layers()[i];
    out << "\n";
    switch (l.type) {
      case LayerType::kConvolution:
        out << "[convolutional]\nfilters=" << l.filters << "\nsize=" << l.size
            << "\nstride=" << l.stride << "\npadding=" << l.pad
            << "\nactivation=" << activation(l.activation) << "\n";
        break;
      case LayerType::kMaxPool:
        out << "[maxpool]\nsize=" << l.size << "\nstride=" << l.stride << "\npadding=" << l.pad
            << "\n";
        break;
      case LayerType::kGlobalAvgPool:
        out << "[avgpool]\n";
        break;
      case LayerType::kRoute: {
        out << "[route]\nlayers=";
        for (std::size_t j = 0; j < l.inputs.size(); ++j) {
          out << (j ? "," : "") << l.inputs[j] - static_cast<int>(i);
        }
        out << "\n";
        break;
      }
      case LayerType::kConnected:
        out << "[connected]\noutput=" << l.filters << "\nactivation=" << activation(l.activation)
            << "\n";
        break;
      case LayerType::kSoftmax:
        out << "[softmax]\n";
        break;
    }
  }
  return out.str();
}

namespace {

void writeAtomically(const std::string& path, const std::string& bytes) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw Error(path + ": cannot write (cannot create " + tmp + ")");
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.close();
    if (!out) throw Error(path + ": write failed");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) throw Error(path + ": cannot rename " + tmp + ": " + ec.message());
}

}  // namespace

void writeDarknetCfg(const Net& net, const std::string& cfg_path) {
  writeAtomically(cfg_path, darknetCfgText(net));
}

void writeDarknetWeights(const Net& net, const std::string& weights_path) {
  std::string bytes(3 * sizeof(std::int32_t) + sizeof(std::uint64_t), '\0');
  const std::int32_t version[3] = {0, 2, 0};
  std::memcpy(bytes.data(), version, sizeof(version));
  const auto& p = net.params();
  bytes.append(reinterpret_cast<const char*>(p.data()), p.size() * sizeof(float));
  writeAtomically(weights_path, bytes);
}

std::string defaultModelDir() { return std::string(COLORFREE_SOURCE_DIR) + "/perception/models"; }

}  // namespace colorfree::cnn
