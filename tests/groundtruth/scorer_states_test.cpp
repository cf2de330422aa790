// Scorer case states: a run split by case (bench workers, shards) merges into the same results.
#include <gtest/gtest.h>

#include <cmath>

#include "colorfree/groundtruth/scorer.h"
#include "colorfree/perception/error.h"

namespace colorfree {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180;
using json = nlohmann::json;

FrameTruth frameWithEverything(int k) {
  FrameTruth t;
  t.ball_present = true;
  t.ball.in_view = true;
  t.ball.should_detect = true;
  t.ball.centre_px = {100, 100};
  t.ball.radius_px = 8;
  t.ball.distance_m = 1.2 + 0.7 * k;
  t.ball.position_in_field = {1.2, 0};
  t.ball.visible_fraction = 1;
  RobotInImage r;
  r.in_view = true;
  r.should_detect = true;
  r.box = {200, 50, 240, 130};
  r.position_in_field = {2, 0.5};
  r.distance_m = 2;
  r.visible_fraction = 1;
  r.heading_rel_rad = 45.0 * k * kDeg;
  t.robots = {r};
  t.field.lines = {LineInImage{"a", false, {0, 100}, {300, 100}, 300}};
  t.field.intersections = {{IntersectionType::kX, {150, 100}, {}}};
  return t;
}

FramePercepts perceptsFor(int k) {
  FramePercepts p;
  p.ball_proposals = {BallProposal{{101, 100}, 8, 1}, BallProposal{{20.0 + k, 20}, 8, 1}};
  BallPercept b;
  b.centre_px = {101.0 + k, 100};
  b.radius_px = 8;
  b.confidence = 0.9;
  b.position_in_robot = Eigen::Vector2d(1.3 + 0.01 * k, 0.02);
  p.balls = {b};
  p.robot_proposals = {RobotProposal{{200, 50, 240, 130}, {}}};
  RobotPercept r;
  r.box = k % 2 ? PixelBox{200, 50, 240, 130} : PixelBox{0, 0, 10, 10};
  r.confidence = 0.8;
  r.orientation_raw = RobotOrientation{(45.0 * k + 3) * kDeg, true};
  r.orientation_filtered = RobotOrientation{(45.0 * k + 180) * kDeg, true};
  p.robots = {r};
  p.orientation_stage = true;
  FieldFeatures ff;
  LinePercept line;
  line.start_px = {20, 102};
  line.end_px = {120, 99};
  ff.lines = {line};
  IntersectionPercept x;
  x.type = IntersectionType::kX;
  x.position_px = {153.0 + k, 104};
  ff.intersections = {x};
  p.field_features = ff;
  p.pose_fit_stage = true;
  p.pose_in_field = FieldPose{0.013 * k, -0.007, 0.001};
  p.stage_times_ms = {{"high_contrast", 1.1 + 0.3 * k}, {"field_features", 2.7 / (k + 1)}};
  p.classifier_samples = {{"BallNet", ClassifierSample::Object::kBall, {100, 101}, {}, {}, k % 2 == 0}};
  return p;
}

// Scores case `c` (three frames) into `s`.
void scoreCase(Scorer& s, int c) {
  s.beginCase({"case_" + std::to_string(c), {{"lighting.scale", 0.5 * (c + 1)}}, {{"camera", c ? "top" : "bottom"}}});
  for (int f = 0; f < 3; ++f) s.addFrame(frameWithEverything(c + f), perceptsFor(3 * c + f), nullptr);
}

ScoringParams params() {
  ScoringParams p;
  p.orientation_heading_bin_deg = 45;
  return p;
}

// Equal JSON, doubles within a relative 1e-12 (a total summed per frame vs per case).
void expectNear(const json& a, const json& b, const std::string& path = "") {
  if (a.is_number_float() || b.is_number_float()) {
    ASSERT_TRUE(a.is_number() && b.is_number()) << path;
    EXPECT_NEAR(a.get<double>(), b.get<double>(), 1e-12 * std::max(1.0, std::abs(a.get<double>()))) << path;
    return;
  }
  ASSERT_EQ(a.type(), b.type()) << path;
  if (a.is_object()) {
    ASSERT_EQ(a.size(), b.size()) << path;
    for (auto it = a.begin(); it != a.end(); ++it) {
      ASSERT_TRUE(b.contains(it.key())) << path << "." << it.key();
      expectNear(it.value(), b.at(it.key()), path + "." + it.key());
    }
  } else if (a.is_array()) {
    ASSERT_EQ(a.size(), b.size()) << path;
    for (std::size_t i = 0; i < a.size(); ++i) expectNear(a[i], b[i], path + "[" + std::to_string(i) + "]");
  } else {
    EXPECT_EQ(a, b) << path;
  }
}

TEST(ScorerStates, RoundTripGivesTheSameResults) {
  Scorer whole(params(), FieldDimensions{});
  scoreCase(whole, 0);
  scoreCase(whole, 1);
  const json expected = whole.results({"s", 1, "v"});
  // Serialised as text and parsed back, as shard files are.
  Scorer merged(params(), FieldDimensions{});
  merged.addCaseStates(json::parse(whole.caseStates().dump()));
  const json got = merged.results({"s", 1, "v"});
  expectNear(expected, got);
  // Per-case results are exact (each case's own tallies).
  EXPECT_EQ(expected["cases"], got["cases"]);
  EXPECT_EQ(merged.frameCount(), 6);
  // The test exercises every section (a tally field the states forgot would show here).
  EXPECT_GT(got["ball"]["counts"]["proposal_hits"].get<long>(), 0);
  EXPECT_GT(got["robot"]["counts"]["detected"].get<long>(), 0);
  EXPECT_GT(got["ball"]["counts"]["should_detect"].get<long>(), 0);
  EXPECT_GT(got["orientation"]["robot_frames"].get<long>(), 0);
  EXPECT_GT(got["orientation"]["per_heading"].size(), 1u);
  EXPECT_TRUE(got["field_features"]["pose_error_mm"].is_number());
  EXPECT_TRUE(got["ball"]["position_error_m"].is_number());
  EXPECT_EQ(got["cnn"]["BallNet"]["samples"], 6);
  EXPECT_TRUE(got["timing_ms"]["high_contrast"]["max"].is_number());
  EXPECT_FALSE(got["by_distance"]["ball"].empty());
  EXPECT_FALSE(got["by_visibility"]["ball"].empty());
  EXPECT_FALSE(got["by_visibility"]["robot"].empty());
}

TEST(ScorerStates, SplitByCaseMergesExactly) {
  Scorer whole(params(), FieldDimensions{});
  scoreCase(whole, 0);
  scoreCase(whole, 1);
  Scorer one(params(), FieldDimensions{}), two(params(), FieldDimensions{});
  scoreCase(one, 0);
  scoreCase(two, 1);
  Scorer a(params(), FieldDimensions{}), b(params(), FieldDimensions{});
  a.addCaseStates(whole.caseStates());
  b.addCaseStates(one.caseStates());
  b.addCaseStates(two.caseStates());
  EXPECT_EQ(a.results({"s", 1, "v"}), b.results({"s", 1, "v"}));
  // Order matters for the case list: the other order is a different run.
  Scorer c(params(), FieldDimensions{});
  c.addCaseStates(two.caseStates());
  c.addCaseStates(one.caseStates());
  EXPECT_NE(a.results({"s", 1, "v"})["cases"], c.results({"s", 1, "v"})["cases"]);
}

TEST(ScorerStates, MalformedStatesAreAnError) {
  Scorer s(params(), FieldDimensions{});
  EXPECT_THROW(s.addCaseStates(json::object()), Error);
  Scorer whole(params(), FieldDimensions{});
  scoreCase(whole, 0);
  json states = whole.caseStates();
  states["cases"][0]["tally"]["ball"].erase("detected");
  EXPECT_THROW(s.addCaseStates(states), Error);
}

}  // namespace
}  // namespace colorfree
