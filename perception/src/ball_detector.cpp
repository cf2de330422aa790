#include "colorfree/perception/ball_detector.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <numeric>
#include <string>
#include <vector>

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
  p.boost_border_mirror = static_cast<int>(f.getInRange("boost_border_mirror", 0, 1));
  p.ball_min_confidence = f.getInRange("ball_min_confidence", 0, 1);
  p.max_balls = static_cast<int>(f.getInRange("max_balls", 1, 100));
  p.max_centre_outside_radii = f.getInRange("max_centre_outside_radii", 0, 100);
  p.smeared_min_coherence = f.getInRange("smeared_min_coherence", 0, 2);
  p.smeared_ball_min_confidence = f.getInRange("smeared_ball_min_confidence", 0, 1);
  p.smeared_min_radius_px = f.getInRange("smeared_min_radius_px", 0, 1000);
  p.smeared_min_camera_smear_radii = f.getInRange("smeared_min_camera_smear_radii", 0, 100);
  p.smeared_max_direction_deg = f.getInRange("smeared_max_direction_deg", 0, 90);
  p.smeared_centre_reach_radii = f.getInRange("smeared_centre_reach_radii", 1, 20);
  p.smeared_centre_min_contrast_gray = f.getInRange("smeared_centre_min_contrast_gray", 0, 255);
  p.rescale_up = f.getInRange("rescale_up", 0, 4);
  p.rescale_down = f.getInRange("rescale_down", 0, 1);
  p.rescale_min_confidence = f.getInRange("rescale_min_confidence", 0, 1);
  p.rescale_min_radius_px = f.getInRange("rescale_min_radius_px", 0, 1000);
  p.sharpen_sigma_radii = f.getInRange("sharpen_sigma_radii", 0, 2);
  p.sharpen_amount = f.getInRange("sharpen_amount", 0, 20);
  p.sharpen_min_radius_px = f.getInRange("sharpen_min_radius_px", 0, 1000);
  p.sharpen_min_confidence = f.getInRange("sharpen_min_confidence", 0, 1);
  p.deblur_iterations = static_cast<int>(f.getInRange("deblur_iterations", 0, 100));
  p.deblur_min_camera_smear_radii = f.getInRange("deblur_min_camera_smear_radii", 0, 100);
  p.deblur_min_radius_px = f.getInRange("deblur_min_radius_px", 0, 1000);
  p.deblur_min_confidence = f.getInRange("deblur_min_confidence", 0, 1);
  p.border_mirror_min_confidence = f.getInRange("border_mirror_min_confidence", 0, 2);
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

namespace {

// Whether `box` reaches beyond the image.
bool cutByBorder(const cnn::PatchBox& box, const GrayView& image) {
  return box.x_px < 0 || box.y_px < 0 || box.x_px + box.width_px > image.width ||
         box.y_px + box.height_px > image.height;
}

}  // namespace

double patchSmear(const GrayView& image, const cnn::PatchBox& box, Eigen::Vector2d* along) {
  constexpr int side = kSmearPatchSide;
  if (cutByBorder(box, image)) return -1;
  std::vector<float> v(static_cast<std::size_t>(side) * side);
  cnn::extractPatch(image, box, side, side, cnn::PatchNormalization::kUnitRange, v.data());
  double xx = 0, xy = 0, yy = 0;
  for (int y = 1; y + 1 < side; ++y) {
    const float* a = &v[(y - 1) * side];
    const float* b = &v[y * side];
    const float* c = &v[(y + 1) * side];
    for (int x = 1; x + 1 < side; ++x) {
      const double gx = (a[x + 1] + 2 * b[x + 1] + c[x + 1]) - (a[x - 1] + 2 * b[x - 1] + c[x - 1]);
      const double gy = (c[x - 1] + 2 * c[x] + c[x + 1]) - (a[x - 1] + 2 * a[x] + a[x + 1]);
      xx += gx * gx;
      xy += gx * gy;
      yy += gy * gy;
    }
  }
  if (along) {
    const double gradient_angle = 0.5 * std::atan2(2 * xy, xx - yy);  // the dominant gradient's direction
    *along = Eigen::Vector2d(-std::sin(gradient_angle), std::cos(gradient_angle));
  }
  const double trace = xx + yy;
  if (trace <= 1e-12) return 0;
  return std::sqrt((xx - yy) * (xx - yy) + 4 * xy * xy) / trace;
}

