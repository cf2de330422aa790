#include "colorfree/groundtruth/scorer.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "colorfree/groundtruth/gallery.h"
#include "colorfree/groundtruth/matching.h"
#include "colorfree/perception/error.h"

namespace colorfree {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180;
constexpr int kCropSizePx = 160;
constexpr int kFrameThumbWidthPx = 480;
constexpr double kToleranceEpsilon = 1e-9;

using json = nlohmann::json;

struct ObjectTally {
  long proposal_frames = 0, proposals = 0, proposal_truths = 0, proposal_hits = 0;
  long detector_frames = 0, percepts = 0, truths = 0, detected = 0, false_positives = 0;
  long true_positives = 0;
  long should_detect = 0;  // whether or not a detector ran
  long position_errors = 0;
  double position_error_sum = 0, position_error_sq = 0;
};

struct BinTally {
  long truths = 0, detected = 0;
};

struct RateTally {
  long truths = 0, hits = 0, percepts = 0, false_positives = 0;
};

struct TimeTally {
  long n = 0;
  double sum = 0, max = 0;
};

struct ClassifierTally {
  long samples = 0, correct = 0, true_pos = 0, false_pos = 0, false_neg = 0;
  long ambiguous = 0;  ///< samples on an object too hidden or too small to demand: left out
};

using ClassCounts = std::array<long, kOrientationClassCount>;

struct Tally {
  long frames = 0;
  ObjectTally ball, robot;
  std::map<int, BinTally> ball_by_distance, robot_by_distance;
  std::map<int, BinTally> ball_by_visibility, robot_by_visibility;
  long orientation_frames = 0;
  ClassCounts orientation_raw{}, orientation_filtered{};
  std::map<int, std::pair<ClassCounts, ClassCounts>> orientation_by_heading;
  long field_frames = 0;
  RateTally lines, intersections, circle, marks;
  long pose_frames = 0, pose_fits = 0;
  double pose_error_sum_mm = 0, pose_error_sq_mm = 0;
  std::map<std::string, TimeTally> timing;
  std::map<std::string, ClassifierTally> classifiers;
};

json rate(long num, long den) {
  return den > 0 ? json(static_cast<double>(num) / den) : json(nullptr);
}
json perFrame(long n, long frames) {
  return frames > 0 ? json(static_cast<double>(n) / frames) : json(nullptr);
}

json objectJson(const ObjectTally& t) {
  json j;
  j["detection_rate"] = t.detector_frames > 0 ? rate(t.detected, t.truths) : json(nullptr);
  j["proposal_recall"] =
      t.proposal_frames > 0 ? rate(t.proposal_hits, t.proposal_truths) : json(nullptr);
  j["proposals_per_frame"] = perFrame(t.proposals, t.proposal_frames);
  j["false_positives_per_frame"] = perFrame(t.false_positives, t.detector_frames);
  j["precision"] = rate(t.true_positives, t.true_positives + t.false_positives);
  j["position_error_m"] =
      t.position_errors > 0 ? json(t.position_error_sum / t.position_errors) : json(nullptr);
  j["position_error_rms_m"] = t.position_errors > 0
                                  ? json(std::sqrt(t.position_error_sq / t.position_errors))
                                  : json(nullptr);
  j["counts"] = {{"proposal_frames", t.proposal_frames},
                 {"proposals", t.proposals},
                 {"proposal_truths", t.proposal_truths},
                 {"proposal_hits", t.proposal_hits},
                 {"detector_frames", t.detector_frames},
                 {"percepts", t.percepts},
                 {"truths", t.truths},
                 {"detected", t.detected},
                 {"should_detect", t.should_detect},
                 {"true_positives", t.true_positives},
                 {"false_positives", t.false_positives},
                 {"position_errors", t.position_errors}};
  return j;
}

json classesJson(const ClassCounts& c, bool present) {
  long total = 0;
  for (long v : c) total += v;
  json j;
  const char* names[] = {"perceived", "semi_perceived", "not_perceived", "false_positive"};
  for (int k = 0; k < kOrientationClassCount; ++k) {
    j[names[k]] = present ? rate(c[k], total) : json(nullptr);
  }
  j["robot_frames"] = total;
  return j;
}

// Bins `width` wide as {from_UNIT, to_UNIT, truths, detection_rate} (unit: "m", "fraction").
json binsJson(const std::map<int, BinTally>& bins, double width, const std::string& unit) {
  // (Rounded to 1e-12: bin 6 of 0.1 is 0.6, not 0.6000000000000001.)
  const auto edge = [&](int i) { return std::round(i * width * 1e12) / 1e12; };
  json a = json::array();
  for (const auto& [k, b] : bins) {
    a.push_back({{"from_" + unit, edge(k)},
                 {"to_" + unit, edge(k + 1)},
                 {"truths", b.truths},
                 {"detection_rate", rate(b.detected, b.truths)}});
  }
  return a;
}

json tallyJson(const Tally& t, const ScoringParams& p) {
  json j;
  j["frames"] = t.frames;
  j["ball"] = objectJson(t.ball);
  j["robot"] = objectJson(t.robot);
  const bool ori = t.orientation_frames > 0;
  json o = classesJson(t.orientation_raw, ori);
  o["tolerance_deg"] = p.orientation_tolerance_deg;
  o["filtered"] = classesJson(t.orientation_filtered, ori);
  json per = json::array();
  for (const auto& [bin, counts] : t.orientation_by_heading) {
    per.push_back({{"heading_deg", bin * p.orientation_heading_bin_deg},
                   {"raw", classesJson(counts.first, ori)},
                   {"filtered", classesJson(counts.second, ori)}});
  }
  o["per_heading"] = per;
  j["orientation"] = o;
  json f;
  const bool ff = t.field_frames > 0;
  f["line_detection_rate"] = ff ? rate(t.lines.hits, t.lines.truths) : json(nullptr);
  f["intersection_detection_rate"] =
      ff ? rate(t.intersections.hits, t.intersections.truths) : json(nullptr);
  f["centre_circle_detection_rate"] = ff ? rate(t.circle.hits, t.circle.truths) : json(nullptr);
  f["penalty_mark_detection_rate"] = ff ? rate(t.marks.hits, t.marks.truths) : json(nullptr);
  f["false_lines_per_frame"] =
      ff ? perFrame(t.lines.false_positives, t.field_frames) : json(nullptr);
  f["false_intersections_per_frame"] =
      ff ? perFrame(t.intersections.false_positives, t.field_frames) : json(nullptr);
  f["pose_error_mm"] = t.pose_fits > 0 ? json(t.pose_error_sum_mm / t.pose_fits) : json(nullptr);
  f["pose_error_rms_mm"] =
      t.pose_fits > 0 ? json(std::sqrt(t.pose_error_sq_mm / t.pose_fits)) : json(nullptr);
  f["pose_fit_rate"] = t.pose_frames > 0 ? rate(t.pose_fits, t.pose_frames) : json(nullptr);
  f["counts"] = {{"frames", t.field_frames},
                 {"lines_in_view", t.lines.truths},
                 {"lines_detected", t.lines.hits},
                 {"line_percepts", t.lines.percepts},
                 {"false_lines", t.lines.false_positives},
                 {"intersections_in_view", t.intersections.truths},
                 {"intersections_detected", t.intersections.hits},
                 {"intersection_percepts", t.intersections.percepts},
                 {"false_intersections", t.intersections.false_positives},
                 {"pose_frames", t.pose_frames},
                 {"pose_fits", t.pose_fits}};
  j["field_features"] = f;
  json tm = json::object();
  for (const auto& s : paperStageNames()) tm[s] = {{"mean", nullptr}, {"max", nullptr}};
  for (const auto& [name, tt] : t.timing) {
    tm[name] = {{"mean", tt.n > 0 ? json(tt.sum / tt.n) : json(nullptr)},
                {"max", tt.n > 0 ? json(tt.max) : json(nullptr)}};
  }
  j["timing_ms"] = tm;
  json cnn = json::object();
  for (const auto& s : paperClassifierNames()) cnn[s] = {{"accuracy", nullptr}, {"samples", 0}};
  for (const auto& [name, c] : t.classifiers) {
    cnn[name] = {{"accuracy", rate(c.correct, c.samples)},
                 {"samples", c.samples},
                 {"true_positives", c.true_pos},
                 {"false_positives", c.false_pos},
                 {"false_negatives", c.false_neg},
                 {"ambiguous", c.ambiguous}};
  }
  j["cnn"] = cnn;
  j["by_distance"] = {{"ball", binsJson(t.ball_by_distance, p.distance_bin_m, "m")},
                      {"robot", binsJson(t.robot_by_distance, p.distance_bin_m, "m")}};
  j["by_visibility"] = {
      {"ball", binsJson(t.ball_by_visibility, p.visibility_bin_fraction, "fraction")},
      {"robot", binsJson(t.robot_by_visibility, p.visibility_bin_fraction, "fraction")}};
  return j;
}

json paramsJson(const ScoringParams& p) {
  return {{"ball_min_visible_fraction", p.ball_min_visible_fraction},
          {"ball_min_distance_m", p.ball_min_distance_m},
          {"ball_max_distance_m", p.ball_max_distance_m},
          {"ball_min_radius_px", p.ball_min_radius_px},
          {"robot_min_visible_fraction", p.robot_min_visible_fraction},
          {"robot_min_distance_m", p.robot_min_distance_m},
          {"robot_max_distance_m", p.robot_max_distance_m},
          {"robot_min_height_px", p.robot_min_height_px},
          {"robot_depth_m", p.robot_depth_m},
          {"robot_feet_region_height_m", p.robot_feet_region_height_m},
          {"foot_lateral_offset_m", p.foot_lateral_offset_m},
          {"ball_match_radius_fraction", p.ball_match_radius_fraction},
          {"ball_match_min_px", p.ball_match_min_px},
          {"robot_match_min_iou", p.robot_match_min_iou},
          {"robot_match_max_feet_distance_m", p.robot_match_max_feet_distance_m},
          {"orientation_tolerance_deg", p.orientation_tolerance_deg},
          {"orientation_heading_bin_deg", p.orientation_heading_bin_deg},
          {"field_feature_max_distance_m", p.field_feature_max_distance_m},
          {"line_min_length_px", p.line_min_length_px},
          {"line_match_max_px", p.line_match_max_px},
          {"intersection_match_max_px", p.intersection_match_max_px},
          {"feature_visibility_window_px", p.feature_visibility_window_px},
          {"pose_guess_offset_m", p.pose_guess_offset_m},
          {"pose_guess_offset_deg", p.pose_guess_offset_deg},
          {"distance_bin_m", p.distance_bin_m},
          {"visibility_bin_fraction", p.visibility_bin_fraction}};
}

bool segmentNear(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const LineInImage& truth,
                 double max_px) {
  for (const Eigen::Vector2d& p : {a, b, Eigen::Vector2d((a + b) / 2)}) {
    if (pointSegmentDistance(p, truth.start_px, truth.end_px) > max_px) return false;
  }
  return true;
}

bool onCircle(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
              const std::vector<LineInImage>& pieces, double max_px) {
  if (pieces.empty()) return false;
  for (const Eigen::Vector2d& p : {a, b, Eigen::Vector2d((a + b) / 2)}) {
    double best = 1e300;
    for (const auto& piece : pieces)
      best = std::min(best, pointSegmentDistance(p, piece.start_px, piece.end_px));
    if (best > max_px) return false;
  }
  return true;
}

std::string fmt(double v, int prec = 2) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(prec);
  s << v;
  return s.str();
}

}  // namespace

