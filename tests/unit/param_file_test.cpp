#include "colorfree/perception/param_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "colorfree/perception/field_dimensions.h"

namespace colorfree {
namespace {

std::string writeTemp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + "/" + name;
  std::ofstream(path) << text;
  return path;
}

TEST(ParamFile, UnknownKeyIsAnErrorNamingFileAndKey) {
  const std::string path = writeTemp("params_unknown.yaml", "a_m: 1.0\nb_px: 2\n");
  ParamFile f(path);
  EXPECT_EQ(f.get<double>("a_m"), 1.0);
  try {
    f.finish();
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("b_px"), std::string::npos);
  }
}

TEST(ParamFile, OutOfRangeAndWrongType) {
  const std::string path = writeTemp("params_range.yaml", "a_m: .nan\nb_m: 5\nc: hello\n");
  ParamFile f(path);
  EXPECT_THROW(f.getInRange("a_m", 0, 10), Error);
  EXPECT_THROW(f.getInRange("b_m", 0, 1), Error);
  EXPECT_THROW(f.get<double>("c"), Error);
  EXPECT_THROW(f.get<double>("missing"), Error);
}

TEST(ParamFile, MalformedYamlNamesTheLine) {
  const std::string path = writeTemp("params_broken.yaml", "a: 1\nb: [1, 2\n");
  try {
    ParamFile f(path);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("line"), std::string::npos);
  }
}

TEST(FieldDimensions, ShippedFileEqualsDefaults) {
  const FieldDimensions shipped = FieldDimensions::loadDefault();
  const FieldDimensions defaults;
  EXPECT_EQ(shipped.field_length_m, defaults.field_length_m);
  EXPECT_EQ(shipped.field_width_m, defaults.field_width_m);
  EXPECT_EQ(shipped.line_width_m, defaults.line_width_m);
  EXPECT_EQ(shipped.border_strip_m, defaults.border_strip_m);
  EXPECT_EQ(shipped.centre_circle_diameter_m, defaults.centre_circle_diameter_m);
  EXPECT_EQ(shipped.penalty_area_length_m, defaults.penalty_area_length_m);
  EXPECT_EQ(shipped.penalty_area_width_m, defaults.penalty_area_width_m);
  EXPECT_EQ(shipped.goal_area_length_m, defaults.goal_area_length_m);
  EXPECT_EQ(shipped.goal_area_width_m, defaults.goal_area_width_m);
  EXPECT_EQ(shipped.penalty_mark_distance_m, defaults.penalty_mark_distance_m);
  EXPECT_EQ(shipped.penalty_mark_size_m, defaults.penalty_mark_size_m);
  EXPECT_EQ(shipped.goal_inner_width_m, defaults.goal_inner_width_m);
  EXPECT_EQ(shipped.goal_depth_m, defaults.goal_depth_m);
  EXPECT_EQ(shipped.goal_height_m, defaults.goal_height_m);
  EXPECT_EQ(shipped.goal_post_diameter_m, defaults.goal_post_diameter_m);
  EXPECT_EQ(shipped.ball_diameter_m, defaults.ball_diameter_m);
  EXPECT_EQ(shipped.robot_height_m, defaults.robot_height_m);
  EXPECT_EQ(shipped.robot_width_m, defaults.robot_width_m);
}

}  // namespace
}  // namespace colorfree
