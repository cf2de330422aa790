#include "colorfree/perception/ball_detector.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "colorfree/perception/cnn/net.h"
#include "colorfree/perception/error.h"
#include "colorfree/perception/param_file.h"

namespace colorfree {

BallDetectorParams BallDetectorParams::load(const std::string& path) {
  ParamFile f(path);
  BallDetectorParams p;
  p.ball_radius_m = f.getInRange("ball_radius_m", 0.01, 0.5);
  p.patch_diameters = f.getInRange("patch_diameters", 0.5, 4);
  p.boost_keep_count = static_cast<int>(f.getInRange("boost_keep_count", 1, 100));
  p.boost_min_confidence = f.getInRange("boost_min_confidence", 0, 1);
  p.ball_min_confidence = f.getInRange("ball_min_confidence", 0, 1);
  p.max_balls = static_cast<int>(f.getInRange("max_balls", 1, 100));
  p.max_centre_outside_radii = f.getInRange("max_centre_outside_radii", 0, 100);
  f.finish();
  return p;
}

BallDetectorParams BallDetectorParams::loadDefault() {
  return load(defaultParamDir() + "/ball_detector.yaml");
}

cnn::PatchBox ballPatchBox(const Eigen::Vector2d& centre_px, double radius_px, double patch_diameters) {
  const double side = std::max(2.0, 2 * radius_px * patch_diameters);
  return {static_cast<float>(centre_px.x() - side / 2), static_cast<float>(centre_px.y() - side / 2),
          static_cast<float>(side), static_cast<float>(side)};
}

double centreOutsideRadii(const Eigen::Vector2d& centre_px, double radius_px, int width, int height) {
  const double dx = std::max({0.0, -centre_px.x(), centre_px.x() - width});
  const double dy = std::max({0.0, -centre_px.y(), centre_px.y() - height});
  return std::hypot(dx, dy) / std::max(radius_px, 1e-9);
}

BallDetector::BallDetector(BallDetectorParams params, cnn::Classifier boost_net, cnn::Classifier ball_net)
    : params_(params), boost_net_(std::move(boost_net)), ball_net_(std::move(ball_net)) {
  if (boost_net_.classes() != 2 || ball_net_.classes() != 2) {
    throw Error("ball detector: both nets must have two classes (none, ball)");
  }
}

BallDetector BallDetector::load(BallDetectorParams params, const std::string& model_dir) {
  const std::string dir = model_dir.empty() ? cnn::defaultModelDir() : model_dir;
  return BallDetector(params,
                      cnn::Classifier::load(dir + "/boost_ball_net.cfg", dir + "/boost_ball_net.weights"),
                      cnn::Classifier::load(dir + "/ball_net.cfg", dir + "/ball_net.weights"));
}

std::vector<BallPercept> BallDetector::run(const GrayView& image, const CameraModel& camera,
                                           const std::vector<BallProposal>& proposals,
                                           std::vector<BallDecision>* decisions) const {
  if (decisions) decisions->clear();
  if (proposals.empty()) return {};
  std::vector<cnn::PatchBox> boxes;
  boxes.reserve(proposals.size());
  for (const BallProposal& p : proposals) {
    boxes.push_back(ballPatchBox(p.centre_px, p.radius_px, params_.patch_diameters));
  }
  std::vector<float> boost_prob;
  boost_net_.classify(image, boxes, boost_prob);
  std::vector<int> order(proposals.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](int a, int b) { return boost_prob[2 * a + 1] > boost_prob[2 * b + 1]; });
  std::vector<int> kept;
  for (int i : order) {
    if (static_cast<int>(kept.size()) >= params_.boost_keep_count) break;
    if (boost_prob[2 * i + 1] < params_.boost_min_confidence) break;
    if (centreOutsideRadii(proposals[i].centre_px, proposals[i].radius_px, image.width,
                           image.height) > params_.max_centre_outside_radii) {
      continue;
    }
    kept.push_back(i);
  }
  std::vector<float> ball_prob;
  std::vector<cnn::PatchBox> kept_boxes;
  for (int i : kept) kept_boxes.push_back(boxes[i]);
  if (!kept_boxes.empty()) ball_net_.classify(image, kept_boxes, ball_prob);

  std::vector<BallPercept> out;
  std::vector<BallDecision> all(proposals.size());
  for (std::size_t i = 0; i < proposals.size(); ++i) {
    all[i].proposal = static_cast<int>(i);
    all[i].boost_confidence = boost_prob[2 * i + 1];
  }
  // `kept` is in descending boost order; detections are reported in descending BallNet order.
  std::vector<std::pair<float, int>> hits;
  for (std::size_t k = 0; k < kept.size(); ++k) {
    const int i = kept[k];
    all[i].passed_boost = true;
    all[i].ball_confidence = ball_prob[2 * k + 1];
    if (ball_prob[2 * k + 1] >= params_.ball_min_confidence) hits.emplace_back(ball_prob[2 * k + 1], i);
  }
  std::stable_sort(hits.begin(), hits.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  for (const auto& [conf, i] : hits) {
    if (static_cast<int>(out.size()) >= params_.max_balls) break;
    all[i].detected = true;
    BallPercept b;
    b.centre_px = proposals[i].centre_px;
    b.radius_px = proposals[i].radius_px;
    b.confidence = conf;
    b.position_in_robot = camera.pixelToGround(b.centre_px, params_.ball_radius_m);
    out.push_back(b);
  }
  if (decisions) *decisions = std::move(all);
  return out;
}

}  // namespace colorfree