const char* orientationClassName(OrientationClass c) {
  switch (c) {
    case OrientationClass::kPerceived:
      return "perceived";
    case OrientationClass::kSemiPerceived:
      return "semi_perceived";
    case OrientationClass::kNotPerceived:
      return "not_perceived";
    case OrientationClass::kFalsePositive:
      return "false_positive";
  }
  return "?";
}

OrientationClass classifyOrientation(const std::optional<RobotOrientation>& estimate,
                                     double true_angle_rad, double tolerance_rad) {
  if (!estimate) return OrientationClass::kNotPerceived;
  const double err = std::abs(wrapAngle(estimate->angle_rad - true_angle_rad));
  const double flipped = kPi - err;  // error of the opposite facing
  const double tol = tolerance_rad + kToleranceEpsilon;
  if (estimate->facing_known) {
    if (err <= tol) return OrientationClass::kPerceived;
    if (flipped <= tol) return OrientationClass::kSemiPerceived;
    return OrientationClass::kFalsePositive;
  }
  return std::min(err, flipped) <= tol ? OrientationClass::kSemiPerceived
                                       : OrientationClass::kFalsePositive;
}

const std::vector<std::string>& paperStageNames() {
  static const std::vector<std::string> kNames = {
      "high_contrast",     "field_features", "robot_proposals", "robot_detector",
      "robot_orientation", "ball_proposals", "ball_detector"};
  return kNames;
}

