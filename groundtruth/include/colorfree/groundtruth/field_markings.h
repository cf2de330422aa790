#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "colorfree/perception/field_dimensions.h"
#include "colorfree/perception/percepts.h"

namespace colorfree {

/// A straight field line, between the centres of its painted ends, field frame, metres.
struct FieldLineSegment {
  std::string name;
  Eigen::Vector2d start = Eigen::Vector2d::Zero();
  Eigen::Vector2d end = Eigen::Vector2d::Zero();
};

/// A line crossing on the field.
struct FieldIntersection {
  IntersectionType type = IntersectionType::kL;
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
};

/// The SPL field's markings built from FieldDimensions only: lines, the centre circle, the
/// L/T/X intersections and the penalty marks, field frame (origin centre, x to the opponent goal).
struct FieldMarkings {
  std::vector<FieldLineSegment> lines;
  Eigen::Vector2d centre_circle_centre = Eigen::Vector2d::Zero();
  double centre_circle_radius_m = 0.75;
  std::vector<FieldIntersection> intersections;
  std::vector<Eigen::Vector2d> penalty_marks;

  static FieldMarkings fromDimensions(const FieldDimensions& d);
};

const char* intersectionTypeName(IntersectionType type);

}  // namespace colorfree
