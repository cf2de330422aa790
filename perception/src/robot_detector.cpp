#include "colorfree/perception/robot_detector.h"

#include <algorithm>
#include <numeric>

#include "colorfree/perception/cnn/shipped_nets.h"
#include "colorfree/perception/error.h"
#include "colorfree/perception/param_file.h"

namespace colorfree {

RobotDetectorParams RobotDetectorParams::load(const std::string& path) {
  ParamFile f(path);
  RobotDetectorParams p;
  p.min_confidence = f.getInRange("min_confidence", 0, 1);
  p.max_overlap_iou = f.getInRange("max_overlap_iou", 0, 1);
  p.max_inside_fraction = f.getInRange("max_inside_fraction", 0, 1);
  p.min_held_back_confidence = f.getInRange("min_held_back_confidence", 0, 1);
  f.finish();
  return p;
}

RobotDetectorParams RobotDetectorParams::loadDefault() {
  return load(defaultParamDir() + "/robot_detector.yaml");
}

cnn::PatchBox robotPatchBox(const RobotProposal& proposal) {
  const PixelBox& b = proposal.box;
  return {static_cast<float>(b.x0), static_cast<float>(b.y0), static_cast<float>(b.width()),
          static_cast<float>(b.height())};
}

RobotDetector::RobotDetector(RobotDetectorParams params, cnn::Classifier robot_net)
    : params_(params), net_(std::move(robot_net)) {
  if (net_.input().width != 24 || net_.input().height != 24 || net_.classes() != 2) {
    throw Error("robot detector: RobotNet must take 24x24 patches and give 2 classes");
  }
}

RobotDetector RobotDetector::loadDefault() {
  const cnn::ShippedNet& s = cnn::kShippedNets[0];
  return RobotDetector(RobotDetectorParams::loadDefault(),
                       cnn::Classifier::load(s.cfgPath(), s.weightsPath()));
}

namespace {
double boxIou(const PixelBox& a, const PixelBox& b) {
  const double ix = std::max(0.0, std::min(a.x1, b.x1) - std::max(a.x0, b.x0));
  const double iy = std::max(0.0, std::min(a.y1, b.y1) - std::max(a.y0, b.y0));
  const double inter = ix * iy;
  const double uni = a.width() * a.height() + b.width() * b.height() - inter;
  return uni > 0 ? inter / uni : 0;
}
// The fraction of a's area inside b.
double insideFraction(const PixelBox& a, const PixelBox& b) {
  const double ix = std::max(0.0, std::min(a.x1, b.x1) - std::max(a.x0, b.x0));
  const double iy = std::max(0.0, std::min(a.y1, b.y1) - std::max(a.y0, b.y0));
  const double area = a.width() * a.height();
  return area > 0 ? ix * iy / area : 0;
}
}  // namespace

std::vector<int> keptRobotBoxes(const std::vector<PixelBox>& boxes,
                                const std::vector<float>& confidence,
                                const RobotDetectorParams& params) {
  if (boxes.size() != confidence.size()) throw Error("keptRobotBoxes: one confidence per box");
  std::vector<int> order;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    if (confidence[i] >= params.min_confidence) order.push_back(static_cast<int>(i));
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return confidence[a] > confidence[b]; });
  const auto area = [](const PixelBox& b) { return b.width() * b.height(); };
  const auto partOf = [&](const PixelBox& part, const PixelBox& whole) {
    return area(whole) > area(part) && insideFraction(part, whole) >= params.max_inside_fraction;
  };
  // Most confident first; then a part (a box inside a larger kept one) goes, whichever of the
  // two was the more confident.
  std::vector<int> kept;
  for (int i : order) {
    bool drop = false;
    for (int k : kept) {
      drop |= boxIou(boxes[k], boxes[i]) > params.max_overlap_iou || partOf(boxes[i], boxes[k]);
    }
    if (!drop) kept.push_back(i);
  }
  std::vector<int> out;
  for (int i : kept) {
    bool part = false;
    for (int k : kept) part |= k != i && partOf(boxes[i], boxes[k]);
    if (!part) out.push_back(i);
  }
  return out;
}

std::vector<RobotPercept> RobotDetector::run(const GrayView& image, const CameraModel& camera,
                                             const std::vector<RobotProposal>& proposals,
                                             std::vector<float>* confidences) const {
  return run(image, camera, proposals, {}, nullptr, confidences);
}

std::vector<RobotPercept> RobotDetector::run(const GrayView& image, const CameraModel& camera,
                                             const std::vector<RobotProposal>& proposals,
                                             const std::vector<HeldBackRobotProposal>& held_back,
                                             std::vector<RobotProposal>* classified,
                                             std::vector<float>* confidences) const {
  std::vector<RobotProposal> seen = proposals;
  std::vector<float> robot;
  const auto classify = [&](std::size_t from) {
    if (seen.size() == from) return;
    std::vector<cnn::PatchBox> boxes;
    boxes.reserve(seen.size() - from);
    for (std::size_t i = from; i < seen.size(); ++i) boxes.push_back(robotPatchBox(seen[i]));
    std::vector<float> probs;
    net_.classify(image, boxes, probs);
    for (std::size_t i = 0; i < boxes.size(); ++i) robot.push_back(probs[2 * i + 1]);
  };
  classify(0);
  for (const HeldBackRobotProposal& h : held_back) {
    bool free = true;
    for (int k : h.nearer) {
      if (k < 0 || k >= static_cast<int>(proposals.size())) {
        throw Error("robot detector: a held-back proposal refers to no proposal");
      }
      free &= robot[k] < params_.min_confidence;
    }
    if (free) seen.push_back(h.proposal);
  }
  classify(proposals.size());
  std::vector<PixelBox> proposal_boxes;
  proposal_boxes.reserve(seen.size());
  for (const RobotProposal& p : seen) proposal_boxes.push_back(p.box);
  // Held-back boxes under their own bar take no part in the choice.
  std::vector<float> accepted = robot;
  for (std::size_t i = proposals.size(); i < seen.size(); ++i) {
    if (accepted[i] < params_.min_held_back_confidence) accepted[i] = 0;
  }
  std::vector<RobotPercept> out;
  for (int i : keptRobotBoxes(proposal_boxes, accepted, params_)) {
    const RobotProposal& p = seen[i];
    RobotPercept r;
    r.box = p.box;
    r.feet_px = p.feet_px;
    r.confidence = robot[i];
    r.position_in_robot = camera.pixelToGround(p.feet_px);
    out.push_back(r);
  }
  if (confidences) *confidences = std::move(robot);
  if (classified) *classified = std::move(seen);
  return out;
}

}  // namespace colorfree