const std::vector<std::string>& paperClassifierNames() {
  static const std::vector<std::string> kNames = {"RobotNet", "BoostBallNet", "BallNet",
                                                  "OriBoostNet", "OriNet"};
  return kNames;
}

struct Scorer::State {
  Tally total;
  std::vector<std::pair<CaseInfo, Tally>> cases;
  std::map<std::string, std::vector<GalleryItem>> gallery_by_kind;
  std::vector<GalleryItem> gallery;  // flattened view, rebuilt on change
  void rebuildGallery() {
    gallery.clear();
    for (const auto& [k, v] : gallery_by_kind) gallery.insert(gallery.end(), v.begin(), v.end());
  }
};

Scorer::Scorer(ScoringParams params, FieldDimensions dims)
    : params_(params),
      dims_(dims),
      field_(FieldMarkings::fromDimensions(dims)),
      state_(std::make_unique<State>()) {}
Scorer::~Scorer() = default;
Scorer::Scorer(Scorer&&) noexcept = default;
Scorer& Scorer::operator=(Scorer&&) noexcept = default;

void Scorer::beginCase(const CaseInfo& info) { state_->cases.push_back({info, Tally{}}); }

int Scorer::frameCount() const { return static_cast<int>(state_->total.frames); }

const std::vector<GalleryItem>& Scorer::gallery() const { return state_->gallery; }

FrameTruth Scorer::addFrame(const WorldState& world, const FramePercepts& percepts,
                            const GrayImage* image) {
  FrameTruth truth = computeFrameTruth(world, field_, dims_, params_);
  addFrame(truth, percepts, &world.camera.model, image);
  return truth;
}