namespace {

// Bilinear gray at (x, y) in image coordinates (pixel centres at +0.5), clamped to the image.
double grayAt(const GrayView& image, double x, double y) {
  const double u = std::clamp(x - 0.5, 0.0, image.width - 1.0), v = std::clamp(y - 0.5, 0.0, image.height - 1.0);
  const int x0 = static_cast<int>(u), y0 = static_cast<int>(v);
  const int x1 = std::min(x0 + 1, image.width - 1), y1 = std::min(y0 + 1, image.height - 1);
  const double fx = u - x0, fy = v - y0;
  const double top = image.at(x0, y0) + fx * (image.at(x1, y0) - image.at(x0, y0));
  const double bottom = image.at(x0, y1) + fx * (image.at(x1, y1) - image.at(x0, y1));
  return top + fy * (bottom - top);
}

// The pixels under `box` (and one more on every side) with those beyond the image mirrored about
// its border; `local` is `box` in the returned image's coordinates.
GrayImage mirroredAtBorder(const GrayView& image, const cnn::PatchBox& box, cnn::PatchBox& local) {
  const int x0 = static_cast<int>(std::floor(box.x_px)) - 1, y0 = static_cast<int>(std::floor(box.y_px)) - 1;
  const int x1 = static_cast<int>(std::ceil(box.x_px + box.width_px)) + 1;
  const int y1 = static_cast<int>(std::ceil(box.y_px + box.height_px)) + 1;
  // (a second reflection for a box more than the image's size beyond it: clamped instead)
  const auto reflect = [](int i, int n) { return std::clamp(i < 0 ? -1 - i : i >= n ? 2 * n - 1 - i : i, 0, n - 1); };
  GrayImage out(x1 - x0, y1 - y0);
  for (int y = y0; y < y1; ++y) {
    const std::uint8_t* row = image.row(reflect(y, image.height));
    for (int x = x0; x < x1; ++x) out.at(x - x0, y - y0) = row[reflect(x, image.width)];
  }
  local = box;
  local.x_px -= static_cast<float>(x0);
  local.y_px -= static_cast<float>(y0);
  return out;
}

// `net`'s "ball" probability for each of `boxes` mirrored about the image border, in one batch.
std::vector<float> mirroredBallProbability(const cnn::Classifier& net, const GrayView& image,
                                           const std::vector<cnn::PatchBox>& boxes) {
  if (boxes.empty()) return {};
  const std::size_t count = static_cast<std::size_t>(net.input().size());
  std::vector<float> inputs(boxes.size() * count), prob(boxes.size() * 2), ball(boxes.size());
  for (std::size_t m = 0; m < boxes.size(); ++m) {
    cnn::PatchBox local;
    const GrayImage part = mirroredAtBorder(image, boxes[m], local);
    net.extract(part.view(), local, inputs.data() + m * count);
  }
  net.run(inputs.data(), static_cast<int>(boxes.size()), prob.data());
  for (std::size_t m = 0; m < boxes.size(); ++m) ball[m] = prob[2 * m + 1];
  return ball;
}

}  // namespace

