#include "colorfree/perception/field_dimensions.h"

#include "colorfree/perception/param_file.h"

namespace colorfree {

FieldDimensions FieldDimensions::load(const std::string& path) {
  ParamFile f(path);
  FieldDimensions d;
  d.field_length_m = f.getInRange("field_length_m", 1.0, 30.0);
  d.field_width_m = f.getInRange("field_width_m", 1.0, 30.0);
  d.line_width_m = f.getInRange("line_width_m", 0.005, 0.5);
  d.border_strip_m = f.getInRange("border_strip_m", 0.0, 5.0);
  d.centre_circle_diameter_m = f.getInRange("centre_circle_diameter_m", 0.1, 10.0);
  d.penalty_area_length_m = f.getInRange("penalty_area_length_m", 0.1, 10.0);
  d.penalty_area_width_m = f.getInRange("penalty_area_width_m", 0.1, 20.0);
  d.goal_area_length_m = f.getInRange("goal_area_length_m", 0.1, 10.0);
  d.goal_area_width_m = f.getInRange("goal_area_width_m", 0.1, 20.0);
  d.penalty_mark_distance_m = f.getInRange("penalty_mark_distance_m", 0.1, 10.0);
  d.penalty_mark_size_m = f.getInRange("penalty_mark_size_m", 0.01, 1.0);
  d.goal_inner_width_m = f.getInRange("goal_inner_width_m", 0.1, 10.0);
  d.goal_depth_m = f.getInRange("goal_depth_m", 0.1, 5.0);
  d.goal_height_m = f.getInRange("goal_height_m", 0.1, 5.0);
  d.goal_post_diameter_m = f.getInRange("goal_post_diameter_m", 0.01, 1.0);
  d.ball_diameter_m = f.getInRange("ball_diameter_m", 0.01, 1.0);
  d.robot_height_m = f.getInRange("robot_height_m", 0.1, 3.0);
  d.robot_width_m = f.getInRange("robot_width_m", 0.05, 3.0);
  f.finish();
  if (d.penalty_area_width_m >= d.field_width_m || d.penalty_area_length_m >= d.halfLength()) {
    throw Error(path + ": the penalty area does not fit in the field");
  }
  if (d.goal_area_width_m > d.penalty_area_width_m ||
      d.goal_area_length_m > d.penalty_area_length_m) {
    throw Error(path + ": the goal area does not fit in the penalty area");
  }
  return d;
}

FieldDimensions FieldDimensions::loadDefault() {
  return load(defaultParamDir() + "/field_dimensions.yaml");
}

}  // namespace colorfree
