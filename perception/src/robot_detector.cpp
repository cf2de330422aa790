#include "colorfree/perception/robot_detector.h"

#include <algorithm>
#include <iterator>
#include <numeric>

#include "colorfree/perception/cnn/patch.h"
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
  p.min_wide_group_confidence = f.getInRange("min_wide_group_confidence", 0, 1);
  p.wide_group_shift_width_fraction = f.getInRange("wide_group_shift_width_fraction", 0, 1);
  p.wide_group_min_shift_confidence = f.getInRange("wide_group_min_shift_confidence", 0, 1);
  p.mirror_min_confidence = f.getInRange("mirror_min_confidence", 0, 1);
  p.mirror_max_confidence = f.getInRange("mirror_max_confidence", 0, 1);
  if (p.mirror_min_confidence > p.mirror_max_confidence) {
    throw Error(path + ": mirror_min_confidence must not exceed mirror_max_confidence");
  }
  p.area_min_patch_widths = f.getInRange("area_min_patch_widths", 0, 100);
  p.min_behind_robot_confidence = f.getInRange("min_behind_robot_confidence", 0, 1);
  p.behind_lower_part_fraction = f.getInRange("behind_lower_part_fraction", 0, 1);
  p.behind_net_veto_confidence = f.getInRange("behind_net_veto_confidence", 0, 1);
  p.shin_gap_height_fraction = f.getInRange("shin_gap_height_fraction", 0, 1);
  p.shin_reach_width_fraction = f.getInRange("shin_reach_width_fraction", 0, 5);
  p.shin_min_jump_gray = f.getInRange("shin_min_jump_gray", 1, 255);
  p.shin_jump_ratio = f.getInRange("shin_jump_ratio", 0, 1);
  p.shin_beside_width_factor = f.getInRange("shin_beside_width_factor", 0.1, 10);
  p.shin_min_fill_fraction = f.getInRange("shin_min_fill_fraction", 0, 1);
  p.shin_min_height_fraction = f.getInRange("shin_min_height_fraction", 0, 1);
  p.shin_max_height_fraction = f.getInRange("shin_max_height_fraction", 0, 1);
  p.shin_max_gap_px = static_cast<int>(f.getInRange("shin_max_gap_px", 0, 64));
  p.shin_max_gap_height_fraction = f.getInRange("shin_max_gap_height_fraction", 0, 1);
  if (p.shin_min_height_fraction > p.shin_max_height_fraction) {
    throw Error(path + ": shin_min_height_fraction must not exceed shin_max_height_fraction");
  }
  p.shin_min_span_width_fraction = f.getInRange("shin_min_span_width_fraction", 0, 5);
  p.shin_max_spread_height_fraction = f.getInRange("shin_max_spread_height_fraction", 0, 1);
  p.feet_min_confidence = f.getInRange("feet_min_confidence", 0.5, 1);  // one class at most
  p.feet_step_height_fraction = f.getInRange("feet_step_height_fraction", 0.01, 0.5);
  p.feet_max_steps = static_cast<int>(f.getInRange("feet_max_steps", 0, 10));
  p.feet_search_min_confidence = f.getInRange("feet_search_min_confidence", 0, 1);
  p.feet_search_accept_confidence = f.getInRange("feet_search_accept_confidence", 0, 1);
  p.feet_to_centre_m = f.getInRange("feet_to_centre_m", 0, 0.3);
  p.ball_feet_radii = f.getInRange("ball_feet_radii", 0, 10);
  p.ball_feet_max_confidence = f.getInRange("ball_feet_max_confidence", 0, 1);
  p.track_prior_odds = f.getInRange("track_prior_odds", 1, 1000);
  p.track_prior_min_hits = static_cast<int>(f.getInRange("track_prior_min_hits", 1, 1000));
  p.track_prior_distance_m = f.getInRange("track_prior_distance_m", 0, 5);
  f.finish();
  return p;
}

RobotDetectorParams RobotDetectorParams::loadDefault() {
  return load(defaultParamDir() + "/robot_detector.yaml");
}

std::optional<Eigen::Vector2d> robotGroundPoint(const CameraModel& camera,
                                                const Eigen::Vector2d& feet_px,
                                                double feet_to_centre_m) {
  const auto g = camera.pixelToGround(feet_px);
  if (!g) return std::nullopt;
  const Eigen::Vector2d los = *g - camera.position().head<2>();
  const double d = los.norm();
  return d > 0 ? Eigen::Vector2d(*g + feet_to_centre_m / d * los) : *g;
}

cnn::PatchBox robotPatchBox(const RobotProposal& proposal) {
  const PixelBox& b = proposal.box;
  return {static_cast<float>(b.x0), static_cast<float>(b.y0), static_cast<float>(b.width()),
          static_cast<float>(b.height())};
}

