#include "colorfree/training/robot_kind.h"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "colorfree/groundtruth/matching.h"
#include "colorfree/groundtruth/world_state.h"
#include "colorfree/perception/cnn/net.h"
#include "colorfree/perception/cnn/shipped_nets.h"

namespace colorfree::training {

namespace {

PipelineConfig earlyStages(PipelineConfig c) {
  c.robot_stages = false;
  c.ball_stages = false;
  return c;
}

cnn::Classifier untrained(int shipped_index) {
  cnn::Net net = cnn::readDarknetCfg(cnn::kShippedNets[shipped_index].cfgPath());
  net.initialise(1);
  return cnn::Classifier(std::move(net));
}

cnn::PatchBox patchBox(const PixelBox& b) {
  return {static_cast<float>(b.x0), static_cast<float>(b.y0), static_cast<float>(b.width()),
          static_cast<float>(b.height())};
}

std::string boxKey(const char* what, const PixelBox& b) {
  char key[96];
  std::snprintf(key, sizeof key, "%s %d,%d,%d,%d", what, static_cast<int>(std::floor(b.x0)),
                static_cast<int>(std::floor(b.y0)), static_cast<int>(std::floor(b.x1)),
                static_cast<int>(std::floor(b.y1)));
  return key;
}

std::optional<Eigen::Vector2d> feetInField(const CameraModel& camera, const FieldPose& observer,
                                           const Eigen::Vector2d& feet_px) {
  const auto g = camera.pixelToGround(feet_px);
  if (!g) return std::nullopt;
  return Eigen::Vector2d((robotToField(observer) * Eigen::Vector3d(g->x(), g->y(), 0)).head<2>());
}

// Axial difference of two angles, in [0, π/2].
double axialDiff(double a, double b) {
  const double d = std::fmod(std::abs(a - b), std::numbers::pi);
  return std::min(d, std::numbers::pi - d);
}

// FNV-1a over the pixels: the seed of a frame's random negatives.
std::uint64_t frameSeed(const GrayImage& image) {
  std::uint64_t h = 1469598103934665603ull;
  const std::size_t n = static_cast<std::size_t>(image.width()) * image.height();
  for (std::size_t i = 0; i < n; ++i) {
    h ^= image.data()[i];
    h *= 1099511628211ull;
  }
  return h;
}

std::string robotTruthText(const RobotInImage& r) {
  char text[128];
  std::snprintf(text, sizeof text, "robot %d d=%.2fm heading=%.1fdeg visible=%.2f", r.index,
                r.distance_m, r.heading_in_observer_rad * 180 / std::numbers::pi,
                r.visible_fraction);
  return text;
}

// The box the proposer draws about a feet point (robot_proposer.yaml's box geometry); nullopt
// where no robot can stand.
std::optional<PixelBox> proposerBox(const CameraModel& camera, const RobotProposerParams& pp,
                                    const FieldDimensions& dims, const Eigen::Vector2d& feet) {
  const auto h = camera.robotHeightPx(feet, dims.robot_height_m);
  if (!h) return std::nullopt;
  const double w = pp.box_width_factor * *h * dims.robot_width_m / dims.robot_height_m;
  PixelBox b;
  b.x0 = feet.x() - w / 2;
  b.x1 = feet.x() + w / 2;
  b.y1 = feet.y() + pp.box_below_feet_fraction * *h;
  b.y0 = b.y1 - pp.box_height_factor * *h;
  return b;
}

}  // namespace

RobotKind::RobotKind(RobotNetChoice which, PipelineConfig pipeline, ScoringParams scoring,
                     RobotLabelRules rules)
    : which_(which),
      config_(pipeline),
      pipeline_(earlyStages(pipeline)),
      proposer_(pipeline.robot_proposer, pipeline.field),
      lines_(pipeline.robot_orientation, pipeline.field, untrained(3), untrained(4)),
      scoring_(scoring),
      rules_(rules) {}

std::string RobotKind::name() const {
  switch (which_) {
    case RobotNetChoice::kRobotNet:
      return "robot";
    case RobotNetChoice::kBehindNet:
      return "robot_behind";
    case RobotNetChoice::kFeetNet:
      return "robot_feet";
    case RobotNetChoice::kOriBoostNet:
      return "ori_boost";
    case RobotNetChoice::kOriNet:
      break;
  }
  return "ori";
}

std::vector<std::string> RobotKind::classNames() const {
  switch (which_) {
    case RobotNetChoice::kRobotNet:
    case RobotNetChoice::kBehindNet:
      return {"none", "robot"};
    case RobotNetChoice::kFeetNet:
      return {"feet_right", "feet_lower", "feet_higher"};
    case RobotNetChoice::kOriBoostNet:
      return {"unusable", "usable"};
    case RobotNetChoice::kOriNet:
      break;
  }
  return {"front", "back", "side_left", "side_right"};
}

std::vector<bool> RobotKind::flipAllowed() const {
  if (which_ == RobotNetChoice::kOriNet) return {true, true, false, false};
  return std::vector<bool>(classNames().size(), true);
}

std::vector<std::string> RobotKind::netStems() const {
  switch (which_) {
    case RobotNetChoice::kRobotNet:
      return {"robot_net"};
    case RobotNetChoice::kBehindNet:
      return {"robot_behind_net"};
    case RobotNetChoice::kFeetNet:
      return {"robot_feet_net"};
    case RobotNetChoice::kOriBoostNet:
      return {"ori_boost_net"};
    case RobotNetChoice::kOriNet:
      break;
  }
  return {"ori_net"};
}

std::optional<Candidate> RobotKind::feetCandidate(const CameraModel& camera,
                                                  const FrameTruth& truth, const PixelBox& box,
                                                  const Eigen::Vector2d& feet_px,
                                                  const char* what) const {
  // The robot the box stands on: the in-view robot whose feet lie nearest its feet point, in its
  // column (within 0.35 of the robot's width) and within feet_off_max_fraction of its height.
  const FieldDimensions& dims = config_.field;
  const RobotInImage* best = nullptr;
  double best_cost = 1e9, best_off = 0;
  for (const RobotInImage& r : truth.robots) {
    if (!r.in_view) continue;
    const auto h = camera.robotHeightPx(r.ground_px, dims.robot_height_m);
    if (!h) continue;
    const double w = *h * dims.robot_width_m / dims.robot_height_m;
    const double dx = std::abs(r.ground_px.x() - feet_px.x()) / w;
    const double off = (r.ground_px.y() - feet_px.y()) / *h;  // > 0: the true feet are lower
    if (dx > 0.35 || std::abs(off) > rules_.feet_off_max_fraction) continue;
    const double cost = dx + std::abs(off);
    if (cost < best_cost) {
      best_cost = cost;
      best = &r;
      best_off = off;
    }
  }
  if (!best || !best->should_detect) return std::nullopt;  // none, or a robot too hidden to ask
  Candidate c;
  const double a = std::abs(best_off);
  if (a <= rules_.feet_right_max_fraction) {
    c.label = 0;
  } else if (a >= rules_.feet_off_min_fraction) {
    c.label = best_off > 0 ? 1 : 2;
  } else {
    return std::nullopt;
  }
  c.box = patchBox(box);
  c.key = boxKey(what, box);
  char text[192];
  std::snprintf(text, sizeof text, "%s feet_off=%.3f", robotTruthText(*best).c_str(), best_off);
  c.truth = text;
  return c;
}

std::vector<Candidate> RobotKind::proposals(const GrayImage& image, const CameraModel& camera,
                                            const FrameTruth& truth) const {
  Frame frame(image.view(), camera);
  pipeline_.process(frame);
  const RobotProposals props =
      proposer_.run(image.view(), camera, *frame.ignore_mask, *frame.contrast_regions);
  std::vector<Candidate> out;
  if (which_ == RobotNetChoice::kFeetNet) {
    for (const RobotProposal& p : props.proposals) {
      if (auto c = feetCandidate(camera, truth, p.box, p.feet_px, "p")) out.push_back(*c);
    }
    return out;
  }
  // RobotBehindNet learns from the held-back candidates as well (robots behind nearer ones, and
  // the nearer robots' hands, arms and knees).
  std::vector<RobotProposal> seen = props.proposals;
  if (which_ == RobotNetChoice::kBehindNet) {
    for (const HeldBackRobotProposal& h : props.held_back) seen.push_back(h.proposal);
  }
  for (const RobotProposal& p : seen) {
    const auto feet = feetInField(camera, truth.observer, p.feet_px);
    int best = -1;
    double best_cost = 1e9;
    bool any = false;
    for (std::size_t i = 0; i < truth.robots.size(); ++i) {
      const RobotInImage& r = truth.robots[i];
      if (!r.in_view) continue;
      const auto c = robotMatchCost(r, p.box, feet, scoring_);
      if (!c) continue;
      any = true;
      if (r.should_detect && *c < best_cost) {
        best_cost = *c;
        best = static_cast<int>(i);
      }
    }
    if (robotNet()) {
      if (best < 0 && any) continue;  // on a robot too hidden to demand: ambiguous
      Candidate c;
      c.box = patchBox(p.box);
      c.label = best >= 0 ? 1 : 0;
      c.key = boxKey("p", p.box);
      c.truth = best >= 0 ? robotTruthText(truth.robots[best]) : "none";
      out.push_back(c);
      continue;
    }
    if (best < 0) continue;
    // The orientation nets see the regions of the robots RobotNet accepts: percept as the
    // detector makes it.
    const RobotInImage& r = truth.robots[best];
    RobotPercept percept;
    percept.box = p.box;
    percept.feet_px = p.feet_px;
    percept.position_in_robot = camera.pixelToGround(p.feet_px);
    const Eigen::Vector2d position =
        percept.position_in_robot ? *percept.position_in_robot : Eigen::Vector2d::Zero();
    const RobotLines lines = lines_.findLines(image.view(), camera, percept);
    for (const LineRegion& region : lines.regions) {
      const Eigen::Vector2d d = region.line_in_robot.direction();
      const double diff = axialDiff(std::atan2(d.y(), d.x()), r.heading_in_observer_rad);
      const double off_deg = std::min(diff, std::numbers::pi / 2 - diff) * 180 / std::numbers::pi;
      char text[160];
      std::snprintf(text, sizeof text, "%s line_off=%.1fdeg", robotTruthText(r).c_str(), off_deg);
      Candidate c;
      c.box = patchBox(region.box);
      c.key = boxKey("l", region.box);
      c.truth = text;
      if (which_ == RobotNetChoice::kOriBoostNet) {
        if (off_deg <= rules_.usable_max_deg) {
          c.label = 1;
        } else if (off_deg >= rules_.unusable_min_deg) {
          c.label = 0;
        } else {
          continue;
        }
        out.push_back(c);
        continue;
      }
      if (off_deg > rules_.classed_max_deg) continue;  // OriNet only sees usable regions
      const Eigen::Vector2d facing(std::cos(r.heading_in_observer_rad),
                                   std::sin(r.heading_in_observer_rad));
      if (diff < std::numbers::pi / 4) {
        // Along the heading: a side of the robot, facing the observer's left (2) or right (3).
        const Eigen::Vector2d left(-position.y(), position.x());
        c.label = facing.dot(left) > 0 ? 2 : 3;
      } else {
        // Across the heading: front when the robot faces the observer's side of the line.
        Eigen::Vector2d normal(-d.y(), d.x());
        if (normal.dot(-position) < 0) normal = -normal;
        c.label = facing.dot(normal) > 0 ? 0 : 1;
      }
      out.push_back(c);
    }
  }
  if (!robotNet()) return out;
  // Robot-sized boxes at random ground points away from every robot: lines, posts, the ball, the
  // own body and the hall as RobotNet's negatives.
  std::mt19937_64 rng(frameSeed(image));
  std::uniform_real_distribution<double> ux(0, camera.width()), uy(0, camera.height());
  const RobotProposerParams& pp = config_.robot_proposer;
  const FieldDimensions& dims = config_.field;
  for (int k = 0, tries = 0; k < rules_.random_negatives && tries < 30; ++tries) {
    const Eigen::Vector2d feet(ux(rng), uy(rng));
    const auto h = camera.robotHeightPx(feet, dims.robot_height_m);
    if (!h || *h < 10) continue;
    const PixelBox b = *proposerBox(camera, pp, dims, feet);
    bool near_robot = false;
    for (const RobotInImage& r : truth.robots) {
      if (r.in_view && boxIou(r.box, b) > 0.05) near_robot = true;
    }
    if (near_robot) continue;
    Candidate c;
    c.box = patchBox(b);
    c.label = 0;
    c.key = boxKey("r", b);
    c.truth = "none (random ground point)";
    out.push_back(c);
    ++k;
  }
  return out;
}

std::vector<Candidate> RobotKind::truthSamples(const GrayImage& /*image*/,
                                               const CameraModel& camera,
                                               const FrameTruth& truth) const {
  std::vector<Candidate> out;
  const RobotProposerParams& pp = config_.robot_proposer;
  const FieldDimensions& dims = config_.field;
  if (which_ == RobotNetChoice::kFeetNet) {
    // Boxes about each demanded robot's feet moved up and down by fixed fractions of its height.
    for (const RobotInImage& r : truth.robots) {
      if (!r.in_view || !r.should_detect) continue;
      const auto h = camera.robotHeightPx(r.ground_px, dims.robot_height_m);
      if (!h) continue;
      for (const double s : {0.0, -0.15, 0.15, -0.3, 0.3}) {
        const Eigen::Vector2d feet = r.ground_px + Eigen::Vector2d(0, s * *h);
        const auto b = proposerBox(camera, pp, dims, feet);
        if (!b) continue;
        if (auto c = feetCandidate(camera, truth, *b, feet, "t")) out.push_back(*c);
      }
    }
    return out;
  }
  if (!robotNet()) return out;
  for (const RobotInImage& r : truth.robots) {
    if (!r.in_view || !r.should_detect) continue;
    const auto b0 = proposerBox(camera, pp, dims, r.ground_px);
    if (!b0) continue;
    const PixelBox& b = *b0;
    Candidate c;
    c.box = patchBox(b);
    c.label = 1;
    c.key = boxKey("truth", b);
    c.truth = robotTruthText(r);
    out.push_back(c);
  }
  return out;
}

}  // namespace colorfree::training
