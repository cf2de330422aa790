#include "colorfree/groundtruth/field_markings.h"

namespace colorfree {

FieldMarkings FieldMarkings::fromDimensions(const FieldDimensions& d) {
  FieldMarkings m;
  const double hl = d.halfLength();
  const double hw = d.halfWidth();
  const double pa_x = hl - d.penalty_area_length_m;
  const double pa_y = d.penalty_area_width_m / 2;
  const double ga_x = hl - d.goal_area_length_m;
  const double ga_y = d.goal_area_width_m / 2;
  auto line = [&](const std::string& name, double x0, double y0, double x1, double y1) {
    m.lines.push_back({name, {x0, y0}, {x1, y1}});
  };
  auto add = [&](IntersectionType t, double x, double y) { m.intersections.push_back({t, {x, y}}); };
  line("touch line left", -hl, hw, hl, hw);
  line("touch line right", -hl, -hw, hl, -hw);
  line("halfway line", 0, -hw, 0, hw);
  add(IntersectionType::kT, 0, hw);
  add(IntersectionType::kT, 0, -hw);
  m.centre_circle_radius_m = d.centre_circle_diameter_m / 2;
  add(IntersectionType::kX, 0, m.centre_circle_radius_m);
  add(IntersectionType::kX, 0, -m.centre_circle_radius_m);
  for (double s : {-1.0, 1.0}) {
    const std::string side = s > 0 ? " opponent" : " own";
    line("goal line" + side, s * hl, -hw, s * hl, hw);
    line("penalty area front" + side, s * pa_x, -pa_y, s * pa_x, pa_y);
    line("penalty area left" + side, s * hl, pa_y, s * pa_x, pa_y);
    line("penalty area right" + side, s * hl, -pa_y, s * pa_x, -pa_y);
    line("goal area front" + side, s * ga_x, -ga_y, s * ga_x, ga_y);
    line("goal area left" + side, s * hl, ga_y, s * ga_x, ga_y);
    line("goal area right" + side, s * hl, -ga_y, s * ga_x, -ga_y);
    for (double t : {-1.0, 1.0}) {
      add(IntersectionType::kL, s * hl, t * hw);
      add(IntersectionType::kT, s * hl, t * pa_y);
      add(IntersectionType::kL, s * pa_x, t * pa_y);
      add(IntersectionType::kT, s * hl, t * ga_y);
      add(IntersectionType::kL, s * ga_x, t * ga_y);
    }
    m.penalty_marks.push_back({s * (hl - d.penalty_mark_distance_m), 0});
  }
  return m;
}

const char* intersectionTypeName(IntersectionType type) {
  switch (type) {
    case IntersectionType::kL: return "L";
    case IntersectionType::kT: return "T";
    case IntersectionType::kX: return "X";
  }
  return "?";
}

}  // namespace colorfree