RobotDetector::RobotDetector(RobotDetectorParams params, cnn::Classifier robot_net,
                             FieldDimensions field, std::optional<cnn::Classifier> feet_net,
                             std::optional<cnn::Classifier> behind_net)
    : params_(params),
      net_(std::move(robot_net)),
      field_(field),
      feet_net_(std::move(feet_net)),
      behind_net_(std::move(behind_net)) {
  if (net_.input().width != 24 || net_.input().height != 24 || net_.classes() != 2) {
    throw Error("robot detector: RobotNet must take 24x24 patches and give 2 classes");
  }
  if (behind_net_ && (behind_net_->input().width != 24 || behind_net_->input().height != 24 ||
                      behind_net_->classes() != 2)) {
    throw Error("robot detector: RobotBehindNet must take 24x24 patches and give 2 classes");
  }
  if (feet_net_ && (feet_net_->input().width != 24 || feet_net_->input().height != 24 ||
                    feet_net_->classes() != 3)) {
    throw Error("robot detector: RobotFeetNet must take 24x24 patches and give 3 classes");
  }
}

RobotDetector RobotDetector::loadDefault() {
  const cnn::ShippedNet& s = cnn::kShippedNets[0];
  const cnn::ShippedNet& f = cnn::kShippedNets[6];
  const cnn::ShippedNet& b = cnn::kShippedNets[7];
  return RobotDetector(
      RobotDetectorParams::loadDefault(), cnn::Classifier::load(s.cfgPath(), s.weightsPath()),
      FieldDimensions::loadDefault(), cnn::Classifier::load(f.cfgPath(), f.weightsPath()),
      cnn::Classifier::load(b.cfgPath(), b.weightsPath()));
}

namespace {

// feetMovedTo with the box's expected robot height at its feet point, `h` px, already known.
std::optional<RobotProposal> movedWithHeight(const RobotProposal& box, double h,
                                             const CameraModel& camera, const Eigen::Vector2d& feet,
                                             const FieldDimensions& field) {
  const auto h_moved = camera.robotHeightPx(feet, field.robot_height_m);
  if (!h_moved) return std::nullopt;
  const double scale = *h_moved / h;
  RobotProposal out = box;
  out.feet_px = feet;
  out.box.x0 = feet.x() + (box.box.x0 - box.feet_px.x()) * scale;
  out.box.x1 = feet.x() + (box.box.x1 - box.feet_px.x()) * scale;
  out.box.y0 = feet.y() + (box.box.y0 - box.feet_px.y()) * scale;
  out.box.y1 = feet.y() + (box.box.y1 - box.feet_px.y()) * scale;
  return out;
}

}  // namespace

std::optional<RobotProposal> feetMoved(const RobotProposal& box, const CameraModel& camera,
                                       double step_height_fraction, int dir,
                                       const FieldDimensions& field) {
  const auto h = camera.robotHeightPx(box.feet_px, field.robot_height_m);
  if (!h) return std::nullopt;
  return movedWithHeight(box, *h, camera,
                         box.feet_px + Eigen::Vector2d(0, dir * step_height_fraction * *h), field);
}

std::optional<RobotProposal> feetMovedTo(const RobotProposal& box, const CameraModel& camera,
                                         const Eigen::Vector2d& feet,
                                         const FieldDimensions& field) {
  const auto h = camera.robotHeightPx(box.feet_px, field.robot_height_m);
  if (!h) return std::nullopt;
  return movedWithHeight(box, *h, camera, feet, field);
}

namespace {

// Whether the box lies between the image's top and bottom rows (RobotFeetNet reads a robot's
// height in its patch: a box the border cuts has no feet or head to see).
bool insideRows(const PixelBox& box, const GrayView& image) {
  return box.y0 >= 0 && box.y1 <= image.height;
}

// Whether RobotNet's look at the box is to be checked mirrored (when unsure): not where the image's
// left, right or bottom border cuts the box (near robots, whose mirrored look RobotNet rejected).
bool mirrorable(const PixelBox& box, const GrayView& image) {
  return box.x0 >= 0 && box.x1 <= image.width && box.y1 <= image.height;
}

// Whether `feet` lies inside the box of `nearer`, whose own feet stand lower in the image (a
// nearer robot's): the feet point of its knee, hand or arm, or of a robot behind it.
bool feetInsideNearer(const Eigen::Vector2d& feet, const RobotProposal& nearer) {
  const PixelBox& b = nearer.box;
  return nearer.feet_px.y() > feet.y() && feet.x() > b.x0 && feet.x() < b.x1 && feet.y() > b.y0 &&
         feet.y() < b.y1;
}

}  // namespace