void Scorer::addFrame(const FrameTruth& truth, const FramePercepts& pc, const CameraModel* camera,
                      const GrayImage* image) {
  if (state_->cases.empty()) beginCase(CaseInfo{});
  Tally& case_tally = state_->cases.back().second;
  const ScoringParams& p = params_;
  const Eigen::Isometry3d robot_to_field = robotToField(truth.observer);
  auto toField = [&](const Eigen::Vector2d& in_robot) {
    return Eigen::Vector2d(
        (robot_to_field * Eigen::Vector3d(in_robot.x(), in_robot.y(), 0)).head<2>());
  };
  auto feetInField = [&](const Eigen::Vector2d& feet_px) -> std::optional<Eigen::Vector2d> {
    if (!camera) return std::nullopt;
    const auto g = camera->pixelToGround(feet_px);
    if (!g) return std::nullopt;
    return toField(*g);
  };
  auto distanceBin = [&](double d) { return static_cast<int>(std::floor(d / p.distance_bin_m)); };
  // (A whole object, visible fraction 1, falls in the last bin below 1, not in one of its own.)
  const int last_visibility_bin =
      std::max(0, static_cast<int>(std::ceil(1 / p.visibility_bin_fraction - 1e-9)) - 1);
  auto visibilityBin = [&](double f) {
    return std::clamp(static_cast<int>(std::floor(f / p.visibility_bin_fraction)), 0,
                      last_visibility_bin);
  };
  std::vector<Tally*> tallies = {&state_->total, &case_tally};
  const std::string where =
      state_->cases.back().first.name + " frame " + std::to_string(truth.frame_index);
  for (Tally* t : tallies) ++t->frames;

  // Events for the gallery: (kind, severity, region, overlays, caption).
  struct Event {
    std::string kind;
    double severity;
    PixelBox region;
    std::vector<Overlay> overlays;
    std::string caption;
  };
  std::vector<Event> events;
  std::vector<Overlay> frame_overlays;
  int frame_errors = 0;

  // Ball.
  std::vector<BallInImage> balls;
  if (truth.ball_present && truth.ball.in_view) balls.push_back(truth.ball);
  auto ballOverlay = [](const BallInImage& b) {
    Overlay o;
    o.shape = Overlay::Shape::kCircle;
    o.a = b.centre_px;
    o.radius_px = b.radius_px;
    return o;
  };
  for (const auto& b : balls) {
    frame_overlays.push_back(ballOverlay(b));
    if (b.should_detect)
      for (Tally* t : tallies) ++t->ball.should_detect;
  }
  if (pc.ball_proposals) {
    for (Tally* t : tallies) {
      ++t->ball.proposal_frames;
      t->ball.proposals += static_cast<long>(pc.ball_proposals->size());
    }
    for (const auto& b : balls) {
      if (!b.should_detect) continue;
      bool hit = false;
      for (const auto& prop : *pc.ball_proposals)
        hit = hit || ballMatchCost(b, prop.centre_px, p).has_value();
      for (Tally* t : tallies) {
        ++t->ball.proposal_truths;
        if (hit) ++t->ball.proposal_hits;
      }
    }
  }
  if (pc.balls) {
    const auto& percepts = *pc.balls;
    std::vector<MatchCandidate> cands;
    for (std::size_t ti = 0; ti < balls.size(); ++ti) {
      for (std::size_t pi = 0; pi < percepts.size(); ++pi) {
        if (auto c = ballMatchCost(balls[ti], percepts[pi].centre_px, p)) {
          cands.push_back({static_cast<int>(ti), static_cast<int>(pi), *c});
        }
      }
    }
    const Matching m =
        matchOneToOne(static_cast<int>(balls.size()), static_cast<int>(percepts.size()), cands);
    for (Tally* t : tallies) {
      ++t->ball.detector_frames;
      t->ball.percepts += static_cast<long>(percepts.size());
    }
    for (std::size_t ti = 0; ti < balls.size(); ++ti) {
      const auto& b = balls[ti];
      if (!b.should_detect) continue;
      const int pi = m.truth_to_percept[ti];
      std::optional<double> err;
      if (pi >= 0 && percepts[pi].position_in_robot) {
        err = (toField(*percepts[pi].position_in_robot) - b.position_in_field).norm();
      }
      for (Tally* t : tallies) {
        ++t->ball.truths;
        auto& bin = t->ball_by_distance[distanceBin(b.distance_m)];
        auto& vbin = t->ball_by_visibility[visibilityBin(b.visible_fraction)];
        ++bin.truths;
        ++vbin.truths;
        if (pi >= 0) {
          ++t->ball.detected;
          ++t->ball.true_positives;
          ++bin.detected;
          ++vbin.detected;
        }
        if (err) {
          ++t->ball.position_errors;
          t->ball.position_error_sum += *err;
          t->ball.position_error_sq += *err * *err;
        }
      }
      if (pi < 0) {
        ++frame_errors;
        std::vector<Overlay> ov = {ballOverlay(b)};
        if (pc.ball_proposals) {
          for (const auto& prop : *pc.ball_proposals) {
            if ((prop.centre_px - b.centre_px).norm() < 4 * b.radius_px + 10) {
              Overlay o;
              o.shape = Overlay::Shape::kCircle;
              o.role = Overlay::Role::kProposal;
              o.a = prop.centre_px;
              o.radius_px = prop.radius_px;
              ov.push_back(o);
            }
          }
        }
        events.push_back({"missed_ball",
                          b.visible_fraction,
                          {b.centre_px.x() - b.radius_px, b.centre_px.y() - b.radius_px,
                           b.centre_px.x() + b.radius_px, b.centre_px.y() + b.radius_px},
                          ov,
                          where + ": missed ball, r " + fmt(b.radius_px, 1) + " px, " +
                              fmt(b.distance_m) + " m, visible " +
                              fmt(100 * b.visible_fraction, 0) + " %"});
      }
    }
    for (std::size_t pi = 0; pi < percepts.size(); ++pi) {
      Overlay o;
      o.shape = Overlay::Shape::kCircle;
      o.role = Overlay::Role::kPercept;
      o.a = percepts[pi].centre_px;
      o.radius_px = percepts[pi].radius_px;
      frame_overlays.push_back(o);
      const int ti = m.percept_to_truth[pi];
      if (ti >= 0) continue;  // a hit, or a detection of a don't-care ball
      for (Tally* t : tallies) ++t->ball.false_positives;
      ++frame_errors;
      const auto& q = percepts[pi];
      events.push_back({"false_ball",
                        q.confidence,
                        {q.centre_px.x() - q.radius_px, q.centre_px.y() - q.radius_px,
                         q.centre_px.x() + q.radius_px, q.centre_px.y() + q.radius_px},
                        {o},
                        where + ": false ball, confidence " + fmt(q.confidence)});
    }
  }

  // Robots.
  std::vector<const RobotInImage*> robots;
  for (const auto& r : truth.robots) {
    if (r.in_view) robots.push_back(&r);
  }
  auto robotOverlay = [](const RobotInImage& r) {
    Overlay o;
    o.box = r.box;
    // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "literal" + std::string&&.
    o.label = "R";
    o.label += std::to_string(r.index);
    o.label += ' ';
    o.label += robotSideName(r.side_seen);
    return o;
  };
  for (const auto* r : robots) {
    frame_overlays.push_back(robotOverlay(*r));
    if (r->should_detect)
      for (Tally* t : tallies) ++t->robot.should_detect;
  }
  if (pc.robot_proposals) {
    for (Tally* t : tallies) {
      ++t->robot.proposal_frames;
      t->robot.proposals += static_cast<long>(pc.robot_proposals->size());
    }
    for (const auto* r : robots) {
      if (!r->should_detect) continue;
      bool hit = false;
      for (const auto& prop : *pc.robot_proposals) {
        hit = hit || robotMatchCost(*r, prop.box, feetInField(prop.feet_px), p).has_value();
      }
      for (Tally* t : tallies) {
        ++t->robot.proposal_truths;
        if (hit) ++t->robot.proposal_hits;
      }
    }
  }
  if (pc.robots) {
    const auto& percepts = *pc.robots;
    std::vector<MatchCandidate> cands;
    for (std::size_t ti = 0; ti < robots.size(); ++ti) {
      for (std::size_t pi = 0; pi < percepts.size(); ++pi) {
        if (auto c = robotMatchCost(*robots[ti], percepts[pi].box,
                                    feetInField(percepts[pi].feet_px), p)) {
          cands.push_back({static_cast<int>(ti), static_cast<int>(pi), *c});
        }
      }
    }
    const Matching m =
        matchOneToOne(static_cast<int>(robots.size()), static_cast<int>(percepts.size()), cands);
    for (Tally* t : tallies) {
      ++t->robot.detector_frames;
      t->robot.percepts += static_cast<long>(percepts.size());
      if (pc.orientation_stage) ++t->orientation_frames;
    }
    const double tol = p.orientation_tolerance_deg * kDeg;
    const int bins =
        std::max(1, static_cast<int>(std::lround(360.0 / p.orientation_heading_bin_deg)));
    for (std::size_t ti = 0; ti < robots.size(); ++ti) {
      const auto& r = *robots[ti];
      if (!r.should_detect) continue;
      const int pi = m.truth_to_percept[ti];
      std::optional<double> err;
      if (pi >= 0 && percepts[pi].position_in_robot) {
        err = (toField(*percepts[pi].position_in_robot) - r.position_in_field).norm();
      }
      OrientationClass raw = OrientationClass::kNotPerceived,
                       filtered = OrientationClass::kNotPerceived;
      if (pi >= 0) {
        raw = classifyOrientation(percepts[pi].orientation_raw, r.heading_in_observer_rad, tol);
        filtered =
            classifyOrientation(percepts[pi].orientation_filtered, r.heading_in_observer_rad, tol);
      }
      double rel_deg = r.heading_rel_rad / kDeg;
      if (rel_deg < 0) rel_deg += 360;
      const int bin = static_cast<int>(std::lround(rel_deg / p.orientation_heading_bin_deg)) % bins;
      for (Tally* t : tallies) {
        ++t->robot.truths;
        auto& dbin = t->robot_by_distance[distanceBin(r.distance_m)];
        auto& vbin = t->robot_by_visibility[visibilityBin(r.visible_fraction)];
        ++dbin.truths;
        ++vbin.truths;
        if (pi >= 0) {
          ++t->robot.detected;
          ++t->robot.true_positives;
          ++dbin.detected;
          ++vbin.detected;
        }
        if (err) {
          ++t->robot.position_errors;
          t->robot.position_error_sum += *err;
          t->robot.position_error_sq += *err * *err;
        }
        if (pc.orientation_stage) {
          ++t->orientation_raw[static_cast<int>(raw)];
          ++t->orientation_filtered[static_cast<int>(filtered)];
          auto& hb = t->orientation_by_heading[bin];
          ++hb.first[static_cast<int>(raw)];
          ++hb.second[static_cast<int>(filtered)];
        }
      }
      if (pi < 0) {
        ++frame_errors;
        std::vector<Overlay> ov = {robotOverlay(r)};
        if (pc.robot_proposals) {
          for (const auto& prop : *pc.robot_proposals) {
            if (boxIou(prop.box, r.box) > 0.05) {
              Overlay o;
              o.role = Overlay::Role::kProposal;
              o.box = prop.box;
              ov.push_back(o);
            }
          }
        }
        events.push_back({"missed_robot", r.visible_fraction, r.box, ov,
                          where + ": missed robot " + std::to_string(r.index) + ", " +
                              fmt(r.distance_m) + " m, visible " +
                              fmt(100 * r.visible_fraction, 0) + " %"});
      } else if (pc.orientation_stage && raw == OrientationClass::kFalsePositive) {
        Overlay o;
        o.role = Overlay::Role::kPercept;
        o.box = percepts[pi].box;
        o.label = "est " + fmt(percepts[pi].orientation_raw->angle_rad / kDeg, 0) + " deg";
        events.push_back({"orientation",
                          1.0,
                          r.box,
                          {robotOverlay(r), o},
                          where + ": orientation false positive, true " +
                              fmt(r.heading_in_observer_rad / kDeg, 0) + " deg (observer frame), " +
                              fmt(rel_deg, 0) + " deg to the line of sight"});
      }
    }
    for (std::size_t pi = 0; pi < percepts.size(); ++pi) {
      Overlay o;
      o.role = Overlay::Role::kPercept;
      o.box = percepts[pi].box;
      frame_overlays.push_back(o);
      if (m.percept_to_truth[pi] >= 0) continue;
      for (Tally* t : tallies) ++t->robot.false_positives;
      ++frame_errors;
      events.push_back({"false_robot",
                        percepts[pi].confidence,
                        percepts[pi].box,
                        {o},
                        where + ": false robot, confidence " + fmt(percepts[pi].confidence)});
    }
  }

  // Field lines and features.
  if (pc.field_features) {
    const auto& ff = *pc.field_features;
    const auto& fi = truth.field;
    for (Tally* t : tallies) ++t->field_frames;
    std::vector<bool> line_hit(fi.lines.size(), false);
    long false_lines = 0;
    for (const auto& l : ff.lines) {
      bool matched = false;
      for (std::size_t k = 0; k < fi.lines.size(); ++k) {
        if (segmentNear(l.start_px, l.end_px, fi.lines[k], p.line_match_max_px)) {
          line_hit[k] = true;
          matched = true;
        }
      }
      if (!matched && !onCircle(l.start_px, l.end_px, fi.circle_pieces, p.line_match_max_px))
        ++false_lines;
    }
    std::vector<MatchCandidate> cands;
    for (std::size_t ti = 0; ti < fi.intersections.size(); ++ti) {
      for (std::size_t pi = 0; pi < ff.intersections.size(); ++pi) {
        if (ff.intersections[pi].type != fi.intersections[ti].type) continue;
        const double d =
            (ff.intersections[pi].position_px - fi.intersections[ti].position_px).norm();
        if (d <= p.intersection_match_max_px)
          cands.push_back({static_cast<int>(ti), static_cast<int>(pi), d});
      }
    }
    const Matching mi = matchOneToOne(static_cast<int>(fi.intersections.size()),
                                      static_cast<int>(ff.intersections.size()), cands);
    std::vector<MatchCandidate> mark_cands;
    for (std::size_t ti = 0; ti < fi.penalty_marks.size(); ++ti) {
      for (std::size_t pi = 0; pi < ff.penalty_marks.size(); ++pi) {
        const double d = (ff.penalty_marks[pi].centre_px - fi.penalty_marks[ti].position_px).norm();
        if (d <= p.intersection_match_max_px)
          mark_cands.push_back({static_cast<int>(ti), static_cast<int>(pi), d});
      }
    }
    const Matching mm = matchOneToOne(static_cast<int>(fi.penalty_marks.size()),
                                      static_cast<int>(ff.penalty_marks.size()), mark_cands);
    auto cross = [](const Eigen::Vector2d& at, Overlay::Role role, IntersectionType type) {
      Overlay o;
      o.shape = Overlay::Shape::kCross;
      o.role = role;
      o.a = at;
      o.label = intersectionTypeName(type);
      return o;
    };
    const double pad = 3 * p.intersection_match_max_px;
    for (std::size_t ti = 0; ti < fi.intersections.size(); ++ti) {
      if (mi.truth_to_percept[ti] >= 0) continue;
      const auto& x = fi.intersections[ti];
      std::vector<Overlay> ov = {cross(x.position_px, Overlay::Role::kTruth, x.type)};
      for (const auto& q : ff.intersections) {
        if ((q.position_px - x.position_px).norm() < pad)
          ov.push_back(cross(q.position_px, Overlay::Role::kPercept, q.type));
      }
      events.push_back({"missed_intersection",
                        0.0,
                        {x.position_px.x() - pad, x.position_px.y() - pad, x.position_px.x() + pad,
                         x.position_px.y() + pad},
                        ov,
                        where + ": missed " + intersectionTypeName(x.type) + " at field (" +
                            fmt(x.position_in_field.x()) + ", " + fmt(x.position_in_field.y()) +
                            ")"});
    }
    for (std::size_t pi = 0; pi < ff.intersections.size(); ++pi) {
      if (mi.percept_to_truth[pi] >= 0) continue;
      const auto& q = ff.intersections[pi];
      std::vector<Overlay> ov = {cross(q.position_px, Overlay::Role::kPercept, q.type)};
      for (const auto& x : fi.intersections) {
        if ((q.position_px - x.position_px).norm() < pad)
          ov.push_back(cross(x.position_px, Overlay::Role::kTruth, x.type));
      }
      events.push_back({"false_intersection",
                        0.0,
                        {q.position_px.x() - pad, q.position_px.y() - pad, q.position_px.x() + pad,
                         q.position_px.y() + pad},
                        ov,
                        where + ": false " + intersectionTypeName(q.type)});
    }
    const bool circle_hit =
        fi.centre_circle_in_view && ff.centre_circle && fi.circle_centre_px &&
        (ff.centre_circle->centre_px - *fi.circle_centre_px).norm() <= p.intersection_match_max_px;
    for (Tally* t : tallies) {
      t->lines.truths += static_cast<long>(fi.lines.size());
      t->lines.hits += std::count(line_hit.begin(), line_hit.end(), true);
      t->lines.percepts += static_cast<long>(ff.lines.size());
      t->lines.false_positives += false_lines;
      t->intersections.truths += static_cast<long>(fi.intersections.size());
      t->intersections.percepts += static_cast<long>(ff.intersections.size());
      for (int v : mi.truth_to_percept) t->intersections.hits += v >= 0;
      for (int v : mi.percept_to_truth) t->intersections.false_positives += v < 0;
      t->marks.truths += static_cast<long>(fi.penalty_marks.size());
      for (int v : mm.truth_to_percept) t->marks.hits += v >= 0;
      if (fi.centre_circle_in_view) {
        ++t->circle.truths;
        t->circle.hits += circle_hit;
      }
    }
  }
  if (pc.pose_fit_stage) {
    std::optional<double> err_mm;
    if (pc.pose_in_field) {
      err_mm = 1000 * std::hypot(pc.pose_in_field->x_m - truth.observer.x_m,
                                 pc.pose_in_field->y_m - truth.observer.y_m);
    }
    for (Tally* t : tallies) {
      ++t->pose_frames;
      if (err_mm) {
        ++t->pose_fits;
        t->pose_error_sum_mm += *err_mm;
        t->pose_error_sq_mm += *err_mm * *err_mm;
      }
    }
  }

  for (const auto& [stage, ms] : pc.stage_times_ms) {
    for (Tally* t : tallies) {
      auto& tt = t->timing[stage];
      ++tt.n;
      tt.sum += ms;
      tt.max = std::max(tt.max, ms);
    }
  }

  // A sample's label, as the detection scoring and the training loop see it: on an object that
  // should be detected, positive; on an object in view that is too hidden or too small to demand,
  // neither (the detector may take it or not: a percept there is no false positive either), so it
  // is left out of the accuracy and counted as ambiguous; elsewhere, negative.
  for (const auto& s : pc.classifier_samples) {
    bool on_demanded = false, on_other = false;
    if (s.object == ClassifierSample::Object::kBall) {
      for (const auto& b : balls) {
        if (ballMatchCost(b, s.centre_px, p)) (b.should_detect ? on_demanded : on_other) = true;
      }
    } else {
      for (const auto* r : robots) {
        if (robotMatchCost(*r, s.box, feetInField(s.feet_px), p))
          (r->should_detect ? on_demanded : on_other) = true;
      }
    }
    const bool label = on_demanded;
    for (Tally* t : tallies) {
      auto& c = t->classifiers[s.classifier];
      if (!on_demanded && on_other) {
        ++c.ambiguous;
        continue;
      }
      ++c.samples;
      c.correct += label == s.predicted_positive;
      c.true_pos += label && s.predicted_positive;
      c.false_pos += !label && s.predicted_positive;
      c.false_neg += label && !s.predicted_positive;
    }
  }

  if (!image || image->empty()) return;
  // Keep the worst events per kind; render a crop only when it makes the cut.
  auto offer = [&](const std::string& kind, double severity, int limit, auto render) {
    auto& list = state_->gallery_by_kind[kind];
    if (limit <= 0) return;
    if (static_cast<int>(list.size()) >= limit && severity <= list.back().severity) return;
    GalleryItem item = render();
    item.kind = kind;
    item.severity = severity;
    item.frame = truth.frame_index;
    list.push_back(std::move(item));
    std::stable_sort(list.begin(), list.end(),
                     [](const auto& a, const auto& b) { return a.severity > b.severity; });
    if (static_cast<int>(list.size()) > limit) list.pop_back();
    state_->rebuildGallery();
  };
  for (const auto& e : events) {
    offer(e.kind, e.severity, p.gallery_max_crops, [&] {
      GalleryItem g;
      g.caption = e.caption;
      g.png_base64 = cropPngBase64(*image, e.region, e.overlays, kCropSizePx);
      return g;
    });
  }
  if (frame_errors > 0) {
    offer("worst_frame", frame_errors, p.gallery_worst_frames, [&] {
      GalleryItem g;
      g.caption = where + ": " + std::to_string(frame_errors) +
                  " misses and false detections (green truth, red percepts)";
      g.png_base64 = cropPngBase64(
          *image, {0, 0, static_cast<double>(image->width()), static_cast<double>(image->height())},
          frame_overlays, std::max(image->width(), kFrameThumbWidthPx));
      return g;
    });
  }
}

