#include "colorfree/groundtruth/results.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "colorfree/groundtruth/report.h"
#include "colorfree/groundtruth/scorer.h"
#include "colorfree/groundtruth/scoring_params.h"
#include "test_support.h"

namespace colorfree {
namespace {

using json = nlohmann::json;

TEST(ScoringParams, DefaultsEqualTheShippedFile) {
  const ScoringParams file = ScoringParams::loadDefault();
  const ScoringParams code;
  const RunInfo run;
  // Compare through the JSON the report prints, which lists every parameter.
  EXPECT_EQ(Scorer(file, {}).results(run)["scoring"], Scorer(code, {}).results(run)["scoring"]);
  EXPECT_EQ(file.gallery_max_crops, code.gallery_max_crops);
  EXPECT_EQ(file.gallery_worst_frames, code.gallery_worst_frames);
}

TEST(ScoringParams, UnknownKeyIsAnError) {
  const std::string path = ::testing::TempDir() + "/scoring_bad.yaml";
  std::ifstream in(ScoringParams::defaultPath());
  std::ofstream(path) << in.rdbuf() << "ball_min_radius_pix: 3\n";
  try {
    ScoringParams::load(path);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("ball_min_radius_pix"), std::string::npos);
  }
}

TEST(Expectations, ParseAndCheck) {
  const auto e = parseExpectation("ball.detection_rate >= 0.97", "s.yaml");
  EXPECT_EQ(e.metric, "ball.detection_rate");
  EXPECT_EQ(e.op, ">=");
  EXPECT_DOUBLE_EQ(e.bound, 0.97);
  EXPECT_THROW(parseExpectation("ball.detection_rate about 0.97", "s.yaml"), Error);
  EXPECT_THROW(parseExpectation(">= 0.97", "s.yaml"), Error);
  const json r = {{"ball", {{"detection_rate", 0.95}}},
                  {"field_features", {{"pose_error_mm", nullptr}}}};
  auto f = checkExpectations({e}, r);
  ASSERT_EQ(f.size(), 1u);
  const std::string msg = f[0].message("game");
  EXPECT_NE(msg.find("game"), std::string::npos);
  EXPECT_NE(msg.find("ball.detection_rate"), std::string::npos);
  EXPECT_NE(msg.find("0.95"), std::string::npos);
  EXPECT_NE(msg.find(">= 0.97"), std::string::npos);
  EXPECT_TRUE(checkExpectations({parseExpectation("ball.detection_rate > 0.9", "s")}, r).empty());
  EXPECT_TRUE(checkExpectations({parseExpectation("ball.detection_rate <= 0.95", "s")}, r).empty());
  EXPECT_EQ(checkExpectations({parseExpectation("ball.detection_rate < 0.95", "s")}, r).size(), 1u);
  // An absent metric never meets an expectation.
  f = checkExpectations({parseExpectation("field_features.pose_error_mm <= 40", "s")}, r);
  ASSERT_EQ(f.size(), 1u);
  EXPECT_NE(f[0].message("game").find("absent"), std::string::npos);
}

TEST(Expectations, UnknownMetricIsAnErrorBeforeRunning) {
  const auto& known = knownMetricNames();
  for (const char* k :
       {"ball.detection_rate", "ball.proposal_recall", "ball.proposals_per_frame",
        "ball.false_positives_per_frame", "robot.detection_rate", "robot.proposal_recall",
        "robot.proposals_per_frame", "robot.false_positives_per_frame", "orientation.perceived",
        "orientation.semi_perceived", "orientation.not_perceived", "orientation.false_positive",
        "field_features.pose_error_mm", "timing_ms.ball_detector.mean",
        "timing_ms.high_contrast.max"}) {
    EXPECT_TRUE(known.count(k)) << k;
  }
  EXPECT_NO_THROW(
      validateExpectations({parseExpectation("robot.detection_rate >= 0.9", "s")}, "s.yaml"));
  try {
    validateExpectations({parseExpectation("ball.detecton_rate >= 0.9", "s")}, "scenes/x.yaml");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("ball.detecton_rate"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("scenes/x.yaml"), std::string::npos);
  }
}

TEST(Results, AtomicWriteLeavesNoPartialFile) {
  const std::string dir = ::testing::TempDir() + "/atomic";
  std::filesystem::create_directories(dir);
  const std::string path = dir + "/results.json";
  writeFileAtomic(path, "{\"a\": 1}\n");
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  EXPECT_EQ(text, "{\"a\": 1}\n");
  EXPECT_FALSE(std::filesystem::exists(path + ".partial"));
  EXPECT_THROW(writeFileAtomic(dir + "/no/such/dir/results.json", "x"), Error);
}

TEST(Report, SaysAbsentAndShowsThePapersNumbers) {
  Scorer s(ScoringParams{}, FieldDimensions{});
  FrameTruth t;
  FramePercepts p;
  p.balls = std::vector<BallPercept>{};
  s.addFrame(t, p, nullptr);
  const std::string html = renderReportHtml(s.results({"demo", 3, "v"}), s.gallery(),
                                            {{"ball.detection_rate >= 0.97", false, "n/a"}});
  EXPECT_NE(html.find("absent"), std::string::npos);
  EXPECT_NE(html.find("0.949"), std::string::npos);  // robot detection, paper
  EXPECT_NE(html.find("40.07"), std::string::npos);  // pose error, paper
  EXPECT_NE(html.find("6.959"), std::string::npos);  // ball detector max ms, paper
  EXPECT_NE(html.find("NOT MET"), std::string::npos);
  // Self-contained: nothing fetched from elsewhere.
  EXPECT_EQ(html.find("src='http"), std::string::npos);
  EXPECT_EQ(html.find("<script src"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
}

}  // namespace
}  // namespace colorfree

namespace colorfree {
namespace {

TEST(Report, ChartsAndGalleryFromHandMadeFrames) {
  ScoringParams params;
  params.orientation_heading_bin_deg = 90;
  Scorer s(params, FieldDimensions{});
  GrayImage image(320, 240, 70);
  for (int y = 90; y < 110; ++y)
    for (int x = 90; x < 110; ++x) image.at(x, y) = 230;
  for (double light : {0.3, 1.0}) {
    s.beginCase({light < 0.5 ? "dim" : "bright", {{"lighting.scale", light}}, {}});
    for (int i = 0; i < 4; ++i) {
      FrameTruth t;
      t.frame_index = i;
      t.ball_present = true;
      t.ball.in_view = t.ball.should_detect = true;
      t.ball.centre_px = {100, 100};
      t.ball.radius_px = 10;
      t.ball.visible_fraction = 1;
      RobotInImage r;
      r.in_view = r.should_detect = true;
      r.box = {200, 40, 240, 120};
      r.heading_rel_rad = (i % 4) * 3.14159265358979 / 2;
      r.heading_in_observer_rad = r.heading_rel_rad;
      t.robots = {r};
      FramePercepts p;
      p.ball_proposals = {BallProposal{{100, 100}, 10, 1}};
      p.balls = std::vector<BallPercept>{};
      if (light > 0.5 || i == 0) p.balls->push_back(BallPercept{{101, 100}, 10, 0.9, {}});
      if (i == 3) p.balls->push_back(BallPercept{{40, 200}, 8, 0.7, {}});
      p.robots = {RobotPercept{}};
      p.robots->at(0).box = r.box;
      p.robots->at(0).orientation_raw =
          RobotOrientation{r.heading_in_observer_rad + (i == 1 ? 1.0 : 0.0), true};
      p.orientation_stage = true;
      s.addFrame(t, p, nullptr, &image);
    }
  }
  const std::string html = renderReportHtml(s.results({"demo", 1, "v"}), s.gallery(), {});
  EXPECT_NE(html.find("data:image/png;base64,"), std::string::npos);
  EXPECT_NE(html.find("Detection rate against lighting.scale"), std::string::npos);
  EXPECT_NE(html.find("Orientation classes per true heading, raw"), std::string::npos);
  EXPECT_NE(html.find("Missed balls"), std::string::npos);
  EXPECT_NE(html.find("False balls"), std::string::npos);
  EXPECT_NE(html.find("Orientation false positives"), std::string::npos);
  std::ofstream(::testing::TempDir() + "/report_demo.html") << html;
}

}  // namespace
}  // namespace colorfree