void RobotDetector::score(const cnn::Classifier& net, const GrayView& image,
                          const RobotProposal* boxes, const float* patches, std::size_t count,
                          std::vector<float>& robot) const {
  if (count == 0) return;
  const cnn::Shape& in = net.input();
  const std::size_t n = static_cast<std::size_t>(in.size());
  // Near boxes looked at by area resampling too: the mean of both looks (a net that reads its
  // patches by area has had that look). Both looks in one batch.
  std::vector<std::size_t> near;
  const bool area_look =
      params_.area_min_patch_widths > 0 && net.net().resampling() != cnn::PatchResampling::kArea;
  for (std::size_t i = 0; i < count; ++i) {
    if (area_look && boxes[i].box.width() >= params_.area_min_patch_widths * in.width &&
        mirrorable(boxes[i].box, image)) {
      near.push_back(i);
    }
  }
  std::vector<float> probs((count + near.size()) * 2);
  if (near.empty()) {
    net.run(patches, static_cast<int>(count), probs.data());
  } else {
    std::vector<float> looks((count + near.size()) * n);
    std::copy_n(patches, count * n, looks.data());
    for (std::size_t k = 0; k < near.size(); ++k) {
      cnn::extractPatch(image, robotPatchBox(boxes[near[k]]), in.width, in.height,
                        net.net().normalization(), looks.data() + (count + k) * n,
                        cnn::PatchResampling::kArea);
    }
    net.run(looks.data(), static_cast<int>(count + near.size()), probs.data());
    for (std::size_t k = 0; k < near.size(); ++k) {
      float& p = probs[2 * near[k] + 1];
      p = 0.5f * (p + probs[2 * (count + k) + 1]);
    }
  }
  std::vector<std::size_t> unsure;
  for (std::size_t i = 0; i < count; ++i) {
    if (probs[2 * i + 1] >= params_.mirror_min_confidence &&
        probs[2 * i + 1] < params_.mirror_max_confidence && mirrorable(boxes[i].box, image)) {
      unsure.push_back(i);
    }
  }
  if (!unsure.empty()) {
    std::vector<float> mirrored(unsure.size() * n), mirrored_probs(unsure.size() * 2);
    for (std::size_t k = 0; k < unsure.size(); ++k) {
      cnn::mirrorPatch(patches + unsure[k] * n, net.input().width, net.input().height,
                       mirrored.data() + k * n);
    }
    net.run(mirrored.data(), static_cast<int>(unsure.size()), mirrored_probs.data());
    for (std::size_t k = 0; k < unsure.size(); ++k) {
      float& p = probs[2 * unsure[k] + 1];
      p = 0.5f * (p + mirrored_probs[2 * k + 1]);
    }
  }
  for (std::size_t i = 0; i < count; ++i) robot.push_back(probs[2 * i + 1]);
}

void RobotDetector::shiftWidePieces(const GrayView& image, std::vector<RobotProposal>& boxes,
                                    std::size_t count, std::vector<float>& robot,
                                    std::vector<float>& patches) const {
  const double f = params_.wide_group_shift_width_fraction;
  if (f <= 0) return;
  constexpr double kSteps[] = {-2, -1, 1, 2};
  constexpr std::size_t kLooks = std::size(kSteps);
  std::vector<std::size_t> which;
  for (std::size_t i = 0; i < count; ++i) {
    if (boxes[i].wide_group && robot[i] >= params_.wide_group_min_shift_confidence &&
        robot[i] < params_.min_wide_group_confidence) {
      which.push_back(i);
    }
  }
  if (which.empty()) return;
  const cnn::Shape& in = net_.input();
  const std::size_t n = static_cast<std::size_t>(in.size());
  std::vector<RobotProposal> moved;
  moved.reserve(which.size() * kLooks);
  for (std::size_t i : which) {
    for (const double step : kSteps) {
      RobotProposal m = boxes[i];
      const double dx = step * f * m.box.width();
      m.box.x0 += dx;
      m.box.x1 += dx;
      m.feet_px.x() += dx;
      moved.push_back(m);
    }
  }
  std::vector<float> inputs(moved.size() * n), moved_robot;
  for (std::size_t j = 0; j < moved.size(); ++j) {
    net_.extract(image, robotPatchBox(moved[j]), inputs.data() + j * n);
  }
  score(net_, image, moved.data(), inputs.data(), moved.size(), moved_robot);
  for (std::size_t w = 0; w < which.size(); ++w) {
    const std::size_t i = which[w];
    for (std::size_t j = w * kLooks; j < (w + 1) * kLooks; ++j) {
      if (moved_robot[j] <= robot[i]) continue;
      boxes[i] = moved[j];
      robot[i] = moved_robot[j];
      std::copy_n(inputs.data() + j * n, n, patches.data() + i * n);
    }
  }
}

