#include "colorfree/perception/cnn/classifier.h"

#include "colorfree/perception/error.h"
#include "lane_runner.h"
#include "plane_runner.h"

namespace colorfree::cnn {

using detail::kLanes;

namespace {
// Up to this many patches beyond the last full batch run on the single-patch path.
constexpr int kSinglePatchLimit = 3;
}  // namespace

struct Classifier::Impl {
  explicit Impl(Net n)
      : net(std::move(n)), runner(net, true), single(net), patches(kLanes * net.input().size()) {}
  Net net;
  mutable detail::LaneRunner runner;
  mutable detail::PlaneRunner single;
  mutable std::vector<float> patches;
};

namespace {
// The default classifier: one global average over a 1x1x1 input (a placeholder until assigned).
Net placeholderNet() {
  Layer l;
  l.type = LayerType::kGlobalAvgPool;
  return Net({1, 1, 1}, {l});
}
}  // namespace

Classifier::Classifier() : Classifier(placeholderNet()) {}
Classifier::Classifier(Net net) : impl_(std::make_unique<Impl>(std::move(net))) {}
Classifier Classifier::load(const std::string& cfg_path, const std::string& weights_path) {
  return Classifier(readDarknet(cfg_path, weights_path));
}
Classifier::Classifier(const Classifier& other) : impl_(std::make_unique<Impl>(other.net())) {}
Classifier& Classifier::operator=(const Classifier& other) {
  if (this != &other) impl_ = std::make_unique<Impl>(other.net());
  return *this;
}
Classifier::Classifier(Classifier&&) noexcept = default;
Classifier& Classifier::operator=(Classifier&&) noexcept = default;
Classifier::~Classifier() = default;

const Net& Classifier::net() const { return impl_->net; }

void Classifier::run(const float* inputs, int count, float* probabilities) const {
  detail::LaneRunner& r = impl_->runner;
  const int n = impl_->net.input().size();
  const int k = impl_->net.classes();
  const int last = static_cast<int>(impl_->net.layers().size()) - 1;
  int start = 0;
  // A last group of a few patches runs one by one: cheaper than a batch with idle lanes.
  const int batched = count - count % kLanes;
  const int rest = count - batched;
  const int full_until = rest <= kSinglePatchLimit ? batched : count;
  for (; start < full_until; start += kLanes) {
    const int m = std::min(kLanes, count - start);
    r.setInput(inputs + static_cast<std::size_t>(start) * n, m);
    r.forward();
    const detail::Vec* out = r.output(last);
    for (int b = 0; b < m; ++b) {
      for (int c = 0; c < k; ++c)
        probabilities[static_cast<std::size_t>(start + b) * k + c] = out[c][b];
    }
  }
  for (; start < count; ++start) {
    const float* p = impl_->single.run(inputs + static_cast<std::size_t>(start) * n);
    std::copy(p, p + k, probabilities + static_cast<std::size_t>(start) * k);
  }
}

void Classifier::extract(const GrayView& image, const PatchBox& box, float* out) const {
  const Net& net = impl_->net;
  extractPatch(image, box, net.input().width, net.input().height, net.normalization(), out,
               net.resampling());
}

void Classifier::classify(const GrayView& image, const std::vector<PatchBox>& boxes,
                          std::vector<float>& probabilities) const {
  const Net& net = impl_->net;
  if (net.input().channels != 1)
    throw Error("Classifier::classify: the net's input is not grayscale");
  const int n = net.input().size();
  const int k = net.classes();
  probabilities.resize(boxes.size() * k);
  float* buffer = impl_->patches.data();
  for (std::size_t start = 0; start < boxes.size(); start += kLanes) {
    const int m = static_cast<int>(std::min<std::size_t>(kLanes, boxes.size() - start));
    for (int b = 0; b < m; ++b) {
      extract(image, boxes[start + b], buffer + static_cast<std::size_t>(b) * n);
    }
    run(buffer, m, probabilities.data() + start * k);
  }
}

}  // namespace colorfree::cnn