std::optional<Eigen::Vector2d> smearedBallCentre(const GrayView& image, const Eigen::Vector2d& centre_px,
                                                 double radius_px, const Eigen::Vector2d& along,
                                                 double reach_radii, double min_contrast_gray) {
  const int reach = static_cast<int>(std::ceil(reach_radii * radius_px));
  const Eigen::Vector2d across(-along.y(), along.x());
  constexpr int kAcross = 9;  // samples over ±radius/2 across the smear
  std::vector<double> profile(2 * reach + 1);
  for (int t = -reach; t <= reach; ++t) {
    double sum = 0;
    for (int j = 0; j < kAcross; ++j) {
      const Eigen::Vector2d q = centre_px + t * along + radius_px * (j / (kAcross - 1.0) - 0.5) * across;
      sum += grayAt(image, q.x(), q.y());
    }
    profile[t + reach] = sum / kAcross;
  }
  const int ends = std::max(3, static_cast<int>(std::lround(0.5 * radius_px)));
  if (2 * ends >= static_cast<int>(profile.size())) return std::nullopt;
  std::vector<double> outer(profile.begin(), profile.begin() + ends);
  outer.insert(outer.end(), profile.end() - ends, profile.end());
  std::nth_element(outer.begin(), outer.begin() + outer.size() / 2, outer.end());
  const double carpet = outer[outer.size() / 2];
  const int near = std::min(reach, static_cast<int>(std::ceil(radius_px)));
  const double peak = *std::max_element(profile.begin() + reach - near, profile.begin() + reach + near + 1);
  if (peak - carpet < min_contrast_gray) return std::nullopt;
  const double half = carpet + 0.5 * (peak - carpet);
  int seed = -1;  // the above-half sample nearest the proposal's centre
  for (int d = 0; d <= reach && seed < 0; ++d) {
    if (profile[reach + d] > half) seed = reach + d;
    else if (profile[reach - d] > half) seed = reach - d;
  }
  if (seed < 0) return std::nullopt;
  int first = seed, last = seed;
  while (first > 0 && profile[first - 1] > half) --first;
  while (last + 1 < static_cast<int>(profile.size()) && profile[last + 1] > half) ++last;
  if (first == 0 || last + 1 == static_cast<int>(profile.size())) return std::nullopt;
  return Eigen::Vector2d(centre_px + 0.5 * (first + last - 2 * reach) * along);
}

BallDetector::BallDetector(BallDetectorParams params, cnn::Classifier boost_net, cnn::Classifier ball_net,
                           std::optional<cnn::Classifier> smeared_net)
    : params_(params),
      boost_net_(std::move(boost_net)),
      ball_net_(std::move(ball_net)),
      smeared_net_(std::move(smeared_net)) {
  if (boost_net_.classes() != 2 || ball_net_.classes() != 2 || (smeared_net_ && smeared_net_->classes() != 2)) {
    throw Error("ball detector: the nets must have two classes (none, ball)");
  }
  if (params_.smeared_min_coherence <= 1 && !smeared_net_) {
    throw Error("ball detector: smeared_min_coherence " + std::to_string(params_.smeared_min_coherence) +
                " routes smeared patches to SmearedBallNet, but no SmearedBallNet was given");
  }
}