void RobotDetector::moveFeet(const GrayView& image, const CameraModel& camera,
                             std::vector<RobotProposal>& boxes, const std::vector<int>& which,
                             const std::vector<float>& robot_net_patches) const {
  if (which.empty()) return;
  const cnn::Shape& in = feet_net_->input();
  const std::size_t n = static_cast<std::size_t>(in.size());
  const bool same_input = feet_net_->net().normalization() == net_.net().normalization() &&
                          feet_net_->net().resampling() == net_.net().resampling();
  std::vector<int> moving = which;
  std::vector<int> last(boxes.size(), 0);  // the direction of each box's last step
  std::vector<float> inputs(which.size() * n);
  std::vector<float> probs(which.size() * 3);
  for (int step = 0; step < params_.feet_max_steps && !moving.empty(); ++step) {
    for (std::size_t k = 0; k < moving.size(); ++k) {
      // The first look at an unmoved box is RobotNet's own patch (same size and normalisation).
      if (step == 0 && same_input) {
        std::copy_n(robot_net_patches.data() + moving[k] * n, n, inputs.data() + k * n);
      } else {
        feet_net_->extract(image, robotPatchBox(boxes[moving[k]]), inputs.data() + k * n);
      }
    }
    feet_net_->run(inputs.data(), static_cast<int>(moving.size()), probs.data());
    std::vector<int> next;
    for (std::size_t k = 0; k < moving.size(); ++k) {
      const int i = moving[k];
      const int dir = probs[3 * k + 1] >= params_.feet_min_confidence   ? 1
                      : probs[3 * k + 2] >= params_.feet_min_confidence ? -1
                                                                        : 0;
      if (dir == 0 || dir == -last[i]) continue;  // right, or back where it came from
      const auto moved =
          feetMoved(boxes[i], camera, params_.feet_step_height_fraction, dir, field_);
      if (!moved || !insideRows(moved->box, image)) continue;
      boxes[i] = *moved;
      last[i] = dir;
      next.push_back(i);
    }
    moving = std::move(next);
  }
}

void RobotDetector::searchFeet(const GrayView& image, const CameraModel& camera,
                               std::vector<RobotProposal>& boxes, std::size_t count,
                               std::vector<float>& robot, std::vector<float>& patches,
                               std::vector<bool>& searched) const {
  if (!feet_net_ || params_.feet_max_steps <= 0 ||
      params_.feet_search_min_confidence >= params_.min_confidence) {
    return;
  }
  std::vector<int> which;
  for (std::size_t i = 0; i < count; ++i) {
    if (robot[i] >= params_.feet_search_min_confidence && robot[i] < params_.min_confidence &&
        !boxes[i].wide_group && insideRows(boxes[i].box, image)) {
      which.push_back(static_cast<int>(i));
    }
  }
  std::vector<RobotProposal> moved = boxes;
  moveFeet(image, camera, moved, which, patches);
  std::vector<int> changed;
  std::vector<RobotProposal> looks;
  for (int i : which) {
    if (moved[i].feet_px == boxes[i].feet_px) continue;
    changed.push_back(i);
    looks.push_back(moved[i]);
  }
  if (changed.empty()) return;
  const std::size_t n = static_cast<std::size_t>(net_.input().size());
  std::vector<float> inputs(changed.size() * n);
  for (std::size_t k = 0; k < changed.size(); ++k) {
    net_.extract(image, robotPatchBox(looks[k]), inputs.data() + k * n);
  }
  std::vector<float> scores;
  score(net_, image, looks.data(), inputs.data(), looks.size(), scores);
  for (std::size_t k = 0; k < changed.size(); ++k) {
    if (scores[k] < params_.feet_search_accept_confidence) continue;
    const int i = changed[k];
    boxes[i] = looks[k];
    robot[i] = scores[k];
    searched[i] = true;
    std::copy_n(inputs.data() + k * n, n, patches.data() + i * n);
  }
}