nlohmann::json Scorer::results(const RunInfo& run) const {
  json j = tallyJson(state_->total, params_);
  j["scenario"] = run.scenario;
  j["seed"] = run.seed;
  j["frame_count"] = state_->total.frames;
  j["code_version"] = run.code_version;
  j["scoring"] = paramsJson(params_);
  j["should_detect_rule"] = params_.shouldDetectRule();
  j["matching_rule"] = params_.matchingRule();
  json cases = json::array();
  for (const auto& [info, tally] : state_->cases) {
    json c = tallyJson(tally, params_);
    c["name"] = info.name;
    json settings = json::object();
    for (const auto& [k, v] : info.numeric_settings) settings[k] = v;
    for (const auto& [k, v] : info.text_settings) settings[k] = v;
    c["settings"] = settings;
    cases.push_back(c);
  }
  j["cases"] = cases;
  return j;
}

}  // namespace colorfree

// Case states: the tallies as JSON, for runs split by case (colorfree bench workers and shards).
namespace colorfree {

namespace {

// Named fields, so that a field added to ObjectTally cannot shift the others.
json objectState(const ObjectTally& t) {
  return {{"proposal_frames", t.proposal_frames}, {"proposals", t.proposals},
          {"proposal_truths", t.proposal_truths}, {"proposal_hits", t.proposal_hits},
          {"detector_frames", t.detector_frames}, {"percepts", t.percepts},
          {"truths", t.truths}, {"detected", t.detected},
          {"false_positives", t.false_positives}, {"true_positives", t.true_positives},
          {"should_detect", t.should_detect}, {"position_errors", t.position_errors},
          {"position_error_sum", t.position_error_sum}, {"position_error_sq", t.position_error_sq}};
}

void objectFromState(const json& j, ObjectTally& t) {
  if (j.size() != 14) throw std::runtime_error("object tally: expected 14 fields");
  t.proposal_frames = j.at("proposal_frames").get<long>();
  t.proposals = j.at("proposals").get<long>();
  t.proposal_truths = j.at("proposal_truths").get<long>();
  t.proposal_hits = j.at("proposal_hits").get<long>();
  t.detector_frames = j.at("detector_frames").get<long>();
  t.percepts = j.at("percepts").get<long>();
  t.truths = j.at("truths").get<long>();
  t.detected = j.at("detected").get<long>();
  t.false_positives = j.at("false_positives").get<long>();
  t.true_positives = j.at("true_positives").get<long>();
  t.should_detect = j.at("should_detect").get<long>();
  t.position_errors = j.at("position_errors").get<long>();
  t.position_error_sum = j.at("position_error_sum").get<double>();
  t.position_error_sq = j.at("position_error_sq").get<double>();
}

json rateState(const RateTally& t) { return {t.truths, t.hits, t.percepts, t.false_positives}; }
RateTally rateFromState(const json& j) {
  if (j.size() != 4) throw std::runtime_error("rate tally size");
  return {j.at(0).get<long>(), j.at(1).get<long>(), j.at(2).get<long>(), j.at(3).get<long>()};
}

json binsState(const std::map<int, BinTally>& bins) {
  json a = json::array();
  for (const auto& [k, b] : bins) a.push_back({k, b.truths, b.detected});
  return a;
}
std::map<int, BinTally> binsFromState(const json& j) {
  std::map<int, BinTally> bins;
  for (const auto& b : j) bins[b.at(0).get<int>()] = {b.at(1).get<long>(), b.at(2).get<long>()};
  return bins;
}

json tallyState(const Tally& t) {
  json j;
  j["frames"] = t.frames;
  j["ball"] = objectState(t.ball);
  j["robot"] = objectState(t.robot);
  j["ball_by_distance"] = binsState(t.ball_by_distance);
  j["robot_by_distance"] = binsState(t.robot_by_distance);
  j["ball_by_visibility"] = binsState(t.ball_by_visibility);
  j["robot_by_visibility"] = binsState(t.robot_by_visibility);
  j["orientation_frames"] = t.orientation_frames;
  j["orientation_raw"] = t.orientation_raw;
  j["orientation_filtered"] = t.orientation_filtered;
  json heading = json::array();
  for (const auto& [bin, c] : t.orientation_by_heading) heading.push_back({bin, c.first, c.second});
  j["orientation_by_heading"] = heading;
  j["field_frames"] = t.field_frames;
  j["lines"] = rateState(t.lines);
  j["intersections"] = rateState(t.intersections);
  j["circle"] = rateState(t.circle);
  j["marks"] = rateState(t.marks);
  j["pose"] = {t.pose_frames, t.pose_fits, t.pose_error_sum_mm, t.pose_error_sq_mm};
  json timing = json::object();
  for (const auto& [name, tt] : t.timing) timing[name] = {tt.n, tt.sum, tt.max};
  j["timing"] = timing;
  json cls = json::object();
  for (const auto& [name, c] : t.classifiers) cls[name] = {c.samples, c.correct, c.true_pos, c.false_pos, c.false_neg, c.ambiguous};
  j["classifiers"] = cls;
  return j;
}

Tally tallyFromState(const json& j) {
  Tally t;
  t.frames = j.at("frames").get<long>();
  objectFromState(j.at("ball"), t.ball);
  objectFromState(j.at("robot"), t.robot);
  t.ball_by_distance = binsFromState(j.at("ball_by_distance"));
  t.robot_by_distance = binsFromState(j.at("robot_by_distance"));
  t.ball_by_visibility = binsFromState(j.at("ball_by_visibility"));
  t.robot_by_visibility = binsFromState(j.at("robot_by_visibility"));
  t.orientation_frames = j.at("orientation_frames").get<long>();
  t.orientation_raw = j.at("orientation_raw").get<ClassCounts>();
  t.orientation_filtered = j.at("orientation_filtered").get<ClassCounts>();
  for (const auto& h : j.at("orientation_by_heading")) {
    t.orientation_by_heading[h.at(0).get<int>()] = {h.at(1).get<ClassCounts>(), h.at(2).get<ClassCounts>()};
  }
  t.field_frames = j.at("field_frames").get<long>();
  t.lines = rateFromState(j.at("lines"));
  t.intersections = rateFromState(j.at("intersections"));
  t.circle = rateFromState(j.at("circle"));
  t.marks = rateFromState(j.at("marks"));
  const json& pose = j.at("pose");
  t.pose_frames = pose.at(0).get<long>();
  t.pose_fits = pose.at(1).get<long>();
  t.pose_error_sum_mm = pose.at(2).get<double>();
  t.pose_error_sq_mm = pose.at(3).get<double>();
  for (auto it = j.at("timing").begin(); it != j.at("timing").end(); ++it) {
    t.timing[it.key()] = {it.value().at(0).get<long>(), it.value().at(1).get<double>(), it.value().at(2).get<double>()};
  }
  for (auto it = j.at("classifiers").begin(); it != j.at("classifiers").end(); ++it) {
    const json& c = it.value();
    t.classifiers[it.key()] = {c.at(0).get<long>(), c.at(1).get<long>(), c.at(2).get<long>(), c.at(3).get<long>(),
                               c.at(4).get<long>(), c.at(5).get<long>()};
  }
  return t;
}

void addObject(ObjectTally& a, const ObjectTally& b) {
  a.proposal_frames += b.proposal_frames;
  a.proposals += b.proposals;
  a.proposal_truths += b.proposal_truths;
  a.proposal_hits += b.proposal_hits;
  a.detector_frames += b.detector_frames;
  a.percepts += b.percepts;
  a.truths += b.truths;
  a.detected += b.detected;
  a.false_positives += b.false_positives;
  a.true_positives += b.true_positives;
  a.should_detect += b.should_detect;
  a.position_errors += b.position_errors;
  a.position_error_sum += b.position_error_sum;
  a.position_error_sq += b.position_error_sq;
}

void addRate(RateTally& a, const RateTally& b) {
  a.truths += b.truths;
  a.hits += b.hits;
  a.percepts += b.percepts;
  a.false_positives += b.false_positives;
}

void addClasses(ClassCounts& a, const ClassCounts& b) {
  for (int k = 0; k < kOrientationClassCount; ++k) a[k] += b[k];
}

void addTally(Tally& a, const Tally& b) {
  a.frames += b.frames;
  addObject(a.ball, b.ball);
  addObject(a.robot, b.robot);
  const auto addBins = [](std::map<int, BinTally>& to, const std::map<int, BinTally>& from) {
    for (const auto& [k, v] : from) {
      to[k].truths += v.truths;
      to[k].detected += v.detected;
    }
  };
  addBins(a.ball_by_distance, b.ball_by_distance);
  addBins(a.robot_by_distance, b.robot_by_distance);
  addBins(a.ball_by_visibility, b.ball_by_visibility);
  addBins(a.robot_by_visibility, b.robot_by_visibility);
  a.orientation_frames += b.orientation_frames;
  addClasses(a.orientation_raw, b.orientation_raw);
  addClasses(a.orientation_filtered, b.orientation_filtered);
  for (const auto& [k, v] : b.orientation_by_heading) {
    addClasses(a.orientation_by_heading[k].first, v.first);
    addClasses(a.orientation_by_heading[k].second, v.second);
  }
  a.field_frames += b.field_frames;
  addRate(a.lines, b.lines);
  addRate(a.intersections, b.intersections);
  addRate(a.circle, b.circle);
  addRate(a.marks, b.marks);
  a.pose_frames += b.pose_frames;
  a.pose_fits += b.pose_fits;
  a.pose_error_sum_mm += b.pose_error_sum_mm;
  a.pose_error_sq_mm += b.pose_error_sq_mm;
  for (const auto& [k, v] : b.timing) {
    auto& t = a.timing[k];
    t.n += v.n;
    t.sum += v.sum;
    t.max = std::max(t.max, v.max);
  }
  for (const auto& [k, v] : b.classifiers) {
    auto& c = a.classifiers[k];
    c.samples += v.samples;
    c.correct += v.correct;
    c.true_pos += v.true_pos;
    c.false_pos += v.false_pos;
    c.false_neg += v.false_neg;
    c.ambiguous += v.ambiguous;
  }
}

}  // namespace

json Scorer::caseStates() const {
  json cases = json::array();
  for (const auto& [info, tally] : state_->cases) {
    cases.push_back({{"name", info.name},
                     {"numeric_settings", info.numeric_settings},
                     {"text_settings", info.text_settings},
                     {"tally", tallyState(tally)}});
  }
  json gallery = json::array();
  for (const auto& g : state_->gallery) {
    gallery.push_back({{"kind", g.kind}, {"caption", g.caption}, {"severity", g.severity}, {"frame", g.frame},
                       {"png_base64", g.png_base64}});
  }
  return {{"cases", cases}, {"gallery", gallery}};
}

void Scorer::addCaseStates(const json& states) {
  try {
    for (const auto& c : states.at("cases")) {
      CaseInfo info;
      info.name = c.at("name").get<std::string>();
      info.numeric_settings = c.at("numeric_settings").get<std::map<std::string, double>>();
      info.text_settings = c.at("text_settings").get<std::map<std::string, std::string>>();
      state_->cases.push_back({info, tallyFromState(c.at("tally"))});
    }
    for (const auto& g : states.at("gallery")) {
      GalleryItem item;
      item.kind = g.at("kind").get<std::string>();
      item.caption = g.at("caption").get<std::string>();
      item.severity = g.at("severity").get<double>();
      item.frame = g.at("frame").get<int>();
      item.png_base64 = g.at("png_base64").get<std::string>();
      state_->gallery_by_kind[item.kind].push_back(std::move(item));
    }
  } catch (const json::exception& e) {
    throw Error(std::string("scorer case states: ") + e.what());
  } catch (const std::runtime_error& e) {
    throw Error(std::string("scorer case states: ") + e.what());
  }
  for (auto& [kind, list] : state_->gallery_by_kind) {
    std::stable_sort(list.begin(), list.end(), [](const auto& a, const auto& b) { return a.severity > b.severity; });
    const int limit = kind == "worst_frame" ? params_.gallery_worst_frames : params_.gallery_max_crops;
    if (static_cast<int>(list.size()) > limit) list.resize(std::max(0, limit));
  }
  state_->rebuildGallery();
  state_->total = Tally{};
  for (const auto& [info, tally] : state_->cases) addTally(state_->total, tally);
}

}  // namespace colorfree
