#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/error.h"
#include "colorfree/perception/field_lines.h"
#include "colorfree/perception/high_contrast.h"
#include "colorfree/perception/ignore_regions.h"
#include "colorfree/perception/param_file.h"
#include "colorfree/perception/pipeline.h"
#include "colorfree/perception/pose_fit.h"
#include "colorfree/perception/robot_detector.h"
#include "colorfree/perception/robot_orientation.h"
#include "colorfree/perception/robot_proposer.h"

namespace colorfree {
namespace {

TEST(StageParams, ShippedFilesEqualTheCodeDefaults) {
  EXPECT_EQ(FieldBoundaryParams::loadDefault(), FieldBoundaryParams{});
  EXPECT_EQ(BodyModelParams::loadDefault(), BodyModelParams{});
  EXPECT_EQ(HighContrastParams::loadDefault(), HighContrastParams{});
  EXPECT_EQ(FieldLineParams::loadDefault(), FieldLineParams{});
  EXPECT_EQ(PoseFitParams::loadDefault(), PoseFitParams{});
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string writeTemp(const std::string& name, const std::string& text) {
  const auto path = std::filesystem::temp_directory_path() / ("colorfree_params_" + name);
  std::ofstream(path) << text;
  return path.string();
}

// The file's text with the value of `key` replaced.
std::string withValue(const std::string& text, const std::string& key, const std::string& value) {
  std::istringstream lines(text);
  std::string line, out;
  bool found = false;
  while (std::getline(lines, line)) {
    if (line.rfind(key + ":", 0) == 0) {
      line = key + ": " + value;
      found = true;
    }
    out += line + "\n";
  }
  EXPECT_TRUE(found) << key;
  return out;
}

// Every shipped stage file: an extra key, a missing key and a NaN are errors naming file and key.
class StrictParamFile : public ::testing::TestWithParam<std::string> {};

void loadByName(const std::string& name, const std::string& path) {
  if (name == "field_boundary.yaml") FieldBoundaryParams::load(path);
  else if (name == "body_model.yaml") BodyModelParams::load(path);
  else if (name == "high_contrast.yaml") HighContrastParams::load(path);
  else if (name == "field_lines.yaml") FieldLineParams::load(path);
  else if (name == "pose_fit.yaml") PoseFitParams::load(path);
  else FAIL() << name;
}

TEST_P(StrictParamFile, RejectsUnknownMissingAndNaN) {
  const std::string name = GetParam();
  const std::string text = readFile(defaultParamDir() + "/" + name);
  ASSERT_FALSE(text.empty());
  EXPECT_NO_THROW(loadByName(name, writeTemp(name, text)));

  const std::string extra = writeTemp("extra_" + name, text + "surprise_key: 1\n");
  try {
    loadByName(name, extra);
    ADD_FAILURE() << "unknown key accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("surprise_key"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(extra), std::string::npos) << e.what();
  }

  // Drop the first key line.
  std::istringstream lines(text);
  std::string line, kept, dropped_key;
  while (std::getline(lines, line)) {
    if (dropped_key.empty() && !line.empty() && line[0] != '#') {
      dropped_key = line.substr(0, line.find(':'));
      continue;
    }
    kept += line + "\n";
  }
  const std::string missing = writeTemp("missing_" + name, kept);
  try {
    loadByName(name, missing);
    ADD_FAILURE() << "missing key accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(dropped_key), std::string::npos) << e.what();
  }
  const std::string nan = writeTemp("nan_" + name, kept + dropped_key + ": .nan\n");
  EXPECT_THROW(loadByName(name, nan), Error);
}

INSTANTIATE_TEST_SUITE_P(Shipped, StrictParamFile,
                         ::testing::Values("field_boundary.yaml", "body_model.yaml", "high_contrast.yaml",
                                           "field_lines.yaml", "pose_fit.yaml"));

// Loading `path` throws an Error whose message names the file and `key`; `accepted` says what
// was wrongly accepted when it does not throw.
template <typename Load>
void expectErrorNaming(const Load& load, const std::string& path, const std::string& key,
                       const std::string& accepted) {
  try {
    load(path);
    ADD_FAILURE() << accepted;
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
  }
}

TEST(StageParams, ImpossibleCombinationsAreErrors) {
  const std::string lines = readFile(defaultParamDir() + "/field_lines.yaml");
  EXPECT_THROW(FieldLineParams::load(writeTemp("widths.yaml", withValue(lines, "min_width_factor", "5.0"))), Error);
  const std::string body = readFile(defaultParamDir() + "/body_model.yaml");
  EXPECT_THROW(BodyModelParams::load(writeTemp("body.yaml", withValue(body, "chest_top_m", "0.10"))), Error);
  const std::string detector = readFile(defaultParamDir() + "/robot_detector.yaml");
  const std::string shins = writeTemp("shins.yaml", withValue(detector, "shin_min_height_fraction", "0.5"));
  expectErrorNaming([](const std::string& f) { RobotDetectorParams::load(f); }, shins,
                    "shin_min_height_fraction", "a shin's least height over its greatest accepted");
  const std::string mirror =
      writeTemp("mirror.yaml", withValue(detector, "mirror_min_confidence", "0.9"));
  expectErrorNaming([](const std::string& f) { RobotDetectorParams::load(f); }, mirror,
                    "mirror_min_confidence",
                    "a mirrored look's band with its lower bound above its upper");
  const std::string orientation = readFile(defaultParamDir() + "/robot_orientation.yaml");
  const std::string panel_rows =
      writeTemp("panel_rows.yaml", withValue(orientation, "dark_panel_edge_min_rows", "3"));
  expectErrorNaming([](const std::string& f) { RobotOrientationParams::load(f); }, panel_rows,
                    "dark_panel_edge_min_rows", "a panel edge asking more rows than any other edge");
}

TEST(StageParams, AnEvenSmoothingWidthIsAnError) {
  // The robot proposer's smoothed scan averages a pixel with as many on each side.
  const std::string proposer = readFile(defaultParamDir() + "/robot_proposer.yaml");
  const std::string even = writeTemp("even.yaml", withValue(proposer, "smooth_width_px", "4"));
  expectErrorNaming([](const std::string& f) { RobotProposerParams::load(f); }, even,
                    "smooth_width_px", "an even smoothing width accepted");
  EXPECT_NO_THROW(RobotProposerParams::load(
      writeTemp("odd.yaml", withValue(proposer, "smooth_width_px", "5"))));
}

TEST(CameraFile, DocumentedExampleLoadsAndSeesTheGroundAhead) {
  const CameraModel cam = CameraModel::load(std::string(COLORFREE_SOURCE_DIR) + "/docs/camera_nao_top_example.yaml");
  EXPECT_EQ(cam.width(), 640);
  EXPECT_EQ(cam.height(), 480);
  // The image centre looks at the ground 1 to 2 m ahead; the horizon is in the upper half.
  const auto centre = cam.pixelToGround({320, 240});
  ASSERT_TRUE(centre);
  EXPECT_GT(centre->x(), 1.0);
  EXPECT_LT(centre->x(), 2.0);
  ASSERT_TRUE(cam.horizonY(320));
  EXPECT_LT(*cam.horizonY(320), 240);
}

TEST(CameraFile, DocumentedBottomExampleLoadsAndSeesTheGroundInFrontOfTheFeet) {
  const CameraModel cam = CameraModel::load(std::string(COLORFREE_SOURCE_DIR) + "/docs/camera_nao_bottom_example.yaml");
  // The image centre looks at the ground 0.3 to 0.5 m ahead; the whole image is below the horizon.
  const auto centre = cam.pixelToGround({320, 240});
  ASSERT_TRUE(centre);
  EXPECT_GT(centre->x(), 0.3);
  EXPECT_LT(centre->x(), 0.5);
  EXPECT_TRUE(cam.pixelToGround({320, 0.5}));
  EXPECT_TRUE(cam.pixelToGround({0.5, 0.5}));
}

TEST(StageParams, PipelineConfigLoadsTheShippedDirectory) {
  const PipelineConfig c = PipelineConfig::loadDefault();
  EXPECT_EQ(c.field_lines, FieldLineParams{});
  EXPECT_THROW(PipelineConfig::load("/nonexistent/colorfree"), Error);
}

}  // namespace
}  // namespace colorfree