std::optional<RobotPercept> feetOnShins(const GrayView& image, const CameraModel& camera,
                                        const RobotPercept& percept,
                                        const RobotDetectorParams& params,
                                        const FieldDimensions& field) {
  if (params.shin_gap_height_fraction <= 0) return std::nullopt;
  const auto h0 = camera.robotHeightPx(percept.feet_px, field.robot_height_m);
  const int feet_y = static_cast<int>(percept.feet_px.y());
  if (!h0 || feet_y < 0 || feet_y >= image.height - 1) return std::nullopt;
  const double width_per_height = field.robot_width_m / field.robot_height_m;
  const double w = *h0 * width_per_height;
  const int knee_rows = static_cast<int>(params.shin_gap_height_fraction * *h0) + 1;
  const int max_gap =
      std::max(params.shin_max_gap_px, static_cast<int>(params.shin_max_gap_height_fraction * *h0));
  const int y_end = std::min(image.height - 1, feet_y + knee_rows + static_cast<int>(0.5 * *h0));
  const auto at = [&](int x, int y) { return image.data[y * image.stride + x]; };
  // The carpet: the median gray beside the robot at those rows.
  std::vector<int> carpet_px;
  for (int y = feet_y; y <= y_end; y += 2) {
    for (double f : {-1.0, -0.8, 0.8, 1.0}) {
      const int x = static_cast<int>(percept.feet_px.x() + f * w);
      if (x >= 0 && x < image.width) carpet_px.push_back(at(x, y));
    }
  }
  if (carpet_px.size() < 4) return std::nullopt;
  std::nth_element(carpet_px.begin(), carpet_px.begin() + carpet_px.size() / 2, carpet_px.end());
  const double carpet = carpet_px[carpet_px.size() / 2];
  const double lit_above =
      carpet + std::max(params.shin_min_jump_gray, params.shin_jump_ratio * carpet);
  const auto lit = [&](int x, int y) { return at(x, y) > lit_above; };
  const int beside = static_cast<int>(params.shin_beside_width_factor * w);  // the percept's widths
  std::vector<int> xs, bottoms;
  const double reach = params.shin_reach_width_fraction * w;
  for (int x = static_cast<int>(percept.feet_px.x() - reach); x <= percept.feet_px.x() + reach;
       x += 2) {
    if (x < 0 || x >= image.width) continue;
    // Down over the knee's gap to the shin's top, then down the shin to carpet below it.
    int y = feet_y, gap = 0;
    while (y <= y_end && !lit(x, y) && gap <= knee_rows) {
      ++y;
      ++gap;
    }
    if (gap > knee_rows || y > y_end) continue;
    const int top = y;
    int holes = 0, last_lit = y, lit_rows = 0;
    for (; y <= y_end && holes <= max_gap; ++y) {
      if (lit(x, y)) {
        last_lit = y;
        holes = 0;
        ++lit_rows;
      } else {
        ++holes;
      }
    }
    if (holes <= max_gap) continue;  // no carpet below it within reach
    const int bottom = last_lit + 1;
    const auto h = camera.robotHeightPx({x + 0.5, static_cast<double>(bottom)}, field.robot_height_m);
    const int tall = bottom - top;
    if (!h || tall < params.shin_min_height_fraction * *h || tall > params.shin_max_height_fraction * *h) {
      continue;
    }
    if (lit_rows < params.shin_min_fill_fraction * tall) continue;
    int lit_beside = 0;
    for (int yy = top; yy < bottom; ++yy) {
      lit_beside += (x - beside >= 0 && lit(x - beside, yy)) ||
                    (x + beside < image.width && lit(x + beside, yy));
    }
    if (2 * lit_beside > tall) continue;
    xs.push_back(x);
    bottoms.push_back(bottom);
  }
  if (xs.size() < 3 || xs.back() - xs.front() < params.shin_min_span_width_fraction * w) {
    return std::nullopt;
  }
  std::sort(bottoms.begin(), bottoms.end());
  const std::size_t q = bottoms.size() / 4;
  if (bottoms[bottoms.size() - 1 - q] - bottoms[q] >
      std::max(3.0, params.shin_max_spread_height_fraction * *h0)) {
    return std::nullopt;
  }
  const int new_feet_y = bottoms[bottoms.size() / 2];
  const double cx = 0.5 * (xs.front() + xs.back() + 1);
  const auto h = camera.robotHeightPx({cx, static_cast<double>(new_feet_y)}, field.robot_height_m);
  if (!h) return std::nullopt;
  // The box as the proposer drew it about the feet, scaled by the expected heights' ratio.
  const double k = *h / *h0;
  const PixelBox& b = percept.box;
  RobotPercept out = percept;
  out.feet_px = {cx, static_cast<double>(new_feet_y)};
  out.box.x0 = cx - 0.5 * k * b.width();
  out.box.x1 = cx + 0.5 * k * b.width();
  out.box.y1 = new_feet_y + k * (b.y1 - percept.feet_px.y());
  out.box.y0 = out.box.y1 - k * b.height();
  out.position_in_robot = robotGroundPoint(camera, out.feet_px, params.feet_to_centre_m);
  return out;
}

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
  // Box i lies inside the larger box k: it is k's part (hand, arm), but for a box RobotNet is sure
  // of (min_behind_robot_confidence) standing above k's lower part: a robot behind k, the near
  // robot's box reaching round it (boxes' lower edges stand as far below their feet points).
  const auto partOf = [&](int i, int k) {
    const PixelBox &part = boxes[i], &whole = boxes[k];
    if (area(whole) <= area(part) || boxInsideFraction(part, whole) < params.max_inside_fraction) {
      return false;
    }
    return !(params.behind_lower_part_fraction > 0 &&
             confidence[i] >= params.min_behind_robot_confidence &&
             part.y1 < whole.y1 - params.behind_lower_part_fraction * whole.height());
  };
  // Most confident first; then a part (a box inside a larger kept one) goes, whichever of the
  // two was the more confident.
  std::vector<int> kept;
  for (int i : order) {
    bool drop = false;
    for (int k : kept) {
      drop |= boxIou(boxes[k], boxes[i]) > params.max_overlap_iou || partOf(i, k);
    }
    if (!drop) kept.push_back(i);
  }
  std::vector<int> out;
  for (int i : kept) {
    bool part = false;
    for (int k : kept) part |= k != i && partOf(i, k);
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
                                             std::vector<float>* confidences,
                                             const std::vector<Eigen::Vector2d>* tracked_in_robot) const {
  std::vector<RobotProposal> seen = proposals;
  std::vector<float> robot;
  // RobotNet's input per box seen (RobotFeetNet's first look reuses it).
  const cnn::Shape& in = net_.input();
  const std::size_t patch_size = static_cast<std::size_t>(in.size());
  std::vector<float> patches;
  const auto classify = [&](std::size_t from) {
    if (seen.size() == from) return;
    patches.resize(seen.size() * patch_size);
    for (std::size_t i = from; i < seen.size(); ++i) {
      net_.extract(image, robotPatchBox(seen[i]), patches.data() + i * patch_size);
    }
    score(net_, image, seen.data() + from, patches.data() + from * patch_size, seen.size() - from,
          robot);
  };
  // With candidates behind robots looked at, every held-back candidate is classified: all in one
  // batch with the proposals.
  const bool all_held_back = params_.min_behind_robot_confidence < 1;
  if (all_held_back) {
    for (const HeldBackRobotProposal& h : held_back) seen.push_back(h.proposal);
  }
  classify(0);
  shiftWidePieces(image, seen, proposals.size(), robot, patches);
  // Per classified held-back candidate: whether a nearer box it stands behind holds a robot.
  std::vector<bool> behind_robot;
  for (const HeldBackRobotProposal& h : held_back) {
    bool free = true;
    for (int k : h.nearer) {
      if (k < 0 || k >= static_cast<int>(proposals.size())) {
        throw Error("robot detector: a held-back proposal refers to no proposal");
      }
      free &= robot[k] < params_.min_confidence;
    }
    if (all_held_back) {
      behind_robot.push_back(!free);
    } else if (free) {
      seen.push_back(h.proposal);
      behind_robot.push_back(false);
    }
  }
  classify(robot.size());
  std::vector<bool> searched(seen.size(), false);
  searchFeet(image, camera, seen, proposals.size(), robot, patches, searched);
  // A box where a tracked robot stands: its odds times track_prior_odds (RobotNet's own scores kept
  // for `confidences`).
  std::optional<std::vector<float>> robot_net_scores;
  if (tracked_in_robot && !tracked_in_robot->empty() && params_.track_prior_odds > 1) {
    if (confidences) robot_net_scores = robot;
    const double k = params_.track_prior_odds;
    const double reach2 = params_.track_prior_distance_m * params_.track_prior_distance_m;
    for (std::size_t i = 0; i < seen.size(); ++i) {
      const auto g = robotGroundPoint(camera, seen[i].feet_px, params_.feet_to_centre_m);
      if (!g) continue;
      bool near = false;
      for (const Eigen::Vector2d& t : *tracked_in_robot) near |= (t - *g).squaredNorm() <= reach2;
      if (!near) continue;
      const double c = robot[i];
      robot[i] = static_cast<float>(k * c / (k * c + (1 - c)));
    }
  }
  std::vector<PixelBox> proposal_boxes;
  proposal_boxes.reserve(seen.size());
  for (const RobotProposal& p : seen) proposal_boxes.push_back(p.box);
  // The boxes RobotNet accepted on their own bars (the others take no part in the choice): the
  // proposals from min_confidence (pieces of wide groups from min_wide_group_confidence), held-back
  // candidates behind boxes it rejected from min_held_back_confidence. (Boxes behind a robot are
  // there only when every held-back candidate was classified, in held_back's order.)
  std::vector<bool> on_own_bar(seen.size(), false);
  for (std::size_t i = 0; i < seen.size(); ++i) {
    if (i < proposals.size()) {
      on_own_bar[i] = robot[i] >= params_.min_confidence &&
                      (!seen[i].wide_group || robot[i] >= params_.min_wide_group_confidence);
    } else if (!behind_robot[i - proposals.size()]) {
      on_own_bar[i] = robot[i] >= params_.min_held_back_confidence;
    }
  }
  // The boxes inside a nearer robot's: a held-back candidate behind a box RobotNet accepted, or a
  // box accepted on its own bar whose feet point lies inside a nearer one's box (lower feet). They
  // are a robot behind it or its hand, arm or knee, which RobotNet scores as high as robots;
  // RobotBehindNet, trained with such boxes too, looks at them as well: one it scores under
  // behind_net_veto_confidence is no robot (score 0 for the bars and rules below; `confidences`
  // keeps RobotNet's).
  if (behind_net_ && params_.behind_net_veto_confidence > 0) {
    if (confidences && !robot_net_scores) robot_net_scores = robot;
    std::vector<std::size_t> nested;
    std::vector<RobotProposal> nested_boxes;
    for (std::size_t i = 0; i < seen.size(); ++i) {
      // (A held-back candidate under the bar behind a robot stays out whatever this net says.)
      bool inside = i >= proposals.size() && behind_robot[i - proposals.size()] &&
                    robot[i] >= params_.min_behind_robot_confidence;
      for (std::size_t k = 0; k < seen.size() && !inside && on_own_bar[i]; ++k) {
        inside = k != i && on_own_bar[k] && feetInsideNearer(seen[i].feet_px, seen[k]);
      }
      if (inside) {
        nested.push_back(i);
        nested_boxes.push_back(seen[i]);
      }
    }
    // RobotNet's patches where the net reads its patches alike (the shipped one: RobotNet's cfg).
    const bool same_input = behind_net_->net().normalization() == net_.net().normalization() &&
                            behind_net_->net().resampling() == net_.net().resampling();
    std::vector<float> inputs(nested.size() * patch_size), scores;
    for (std::size_t k = 0; k < nested.size(); ++k) {
      if (same_input) {
        std::copy_n(patches.data() + nested[k] * patch_size, patch_size,
                    inputs.data() + k * patch_size);
      } else {
        behind_net_->extract(image, robotPatchBox(nested_boxes[k]), inputs.data() + k * patch_size);
      }
    }
    score(*behind_net_, image, nested_boxes.data(), inputs.data(), nested.size(), scores);
    for (std::size_t k = 0; k < nested.size(); ++k) {
      if (scores[k] >= params_.behind_net_veto_confidence) continue;
      robot[nested[k]] = 0;
      on_own_bar[nested[k]] = false;
    }
  }
  std::vector<float> accepted(seen.size(), 0.0f);
  for (std::size_t i = 0; i < seen.size(); ++i) {
    if (on_own_bar[i]) accepted[i] = robot[i];
    if (i < proposals.size() || !behind_robot[i - proposals.size()]) continue;
    // A box behind a robot takes part from min_behind_robot_confidence, but not when it overlaps
    // an accepted box it stands behind as two robots' boxes overlap (it is that robot's knee or
    // hand, which RobotNet may score higher than the robot), nor with another accepted box inside
    // it (its patch holds the nearer robot's body and that robot, which would become its part),
    // unless that box's feet lie in its own lower part: that is its knee or hand, not the nearer
    // robot (a free-standing knee box must not shut out its robot held back behind another).
    if (robot[i] < params_.min_behind_robot_confidence) continue;
    bool excluded = false;
    for (int k : held_back[i - proposals.size()].nearer) {
      excluded |= on_own_bar[k] && boxIou(proposal_boxes[k], proposal_boxes[i]) > params_.max_overlap_iou;
    }
    for (std::size_t k = 0; k < seen.size() && !excluded; ++k) {
      excluded =
          on_own_bar[k] &&
          boxInsideFraction(proposal_boxes[k], proposal_boxes[i]) >= params_.max_inside_fraction &&
          !feetInLowerPart(seen[k].feet_px, seen[i], params_.behind_lower_part_fraction);
    }
    if (!excluded) accepted[i] = robot[i];
  }
  // The accepted boxes with their feet moved to their robots' (RobotFeetNet), before the boxes
  // are compared; but not a box the image's top or bottom cuts, nor one whose feet point lies in
  // a nearer accepted box (lower feet): that robot hides its feet, or it is that robot's part.
  std::vector<RobotProposal> placed = seen;
  if (feet_net_ && params_.feet_max_steps > 0) {
    std::vector<int> which;
    for (std::size_t i = 0; i < seen.size(); ++i) {
      if (accepted[i] <= 0 || searched[i] || !insideRows(seen[i].box, image)) continue;
      const Eigen::Vector2d& f = seen[i].feet_px;
      bool hidden = false;
      for (std::size_t k = 0; k < seen.size() && !hidden; ++k) {
        hidden = accepted[k] > 0 && feetInsideNearer(f, seen[k]);
      }
      if (!hidden) which.push_back(static_cast<int>(i));
    }
    moveFeet(image, camera, placed, which, patches);
    for (int i : which) proposal_boxes[i] = placed[i].box;
  }
  // An accepted box whose feet lie in the lower part of a nearer accepted box (lower in the
  // image, taken first) is that robot's knee or hand, or a robot behind it: it stays only from
  // min_behind_robot_confidence, as a held-back candidate behind a robot does. (The proposer holds
  // such candidates back only behind boxes it kept before them.)
  if (params_.behind_lower_part_fraction > 0) {
    std::vector<int> order;
    for (std::size_t i = 0; i < seen.size(); ++i) {
      if (accepted[i] > 0) order.push_back(static_cast<int>(i));
    }
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return placed[a].feet_px.y() > placed[b].feet_px.y(); });
    std::vector<int> standing;
    for (int i : order) {
      bool behind = false;
      for (int k : standing) {
        behind |= feetInLowerPart(placed[i].feet_px, placed[k], params_.behind_lower_part_fraction);
      }
      if (behind && (accepted[i] < params_.min_behind_robot_confidence || searched[i])) {
        accepted[i] = 0;
      } else {
        standing.push_back(i);
      }
    }
  }
  // A box kept by the feet search yields to a box accepted at its first look that overlaps it or
  // holds it (the search took that robot's hand or knee down to its feet).
  for (std::size_t i = 0; i < seen.size(); ++i) {
    if (!searched[i] || accepted[i] <= 0) continue;
    for (std::size_t k = 0; k < seen.size() && accepted[i] > 0; ++k) {
      if (k != i && !searched[k] && accepted[k] > 0 &&
          (boxIou(proposal_boxes[k], proposal_boxes[i]) > params_.max_overlap_iou ||
           boxInsideFraction(proposal_boxes[i], proposal_boxes[k]) >=
               params_.max_inside_fraction)) {
        accepted[i] = 0;
      }
    }
  }
  std::vector<RobotPercept> out;
  for (int i : keptRobotBoxes(proposal_boxes, accepted, params_)) {
    const RobotProposal& p = placed[i];
    RobotPercept r;
    r.box = p.box;
    r.feet_px = p.feet_px;
    r.confidence = robot[i];
    r.position_in_robot = robotGroundPoint(camera, p.feet_px, params_.feet_to_centre_m);
    // Its legs below a backlit knee: the feet at the shins.
    if (auto lowered = feetOnShins(image, camera, r, params_, field_)) r = *lowered;
    out.push_back(r);
  }
  if (confidences) {
    *confidences = robot_net_scores ? std::move(*robot_net_scores) : std::move(robot);
  }
  if (classified) *classified = std::move(seen);
  return out;
}

