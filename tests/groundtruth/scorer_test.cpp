#include "colorfree/groundtruth/scorer.h"

#include <gtest/gtest.h>

#include <cmath>

#include "colorfree/groundtruth/matching.h"
#include "test_support.h"

namespace colorfree {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180;
using json = nlohmann::json;

RobotOrientation facing(double deg, bool known = true) { return {deg * kDeg, known}; }

TEST(OrientationClasses, ToleranceBoundariesAreInclusive) {
  const double tol = 11.25 * kDeg;
  EXPECT_EQ(classifyOrientation(facing(11.25), 0, tol), OrientationClass::kPerceived);
  EXPECT_EQ(classifyOrientation(facing(-11.25), 0, tol), OrientationClass::kPerceived);
  EXPECT_EQ(classifyOrientation(facing(11.26), 0, tol), OrientationClass::kFalsePositive);
  EXPECT_EQ(classifyOrientation(facing(-11.26), 0, tol), OrientationClass::kFalsePositive);
  EXPECT_EQ(classifyOrientation(std::nullopt, 0, tol), OrientationClass::kNotPerceived);
}

TEST(OrientationClasses, AcrossTheWrap) {
  const double tol = 11.25 * kDeg;
  // True 359°, estimate 10°: 11° apart across 0°/360°.
  EXPECT_EQ(classifyOrientation(facing(10), 359 * kDeg, tol), OrientationClass::kPerceived);
  EXPECT_EQ(classifyOrientation(facing(-175), 175 * kDeg, tol), OrientationClass::kPerceived);
  EXPECT_EQ(classifyOrientation(facing(-173), 175 * kDeg, tol), OrientationClass::kFalsePositive);
  EXPECT_EQ(classifyOrientation(facing(180), -179 * kDeg, tol), OrientationClass::kPerceived);
  EXPECT_EQ(classifyOrientation(facing(350), -10 * kDeg, tol), OrientationClass::kPerceived);
}

TEST(OrientationClasses, SemiPerceivedIsTheRightAxis) {
  const double tol = 22.5 * kDeg;
  // Facing known but flipped by 180°: the axis is right.
  EXPECT_EQ(classifyOrientation(facing(180 - 22.5), 0, tol), OrientationClass::kSemiPerceived);
  EXPECT_EQ(classifyOrientation(facing(180 - 22.6), 0, tol), OrientationClass::kFalsePositive);
  // Facing unknown: either end of the axis within the tolerance.
  EXPECT_EQ(classifyOrientation(facing(5, false), 0, tol), OrientationClass::kSemiPerceived);
  EXPECT_EQ(classifyOrientation(facing(-170, false), 0, tol), OrientationClass::kSemiPerceived);
  EXPECT_EQ(classifyOrientation(facing(10, false), 350 * kDeg, tol),
            OrientationClass::kSemiPerceived);
  EXPECT_EQ(classifyOrientation(facing(90, false), 0, tol), OrientationClass::kFalsePositive);
  EXPECT_EQ(classifyOrientation(facing(22.6, false), 0, tol), OrientationClass::kFalsePositive);
}

TEST(Matching, GreedyOneToOneTakesTheBestPairFirst) {
  // Truth 0 could take percept 0 or 1; truth 1 only percept 0. The cheapest pair wins.
  const auto m = matchOneToOne(2, 2, {{0, 0, 0.1}, {0, 1, 0.5}, {1, 0, 0.3}});
  EXPECT_EQ(m.truth_to_percept[0], 0);
  EXPECT_EQ(m.truth_to_percept[1], -1);
  EXPECT_EQ(m.percept_to_truth[1], -1);
  const auto n = matchOneToOne(1, 3, {{0, 2, 0.2}, {0, 1, 0.2}});
  EXPECT_EQ(n.truth_to_percept[0], 1);  // tie: lower percept index
}

TEST(Matching, BallCentreWithinAFractionOfTheRadius) {
  ScoringParams p;
  p.ball_match_radius_fraction = 0.5;
  p.ball_match_min_px = 2;
  BallInImage b;
  b.in_view = true;
  b.centre_px = {100, 100};
  b.radius_px = 10;
  EXPECT_TRUE(ballMatchCost(b, {105, 100}, p));
  EXPECT_FALSE(ballMatchCost(b, {105.01, 100}, p));
  b.radius_px = 2;  // the minimum in pixels takes over
  EXPECT_TRUE(ballMatchCost(b, {102, 100}, p));
  EXPECT_FALSE(ballMatchCost(b, {102.1, 100}, p));
}

TEST(Matching, RobotByIouOrByFeet) {
  ScoringParams p;
  p.robot_match_min_iou = 0.5;
  p.robot_match_max_feet_distance_m = 0.3;
  RobotInImage r;
  r.in_view = true;
  r.box = {0, 0, 10, 20};
  r.position_in_field = {2, 0};
  EXPECT_TRUE(robotMatchCost(r, {0, 0, 10, 20}, std::nullopt, p));
  EXPECT_FALSE(robotMatchCost(r, {5, 0, 15, 20}, std::nullopt, p));  // IoU 1/3
  EXPECT_TRUE(robotMatchCost(r, {5, 0, 15, 20}, Eigen::Vector2d(2.25, 0.1), p));
  EXPECT_FALSE(robotMatchCost(r, {5, 0, 15, 20}, Eigen::Vector2d(2.4, 0), p));
  // A box match beats a feet match.
  EXPECT_LT(*robotMatchCost(r, {0, 0, 10, 19}, std::nullopt, p),
            *robotMatchCost(r, {5, 0, 15, 20}, Eigen::Vector2d(2.0, 0), p));
}

FrameTruth ballFrame(bool should_detect = true) {
  FrameTruth t;
  t.ball_present = true;
  t.ball.in_view = true;
  t.ball.should_detect = should_detect;
  t.ball.centre_px = {100, 100};
  t.ball.radius_px = 8;
  t.ball.distance_m = 1.2;
  t.ball.position_in_field = {1.2, 0};
  t.ball.visible_fraction = 1;
  return t;
}

BallProposal proposal(double x, double y) { return {{x, y}, 8, 1}; }
BallPercept ballAt(double x, double y) {
  BallPercept b;
  b.centre_px = {x, y};
  b.radius_px = 8;
  b.confidence = 0.9;
  return b;
}

TEST(Scorer, AbsentStagesStayAbsent) {
  Scorer s(ScoringParams{}, FieldDimensions{});
  s.addFrame(ballFrame(), FramePercepts{}, nullptr);
  const json r = s.results({"x", 1, "v"});
  for (const char* k : {"detection_rate", "proposal_recall", "proposals_per_frame",
                        "false_positives_per_frame", "precision"}) {
    EXPECT_TRUE(r["ball"][k].is_null()) << k;
    EXPECT_TRUE(r["robot"][k].is_null()) << k;
  }
  for (const char* k : {"perceived", "semi_perceived", "not_perceived", "false_positive"}) {
    EXPECT_TRUE(r["orientation"][k].is_null()) << k;
  }
  EXPECT_TRUE(r["field_features"]["pose_error_mm"].is_null());
  EXPECT_TRUE(r["field_features"]["line_detection_rate"].is_null());
  for (const auto& stage : paperStageNames()) {
    EXPECT_TRUE(r["timing_ms"][stage]["mean"].is_null());
    EXPECT_TRUE(r["timing_ms"][stage]["max"].is_null());
  }
  EXPECT_TRUE(r["cnn"]["BallNet"]["accuracy"].is_null());
  EXPECT_EQ(r["frame_count"], 1);
  // What should have been detected is counted even without a detector.
  EXPECT_EQ(r["ball"]["counts"]["should_detect"], 1);
  EXPECT_EQ(r["ball"]["counts"]["truths"], 0);
}

TEST(Scorer, BallMetricsOnHandMadeFrames) {
  Scorer s(ScoringParams{}, FieldDimensions{});
  // Frame 1: three proposals (one on the ball), two detections (one hit, one false).
  FramePercepts a;
  a.ball_proposals = {proposal(101, 100), proposal(200, 50), proposal(20, 20)};
  a.balls = {ballAt(101, 101), ballAt(200, 50)};
  a.balls->at(0).position_in_robot = Eigen::Vector2d(1.3, 0);  // observer at the origin: 0.1 m off
  s.addFrame(ballFrame(), a, nullptr);
  // Frame 2: one far proposal, no detection: a miss.
  FramePercepts b;
  b.ball_proposals = {proposal(140, 100)};
  b.balls = std::vector<BallPercept>{};
  s.addFrame(ballFrame(), b, nullptr);
  // Frame 3: a detection of a ball that need not be detected is neither hit nor false.
  FramePercepts c;
  c.ball_proposals = std::vector<BallProposal>{};
  c.balls = {ballAt(100, 100)};
  s.addFrame(ballFrame(false), c, nullptr);
  const json r = s.results({});
  EXPECT_DOUBLE_EQ(r["ball"]["proposals_per_frame"], 4.0 / 3);
  EXPECT_DOUBLE_EQ(r["ball"]["proposal_recall"], 0.5);
  EXPECT_DOUBLE_EQ(r["ball"]["detection_rate"], 0.5);
  EXPECT_DOUBLE_EQ(r["ball"]["false_positives_per_frame"], 1.0 / 3);
  EXPECT_DOUBLE_EQ(r["ball"]["precision"], 0.5);
  EXPECT_NEAR(r["ball"]["position_error_m"].get<double>(), 0.1, 1e-12);
  EXPECT_EQ(r["ball"]["counts"]["truths"], 2);
}

TEST(Scorer, PositionErrorUsesTheObserverPose) {
  Scorer s(ScoringParams{}, FieldDimensions{});
  FrameTruth t = ballFrame();
  t.observer = {1.0, 2.0, kPi / 2};       // facing +y
  t.ball.position_in_field = {1.0, 3.5};  // 1.5 m ahead of the observer
  FramePercepts p;
  p.balls = {ballAt(100, 100)};
  p.balls->at(0).position_in_robot = Eigen::Vector2d(1.5, -0.2);  // 0.2 m to its right
  s.addFrame(t, p, nullptr);
  EXPECT_NEAR(s.results({})["ball"]["position_error_m"].get<double>(), 0.2, 1e-12);
}

RobotInImage robotTruth(int index, double heading_observer_deg, double rel_deg) {
  RobotInImage r;
  r.index = index;
  r.in_view = true;
  r.should_detect = true;
  r.box = {100.0 + 60 * index, 50, 140.0 + 60 * index, 130};
  r.position_in_field = {2, 0.5 * index};
  r.distance_m = 2;
  r.visible_fraction = 1;
  r.heading_in_observer_rad = heading_observer_deg * kDeg;
  r.heading_rel_rad = rel_deg * kDeg;
  return r;
}

RobotPercept robotAt(const PixelBox& b, std::optional<RobotOrientation> raw,
                     std::optional<RobotOrientation> filtered) {
  RobotPercept p;
  p.box = b;
  p.confidence = 0.8;
  p.orientation_raw = raw;
  p.orientation_filtered = filtered;
  return p;
}

TEST(Scorer, RobotAndOrientationMetricsOnHandMadeFrames) {
  ScoringParams params;
  params.orientation_tolerance_deg = 22.5;
  params.orientation_heading_bin_deg = 45;
  Scorer s(params, FieldDimensions{});
  FrameTruth t;
  t.robots = {robotTruth(0, 180, 0), robotTruth(1, 90, 90), robotTruth(2, 0, 180)};
  FramePercepts p;
  p.robot_proposals = {RobotProposal{t.robots[0].box, {}}, RobotProposal{t.robots[1].box, {}},
                       RobotProposal{{300, 0, 310, 10}, {}}};
  p.orientation_stage = true;
  // Robot 0: perceived raw, perceived filtered. Robot 1: raw flipped (semi), filtered perceived.
  // Robot 2: not detected (not perceived). One false robot.
  p.robots = {robotAt(t.robots[0].box, facing(-175), facing(180)),
              robotAt(t.robots[1].box, facing(-90), facing(80)),
              robotAt({0, 200, 20, 230}, std::nullopt, std::nullopt)};
  s.addFrame(t, p, nullptr);
  const json r = s.results({});
  EXPECT_DOUBLE_EQ(r["robot"]["proposals_per_frame"], 3);
  EXPECT_DOUBLE_EQ(r["robot"]["proposal_recall"], 2.0 / 3);
  EXPECT_DOUBLE_EQ(r["robot"]["detection_rate"], 2.0 / 3);
  EXPECT_DOUBLE_EQ(r["robot"]["false_positives_per_frame"], 1);
  EXPECT_DOUBLE_EQ(r["robot"]["precision"], 2.0 / 3);
  EXPECT_DOUBLE_EQ(r["orientation"]["perceived"], 1.0 / 3);
  EXPECT_DOUBLE_EQ(r["orientation"]["semi_perceived"], 1.0 / 3);
  EXPECT_DOUBLE_EQ(r["orientation"]["not_perceived"], 1.0 / 3);
  EXPECT_DOUBLE_EQ(r["orientation"]["false_positive"], 0);
  EXPECT_DOUBLE_EQ(r["orientation"]["filtered"]["perceived"], 2.0 / 3);
  // Per true heading (relative to the line of sight): bins 0, 90 and 180 degrees.
  const auto& per = r["orientation"]["per_heading"];
  ASSERT_EQ(per.size(), 3u);
  EXPECT_DOUBLE_EQ(per[0]["heading_deg"], 0);
  EXPECT_DOUBLE_EQ(per[0]["raw"]["perceived"], 1);
  EXPECT_DOUBLE_EQ(per[1]["heading_deg"], 90);
  EXPECT_DOUBLE_EQ(per[1]["raw"]["semi_perceived"], 1);
  EXPECT_DOUBLE_EQ(per[1]["filtered"]["perceived"], 1);
  EXPECT_DOUBLE_EQ(per[2]["heading_deg"], 180);
  EXPECT_DOUBLE_EQ(per[2]["raw"]["not_perceived"], 1);
}

TEST(Scorer, DetectionRateAgainstTheVisibleFraction) {
  ScoringParams params;
  params.visibility_bin_fraction = 0.25;
  Scorer s(params, FieldDimensions{});
  // Robots 0.55 (missed), 0.6 (found), 0.8 (missed) and 1.0 (found) visible; one not demanded.
  FrameTruth t;
  t.robots = {robotTruth(0, 0, 0), robotTruth(1, 0, 0), robotTruth(2, 0, 0), robotTruth(3, 0, 0),
              robotTruth(4, 0, 0)};
  t.robots[0].visible_fraction = 0.55;
  t.robots[1].visible_fraction = 0.6;
  t.robots[2].visible_fraction = 0.8;
  t.robots[3].visible_fraction = 1.0;
  t.robots[4].visible_fraction = 0.2;
  t.robots[4].should_detect = false;
  FramePercepts p;
  p.robots = {robotAt(t.robots[1].box, std::nullopt, std::nullopt),
              robotAt(t.robots[3].box, std::nullopt, std::nullopt)};
  s.addFrame(t, p, nullptr);
  const json r = s.results({});
  // Bins [0.5, 0.75) and [0.75, 1]: a whole robot counts in the last bin, not in one of its own.
  const json& bins = r["by_visibility"]["robot"];
  ASSERT_EQ(bins.size(), 2u) << bins;
  EXPECT_DOUBLE_EQ(bins[0]["from_fraction"], 0.5);
  EXPECT_DOUBLE_EQ(bins[0]["to_fraction"], 0.75);
  EXPECT_EQ(bins[0]["truths"], 2);
  EXPECT_DOUBLE_EQ(bins[0]["detection_rate"], 0.5);
  EXPECT_DOUBLE_EQ(bins[1]["from_fraction"], 0.75);
  EXPECT_DOUBLE_EQ(bins[1]["to_fraction"], 1.0);
  EXPECT_EQ(bins[1]["truths"], 2);
  EXPECT_DOUBLE_EQ(bins[1]["detection_rate"], 0.5);
  EXPECT_TRUE(r["by_visibility"]["ball"].empty());
  EXPECT_DOUBLE_EQ(r["scoring"]["visibility_bin_fraction"], 0.25);
}

TEST(Scorer, HeadingBinsWrapAt360) {
  ScoringParams params;
  params.orientation_heading_bin_deg = 22.5;
  Scorer s(params, FieldDimensions{});
  FrameTruth t;
  t.robots = {robotTruth(0, 0, -5)};  // 355° to the line of sight: the 0° bin
  FramePercepts p;
  p.orientation_stage = true;
  p.robots = {robotAt(t.robots[0].box, facing(3), facing(3))};
  s.addFrame(t, p, nullptr);
  const json r = s.results({});
  const auto& per = r["orientation"]["per_heading"];
  ASSERT_EQ(per.size(), 1u);
  EXPECT_DOUBLE_EQ(per[0]["heading_deg"], 0);
}

TEST(Scorer, FieldFeaturesPoseTimingAndClassifiers) {
  Scorer s(ScoringParams{}, FieldDimensions{});
  FrameTruth t = ballFrame();
  t.field.lines = {LineInImage{"a", false, {0, 100}, {300, 100}, 300},
                   LineInImage{"b", false, {150, 0}, {150, 240}, 240}};
  t.field.intersections = {{IntersectionType::kX, {150, 100}, {}},
                           {IntersectionType::kL, {10, 10}, {}}};
  FramePercepts p;
  FieldFeatures ff;
  LinePercept on_a;
  on_a.start_px = {20, 102};
  on_a.end_px = {120, 99};
  LinePercept stray;
  stray.start_px = {20, 200};
  stray.end_px = {100, 150};
  ff.lines = {on_a, stray};
  IntersectionPercept x;
  x.type = IntersectionType::kX;
  x.position_px = {153, 104};
  IntersectionPercept wrong_type;
  wrong_type.type = IntersectionType::kT;
  wrong_type.position_px = {10, 10};
  ff.intersections = {x, wrong_type};
  p.field_features = ff;
  p.pose_fit_stage = true;
  p.pose_in_field = FieldPose{0.03, 0, 0};  // 30 mm off
  p.stage_times_ms = {{"high_contrast", 1.0}, {"field_features", 2.0}};
  p.classifier_samples = {{"BallNet", ClassifierSample::Object::kBall, {100, 101}, {}, {}, true},
                          {"BallNet", ClassifierSample::Object::kBall, {30, 30}, {}, {}, true},
                          {"BallNet", ClassifierSample::Object::kBall, {60, 30}, {}, {}, false}};
  s.addFrame(t, p, nullptr);
  FramePercepts q = p;
  q.pose_in_field = FieldPose{0, -0.04, 0};  // 40 mm off
  q.stage_times_ms = {{"high_contrast", 3.0}};
  q.classifier_samples.clear();
  s.addFrame(t, q, nullptr);
  FramePercepts u = q;
  u.pose_in_field.reset();  // the fit found nothing
  u.stage_times_ms.clear();
  s.addFrame(t, u, nullptr);
  const json r = s.results({});
  EXPECT_DOUBLE_EQ(r["field_features"]["line_detection_rate"], 0.5);
  EXPECT_DOUBLE_EQ(r["field_features"]["false_lines_per_frame"], 1);
  EXPECT_DOUBLE_EQ(r["field_features"]["intersection_detection_rate"], 0.5);
  EXPECT_DOUBLE_EQ(r["field_features"]["false_intersections_per_frame"], 1);
  EXPECT_NEAR(r["field_features"]["pose_error_mm"].get<double>(), 35, 1e-9);
  EXPECT_NEAR(r["field_features"]["pose_error_rms_mm"].get<double>(),
              std::sqrt((900.0 + 1600.0) / 2), 1e-9);
  EXPECT_NEAR(r["field_features"]["pose_fit_rate"].get<double>(), 2.0 / 3, 1e-12);
  EXPECT_DOUBLE_EQ(r["timing_ms"]["high_contrast"]["mean"], 2);
  EXPECT_DOUBLE_EQ(r["timing_ms"]["high_contrast"]["max"], 3);
  EXPECT_DOUBLE_EQ(r["timing_ms"]["field_features"]["mean"], 2);
  EXPECT_TRUE(r["timing_ms"]["ball_detector"]["mean"].is_null());
  EXPECT_NEAR(r["cnn"]["BallNet"]["accuracy"].get<double>(), 2.0 / 3, 1e-12);
  EXPECT_EQ(r["cnn"]["BallNet"]["samples"], 3);
  EXPECT_TRUE(r["cnn"]["RobotNet"]["accuracy"].is_null());
}

// A classifier sample on an object too hidden to demand is neither right nor wrong: it is left
// out of the accuracy and counted as ambiguous (the training loop leaves such samples out too).
TEST(Scorer, ClassifierSamplesOnUndemandedObjectsAreLeftOut) {
  Scorer s(ScoringParams{}, FieldDimensions{});
  FrameTruth hidden = ballFrame(/*should_detect=*/false);
  RobotInImage seen = robotTruth(0, 0, 0), cut = robotTruth(1, 0, 0);
  cut.should_detect = false;
  cut.visible_fraction = 0.2;
  hidden.robots = {seen, cut};
  FramePercepts p;
  p.classifier_samples = {
      {"BallNet", ClassifierSample::Object::kBall, {100, 101}, {}, {}, false},  // hidden ball: left out
      {"BallNet", ClassifierSample::Object::kBall, {30, 30}, {}, {}, false},    // carpet, right
      {"RobotNet", ClassifierSample::Object::kRobot, {}, seen.box, {}, false},  // demanded: wrong
      {"RobotNet", ClassifierSample::Object::kRobot, {}, cut.box, {}, false},   // hidden: left out
      {"RobotNet", ClassifierSample::Object::kRobot, {}, {400, 50, 440, 130}, {}, false}};  // right
  s.addFrame(hidden, p, nullptr);
  FramePercepts q;
  q.classifier_samples = {p.classifier_samples[0]};
  s.addFrame(ballFrame(/*should_detect=*/true), q, nullptr);  // on a demanded ball: a false negative
  const json r = s.results({});
  EXPECT_EQ(r["cnn"]["BallNet"]["samples"], 2);
  EXPECT_EQ(r["cnn"]["BallNet"]["ambiguous"], 1);
  EXPECT_EQ(r["cnn"]["BallNet"]["false_negatives"], 1);
  EXPECT_DOUBLE_EQ(r["cnn"]["BallNet"]["accuracy"], 0.5);
  EXPECT_EQ(r["cnn"]["RobotNet"]["samples"], 2);
  EXPECT_EQ(r["cnn"]["RobotNet"]["ambiguous"], 1);
  EXPECT_EQ(r["cnn"]["RobotNet"]["false_negatives"], 1);
  EXPECT_DOUBLE_EQ(r["cnn"]["RobotNet"]["accuracy"], 0.5);
}

TEST(Scorer, EveryMetricPerCase) {
  Scorer s(ScoringParams{}, FieldDimensions{});
  FramePercepts hit;
  hit.balls = {ballAt(100, 100)};
  FramePercepts miss;
  miss.balls = std::vector<BallPercept>{};
  s.beginCase({"dim", {{"light_scale", 0.3}}, {}});
  s.addFrame(ballFrame(), miss, nullptr);
  s.addFrame(ballFrame(), hit, nullptr);
  s.beginCase({"bright", {{"light_scale", 1.0}}, {}});
  s.addFrame(ballFrame(), hit, nullptr);
  const json r = s.results({"sweep", 7, "v1"});
  ASSERT_EQ(r["cases"].size(), 2u);
  EXPECT_EQ(r["cases"][0]["name"], "dim");
  EXPECT_DOUBLE_EQ(r["cases"][0]["settings"]["light_scale"], 0.3);
  EXPECT_DOUBLE_EQ(r["cases"][0]["ball"]["detection_rate"], 0.5);
  EXPECT_DOUBLE_EQ(r["cases"][1]["ball"]["detection_rate"], 1.0);
  EXPECT_DOUBLE_EQ(r["ball"]["detection_rate"], 2.0 / 3);
  EXPECT_EQ(r["scenario"], "sweep");
  EXPECT_EQ(r["seed"], 7);
  EXPECT_EQ(r["code_version"], "v1");
  EXPECT_EQ(r["frame_count"], 3);
  // The per-case objects carry the same metric keys as the total.
  EXPECT_TRUE(r["cases"][0]["timing_ms"].contains("ball_detector"));
  EXPECT_TRUE(r["cases"][0]["orientation"].contains("perceived"));
}

TEST(Scorer, GalleryKeepsTheWorstCropsWithinTheLimit) {
  ScoringParams params;
  params.gallery_max_crops = 2;
  params.gallery_worst_frames = 1;
  Scorer s(params, FieldDimensions{});
  GrayImage image(320, 240, 90);
  for (int i = 0; i < 4; ++i) {
    FrameTruth t = ballFrame();
    t.frame_index = i;
    t.ball.visible_fraction = 0.6 + 0.1 * i;
    FramePercepts p;
    p.balls = std::vector<BallPercept>{};
    s.addFrame(t, p, nullptr, &image);
  }
  int missed = 0, worst = 0;
  for (const auto& g : s.gallery()) {
    EXPECT_FALSE(g.png_base64.empty());
    if (g.kind == "missed_ball") {
      ++missed;
      EXPECT_GE(g.frame, 2);  // the two most visible misses
    }
    worst += g.kind == "worst_frame";
  }
  EXPECT_EQ(missed, 2);
  EXPECT_EQ(worst, 1);
}

}  // namespace
}  // namespace colorfree