BallDetector BallDetector::load(BallDetectorParams params, const std::string& model_dir) {
  const std::string dir = model_dir.empty() ? cnn::defaultModelDir() : model_dir;
  std::optional<cnn::Classifier> smeared;
  if (params.smeared_min_coherence <= 1) {
    smeared = cnn::Classifier::load(dir + "/smeared_ball_net.cfg", dir + "/smeared_ball_net.weights");
  }
  return BallDetector(params,
                      cnn::Classifier::load(dir + "/boost_ball_net.cfg", dir + "/boost_ball_net.weights"),
                      cnn::Classifier::load(dir + "/ball_net.cfg", dir + "/ball_net.weights"), std::move(smeared));
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
  // A proposal the image border cuts: BoostBallNet's score is the larger of its look at the patch
  // and at the patch mirrored about the border (the cut part repeats the border pixel otherwise).
  if (params_.boost_border_mirror) {
    std::vector<std::size_t> cut;
    std::vector<cnn::PatchBox> cut_boxes;
    for (std::size_t i = 0; i < boxes.size(); ++i) {
      if (cutByBorder(boxes[i], image)) cut.push_back(i), cut_boxes.push_back(boxes[i]);
    }
    const std::vector<float> mirrored = mirroredBallProbability(boost_net_, image, cut_boxes);
    for (std::size_t m = 0; m < cut.size(); ++m) {
      boost_prob[2 * cut[m] + 1] = std::max(boost_prob[2 * cut[m] + 1], mirrored[m]);
    }
  }
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
  // BallNet sees every kept patch; SmearedBallNet those it rejects that the camera's motion smeared.
  std::vector<cnn::PatchBox> kept_boxes, smeared_boxes;
  for (int i : kept) kept_boxes.push_back(boxes[i]);
  std::vector<float> ball_prob, smeared_prob;
  if (!kept_boxes.empty()) ball_net_.classify(image, kept_boxes, ball_prob);
  std::vector<float> smear(kept.size(), -1.0f);
  std::vector<Eigen::Vector2d> along(kept.size(), Eigen::Vector2d::UnitX());
  std::vector<bool> smeared(kept.size(), false);  // routed to SmearedBallNet
  const Eigen::Vector2d& camera_smear = camera.exposureSmearPx();
  const double cos_max_direction =
      std::cos(params_.smeared_max_direction_deg * std::numbers::pi / 180);
  if (params_.smeared_min_coherence <= 1) {  // the constructor made sure of the net
    for (std::size_t k = 0; k < kept.size(); ++k) {
      if (ball_prob[2 * k + 1] >= params_.ball_min_confidence) continue;
      const double radius = proposals[kept[k]].radius_px;
      if (radius < params_.smeared_min_radius_px) continue;
      if (camera_smear.norm() < params_.smeared_min_camera_smear_radii * radius) continue;
      smear[k] = static_cast<float>(patchSmear(image, kept_boxes[k], &along[k]));
      // (an undirected angle: the smear's direction has no sign; a still camera has none, so a
      // zero smear, let through by a bound of 0, passes any direction)
      const bool along_camera =
          params_.smeared_max_direction_deg >= 90 ||
          std::abs(along[k].dot(camera_smear)) >= cos_max_direction * camera_smear.norm();
      if (smear[k] >= params_.smeared_min_coherence && along_camera) {
        smeared[k] = true;
        smeared_boxes.push_back(kept_boxes[k]);
      }
    }
  }
  if (!smeared_boxes.empty()) smeared_net_->classify(image, smeared_boxes, smeared_prob);
  // Rejected kept patches at other scales.
  std::vector<cnn::PatchBox> rescaled_boxes;
  std::vector<std::pair<std::size_t, double>> rescaled;  // (k, scale)
  for (std::size_t k = 0; k < kept.size(); ++k) {
    const BallProposal& p = proposals[kept[k]];
    if (ball_prob[2 * k + 1] >= params_.ball_min_confidence || p.radius_px < params_.rescale_min_radius_px) continue;
    for (const double s : {params_.rescale_up, params_.rescale_down}) {
      if (s <= 0) continue;
      rescaled_boxes.push_back(ballPatchBox(p.centre_px, p.radius_px * s, params_.patch_diameters));
      rescaled.emplace_back(k, s);
    }
  }
  std::vector<float> rescaled_prob;
  if (!rescaled_boxes.empty()) ball_net_.classify(image, rescaled_boxes, rescaled_prob);
  std::vector<double> radius_scale(proposals.size(), 1.0);
  std::vector<float> rescaled_conf(kept.size(), -1.0f);
  for (std::size_t m = 0; m < rescaled.size(); ++m) {
    const auto [k, s] = rescaled[m];
    const float c = rescaled_prob[2 * m + 1];
    if (c >= params_.rescale_min_confidence && c > rescaled_conf[k]) {
      rescaled_conf[k] = c;
      radius_scale[kept[k]] = s;
    }
  }
  // The later looks' scores (-1: not looked), and whether BallNet rejected kept patch k and no look
  // so far took it (a look not taken yet reads -1, under its bar).
  std::vector<float> sharpened_conf(kept.size(), -1.0f), deblurred_conf(kept.size(), -1.0f);
  const auto untaken = [&](std::size_t k) {
    return ball_prob[2 * k + 1] < params_.ball_min_confidence && rescaled_conf[k] < 0 &&
           sharpened_conf[k] < params_.sharpen_min_confidence && deblurred_conf[k] < params_.deblur_min_confidence;
  };
  // BallNet on kept patches `which`, each extracted in grey levels and passed through
  // `filter(box, values)` before it is normalised (normalizePatch's kMinStddev is in grey levels):
  // their ball scores into `conf`.
  const cnn::Shape& in = ball_net_.input();
  const int count = in.width * in.height;
  const auto filteredLook = [&](const std::vector<std::size_t>& which, const auto& filter,
                                std::vector<float>& conf) {
    if (which.empty()) return;
    std::vector<float> inputs(which.size() * count), prob(which.size() * 2);
    for (std::size_t m = 0; m < which.size(); ++m) {
      const cnn::PatchBox& box = kept_boxes[which[m]];
      float* v = &inputs[m * count];
      cnn::extractPatch(image, box, in.width, in.height, cnn::PatchNormalization::kUnitRange, v,
                        ball_net_.net().resampling());
      for (int j = 0; j < count; ++j) v[j] *= 255.0f;
      filter(box, v);
      cnn::normalizePatch(v, count, ball_net_.net().normalization());
    }
    ball_net_.run(inputs.data(), static_cast<int>(which.size()), prob.data());
    for (std::size_t m = 0; m < which.size(); ++m) conf[which[m]] = prob[2 * m + 1];
  };
  // Rejected kept patches the rescaled look did not take, through the unsharp mask (a soft lens).
  if (params_.sharpen_sigma_radii > 0) {
    std::vector<std::size_t> which;
    for (std::size_t k = 0; k < kept.size(); ++k) {
      if (untaken(k) && proposals[kept[k]].radius_px >= params_.sharpen_min_radius_px) which.push_back(k);
    }
    // The ball's radius in patch pixels: the patch is patch_diameters ball diameters wide.
    const double sigma_px = params_.sharpen_sigma_radii * in.width / (2 * params_.patch_diameters);
    filteredLook(which, [&](const cnn::PatchBox&, float* v) {
      cnn::unsharpMask(v, in.width, in.height, sigma_px, params_.sharpen_amount);
    }, sharpened_conf);
  }

  // Rejected kept patches neither of those looks took, where the camera turned during the exposure:
  // with that smear taken back (BallNet learnt sharp balls).
  if (params_.deblur_iterations > 0) {
    std::vector<std::size_t> which;
    for (std::size_t k = 0; k < kept.size(); ++k) {
      const double radius = proposals[kept[k]].radius_px;
      if (untaken(k) && radius >= params_.deblur_min_radius_px &&
          camera_smear.norm() >= params_.deblur_min_camera_smear_radii * radius) {
        which.push_back(k);
      }
    }
    filteredLook(which, [&](const cnn::PatchBox& box, float* v) {
      // The smear in patch pixels (a longer one than the patch: the patch is all smear).
      const Eigen::Vector2d s(camera_smear.x() * in.width / box.width_px,
                              camera_smear.y() * in.height / box.height_px);
      const double most = 0.9 * std::min(in.width, in.height);
      const Eigen::Vector2d d = s.norm() > most ? Eigen::Vector2d(s * (most / s.norm())) : s;
      cnn::deblurAlong(v, in.width, in.height, d.x(), d.y(), params_.deblur_iterations);
    }, deblurred_conf);
  }

  // Rejected kept patches the image border cuts that no other look took, mirrored at the border.
  std::vector<float> mirrored_conf(kept.size(), -1.0f);
  if (params_.border_mirror_min_confidence <= 1) {
    std::vector<std::size_t> which;
    std::vector<cnn::PatchBox> which_boxes;
    for (std::size_t k = 0; k < kept.size(); ++k) {
      if (untaken(k) && cutByBorder(kept_boxes[k], image)) {
        which.push_back(k);
        which_boxes.push_back(kept_boxes[k]);
      }
    }
    const std::vector<float> mirrored = mirroredBallProbability(ball_net_, image, which_boxes);
    for (std::size_t m = 0; m < which.size(); ++m) mirrored_conf[which[m]] = mirrored[m];
  }

  std::vector<BallPercept> out;
  std::vector<BallDecision> all(proposals.size());
  for (std::size_t i = 0; i < proposals.size(); ++i) {
    all[i].proposal = static_cast<int>(i);
    all[i].boost_confidence = boost_prob[2 * i + 1];
  }
  // `kept` is in descending boost order; detections are reported in descending confidence (either net's).
  std::vector<std::pair<float, int>> hits;
  std::vector<std::optional<Eigen::Vector2d>> smeared_centre(proposals.size());
  std::size_t next_smeared = 0;
  for (std::size_t k = 0; k < kept.size(); ++k) {
    const int i = kept[k];
    all[i].passed_boost = true;
    all[i].smear = smear[k];
    all[i].ball_confidence = ball_prob[2 * k + 1];
    if (all[i].ball_confidence >= params_.ball_min_confidence) {
      hits.emplace_back(all[i].ball_confidence, i);
    } else if (rescaled_conf[k] >= 0) {
      hits.emplace_back(rescaled_conf[k], i);
    } else if (sharpened_conf[k] >= params_.sharpen_min_confidence) {
      hits.emplace_back(sharpened_conf[k], i);
    } else if (deblurred_conf[k] >= params_.deblur_min_confidence) {
      hits.emplace_back(deblurred_conf[k], i);
    } else if (mirrored_conf[k] >= params_.border_mirror_min_confidence) {
      hits.emplace_back(mirrored_conf[k], i);
    }
    all[i].sharpened_confidence = sharpened_conf[k];
    all[i].deblurred_confidence = deblurred_conf[k];
    all[i].mirrored_confidence = mirrored_conf[k];
    // (SmearedBallNet's answer counts for a patch neither other look took: one hit per proposal.)
    if (smeared[k]) {
      all[i].smeared_confidence = smeared_prob[2 * next_smeared++ + 1];
      // (routed only where BallNet rejected)
      if (all[i].smeared_confidence >= params_.smeared_ball_min_confidence && untaken(k)) {
        hits.emplace_back(all[i].smeared_confidence, i);
        smeared_centre[i] = smearedBallCentre(image, proposals[i].centre_px, proposals[i].radius_px, along[k],
                                              params_.smeared_centre_reach_radii,
                                              params_.smeared_centre_min_contrast_gray);
      }
    }
  }
  std::stable_sort(hits.begin(), hits.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  for (const auto& [conf, i] : hits) {
    if (static_cast<int>(out.size()) >= params_.max_balls) break;
    all[i].detected = true;
    BallPercept b;
    // (where it was at the frame's time: a rolling shutter read its row earlier or later)
    b.centre_px = camera.atFrameTime(smeared_centre[i].value_or(proposals[i].centre_px));
    b.radius_px = proposals[i].radius_px * radius_scale[i];
    b.confidence = conf;
    b.position_in_robot = camera.pixelToGround(b.centre_px, params_.ball_radius_m);
    out.push_back(b);
  }
  if (decisions) *decisions = std::move(all);
  return out;
}

}  // namespace colorfree