std::vector<RobotPercept> RobotDetector::liftOffBalls(const GrayView& image,
                                                      const CameraModel& camera,
                                                      const std::vector<RobotPercept>& robots,
                                                      const std::vector<BallPercept>& balls) const {
  if (params_.ball_feet_radii <= 0 || balls.empty()) return robots;
  std::vector<RobotPercept> out;
  for (const RobotPercept& r : robots) {
    // A ball whose top lies above the feet point, its centre within reach of it.
    const BallPercept* under = nullptr;
    for (const BallPercept& b : balls) {
      if ((r.feet_px - b.centre_px).norm() < params_.ball_feet_radii * b.radius_px &&
          r.feet_px.y() > b.centre_px.y() - b.radius_px) {
        under = &b;
      }
    }
    if (!under || r.confidence > params_.ball_feet_max_confidence) {
      out.push_back(r);
      continue;
    }
    // Its feet at the ball's top, where a robot behind the ball shows its lowest part.
    RobotProposal box;
    box.box = r.box;
    box.feet_px = r.feet_px;
    const Eigen::Vector2d top(r.feet_px.x(), under->centre_px.y() - under->radius_px);
    const auto lifted = feetMovedTo(box, camera, top, field_);
    if (!lifted) continue;
    std::vector<float> patch(static_cast<std::size_t>(net_.input().size()));
    net_.extract(image, robotPatchBox(*lifted), patch.data());
    std::vector<float> robot;
    score(net_, image, &*lifted, patch.data(), 1, robot);
    // A second look at a box whose first place was doubtful, as a held-back candidate is.
    if (robot[0] < std::max(params_.min_confidence, params_.min_held_back_confidence)) continue;
    RobotPercept moved = r;
    moved.box = lifted->box;
    moved.feet_px = lifted->feet_px;
    moved.confidence = robot[0];
    moved.position_in_robot = robotGroundPoint(camera, moved.feet_px, params_.feet_to_centre_m);
    out.push_back(moved);
  }
  return out;
}

}  // namespace colorfree
