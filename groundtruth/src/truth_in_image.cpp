#include "colorfree/groundtruth/truth_in_image.h"

#include "colorfree/perception/orientation/geometry.h"

#include <algorithm>
#include <cmath>

namespace colorfree {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kNearPlaneM = 0.01;
constexpr int kOutlinePoints = 96;
constexpr double kLineSampleStepPx = 2.0;

// Liang–Barsky clipping of a 2-D segment to [0,w]×[0,h].
bool clipToRect(Eigen::Vector2d& a, Eigen::Vector2d& b, double w, double h) {
  const Eigen::Vector2d d = b - a;
  double t0 = 0, t1 = 1;
  const double p[4] = {-d.x(), d.x(), -d.y(), d.y()};
  const double q[4] = {a.x(), w - a.x(), a.y(), h - a.y()};
  for (int i = 0; i < 4; ++i) {
    if (p[i] == 0) {
      if (q[i] < 0) return false;
      continue;
    }
    const double t = q[i] / p[i];
    if (p[i] < 0) {
      t0 = std::max(t0, t);
    } else {
      t1 = std::min(t1, t);
    }
    if (t0 > t1) return false;
  }
  const Eigen::Vector2d a0 = a;
  a = a0 + t0 * d;
  b = a0 + t1 * d;
  return true;
}

bool hasLabelNear(const ObjectMap& map, const Eigen::Vector2d& p, int window, std::uint16_t label) {
  const int cx = static_cast<int>(std::floor(p.x()));
  const int cy = static_cast<int>(std::floor(p.y()));
  for (int y = std::max(0, cy - window); y <= std::min(map.height - 1, cy + window); ++y) {
    for (int x = std::max(0, cx - window); x <= std::min(map.width - 1, cx + window); ++x) {
      if (map.at(x, y) == label) return true;
    }
  }
  return false;
}

bool mapUsable(const ObjectMap& map, const FrameProjector& proj) {
  return map.width == proj.width() && map.height == proj.height() &&
         map.labels.size() == static_cast<std::size_t>(map.width) * map.height;
}

PixelBox boxOf(const std::vector<Eigen::Vector2d>& pts) {
  PixelBox b{1e300, 1e300, -1e300, -1e300};
  for (const auto& p : pts) {
    b.x0 = std::min(b.x0, p.x());
    b.y0 = std::min(b.y0, p.y());
    b.x1 = std::max(b.x1, p.x());
    b.y1 = std::max(b.y1, p.y());
  }
  return b;
}

PixelBox clipBox(PixelBox b, double w, double h) {
  b.x0 = std::clamp(b.x0, 0.0, w);
  b.x1 = std::clamp(b.x1, 0.0, w);
  b.y0 = std::clamp(b.y0, 0.0, h);
  b.y1 = std::clamp(b.y1, 0.0, h);
  return b;
}

// Seen from above, the NAO's outline (arms, legs, feet in stride) is close to an ellipse: a box
// of the same size overstates its width seen diagonally by about a third (measured on renders).
constexpr double kFootprintExponent = 2.0;
constexpr int kFootprintPoints = 24;

// Points of an upright prism with that footprint under a robot, at the ground and at `height`,
// field frame; bottom ring first.
std::vector<Eigen::Vector3d> bodyOutline(const FieldPose& pose, double depth, double width,
                                         double height) {
  const Eigen::Vector2d f(std::cos(pose.heading_rad), std::sin(pose.heading_rad));
  const Eigen::Vector2d l(-f.y(), f.x());
  const Eigen::Vector2d c(pose.x_m, pose.y_m);
  std::vector<Eigen::Vector3d> out;
  for (double z : {0.0, height}) {
    for (int k = 0; k < kFootprintPoints; ++k) {
      const double t = 2 * kPi * k / kFootprintPoints;
      auto se = [](double v) {
        return std::copysign(std::pow(std::abs(v), 2.0 / kFootprintExponent), v);
      };
      const Eigen::Vector2d g =
          c + se(std::cos(t)) * depth / 2 * f + se(std::sin(t)) * width / 2 * l;
      out.emplace_back(g.x(), g.y(), z);
    }
  }
  return out;
}

// The prism's edges (rings and verticals), cut at the near plane and projected.
std::vector<Eigen::Vector2d> projectOutline(const FrameProjector& proj,
                                            const std::vector<Eigen::Vector3d>& pts) {
  std::vector<Eigen::Vector2d> out;
  auto add = [&](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    if (auto s = proj.segmentUnclipped(a, b)) {
      out.push_back(s->first);
      out.push_back(s->second);
    }
  };
  const int n = kFootprintPoints;
  for (int k = 0; k < n; ++k) {
    add(pts[k], pts[(k + 1) % n]);
    add(pts[n + k], pts[n + (k + 1) % n]);
    add(pts[k], pts[n + k]);
  }
  return out;
}

}  // namespace

// wrapAngle and convexHull: the perception library's (orientation/geometry.cpp), same contract.

RobotSide sideSeen(double heading_rel_rad) {
  const double a = std::abs(wrapAngle(heading_rel_rad));
  if (a <= kPi / 4) return RobotSide::kFront;
  if (a >= 3 * kPi / 4) return RobotSide::kBack;
  return RobotSide::kSide;
}

const char* robotSideName(RobotSide side) {
  switch (side) {
    case RobotSide::kFront:
      return "front";
    case RobotSide::kBack:
      return "back";
    case RobotSide::kSide:
      return "side";
  }
  return "?";
}

double polygonArea(const std::vector<Eigen::Vector2d>& poly) {
  double a = 0;
  for (std::size_t i = 0; i < poly.size(); ++i) {
    const auto& p = poly[i];
    const auto& q = poly[(i + 1) % poly.size()];
    a += p.x() * q.y() - q.x() * p.y();
  }
  return std::abs(a) / 2;
}

std::vector<Eigen::Vector2d> clipPolygonToRect(const std::vector<Eigen::Vector2d>& polygon,
                                               double w, double h) {
  // Sutherland–Hodgman against the four half-planes.
  std::vector<Eigen::Vector2d> out = polygon;
  for (int edge = 0; edge < 4 && !out.empty(); ++edge) {
    auto inside = [&](const Eigen::Vector2d& p) {
      switch (edge) {
        case 0:
          return p.x() >= 0;
        case 1:
          return p.x() <= w;
        case 2:
          return p.y() >= 0;
        default:
          return p.y() <= h;
      }
    };
    auto cross = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
      double t = 0;
      switch (edge) {
        case 0:
          t = (0 - a.x()) / (b.x() - a.x());
          break;
        case 1:
          t = (w - a.x()) / (b.x() - a.x());
          break;
        case 2:
          t = (0 - a.y()) / (b.y() - a.y());
          break;
        default:
          t = (h - a.y()) / (b.y() - a.y());
          break;
      }
      return Eigen::Vector2d(a + t * (b - a));
    };
    std::vector<Eigen::Vector2d> in = std::move(out);
    out.clear();
    for (std::size_t i = 0; i < in.size(); ++i) {
      const auto& cur = in[i];
      const auto& prev = in[(i + in.size() - 1) % in.size()];
      if (inside(cur)) {
        if (!inside(prev)) out.push_back(cross(prev, cur));
        out.push_back(cur);
      } else if (inside(prev)) {
        out.push_back(cross(prev, cur));
      }
    }
  }
  return out;
}

bool insideConvex(const std::vector<Eigen::Vector2d>& hull, const Eigen::Vector2d& p) {
  if (hull.size() < 3) return false;
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const auto& a = hull[i];
    const auto& b = hull[(i + 1) % hull.size()];
    if ((b.x() - a.x()) * (p.y() - a.y()) - (b.y() - a.y()) * (p.x() - a.x()) < 0) return false;
  }
  return true;
}

double pointSegmentDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                            const Eigen::Vector2d& b) {
  const Eigen::Vector2d d = b - a;
  const double len2 = d.squaredNorm();
  const double t = len2 > 0 ? std::clamp((p - a).dot(d) / len2, 0.0, 1.0) : 0.0;
  return (p - (a + t * d)).norm();
}

FrameProjector::FrameProjector(const CameraTruth& camera)
    : intrinsics_(camera.model.intrinsics()),
      camera_to_field_(camera.camera_to_field),
      field_to_camera_(camera.camera_to_field.inverse()) {}

Eigen::Vector3d FrameProjector::toCamera(const Eigen::Vector3d& p) const {
  return field_to_camera_ * p;
}

Eigen::Vector2d FrameProjector::toPixel(const Eigen::Vector3d& c) const {
  return {intrinsics_.center_x_px + intrinsics_.focal_x_px * c.x() / c.z(),
          intrinsics_.center_y_px + intrinsics_.focal_y_px * c.y() / c.z()};
}

std::optional<Eigen::Vector2d> FrameProjector::project(const Eigen::Vector3d& p) const {
  const Eigen::Vector3d c = toCamera(p);
  if (c.z() < kNearPlaneM) return std::nullopt;
  return toPixel(c);
}

std::optional<std::pair<Eigen::Vector2d, Eigen::Vector2d>> FrameProjector::segmentUnclipped(
    const Eigen::Vector3d& a_f, const Eigen::Vector3d& b_f) const {
  Eigen::Vector3d a = toCamera(a_f), b = toCamera(b_f);
  if (a.z() < kNearPlaneM && b.z() < kNearPlaneM) return std::nullopt;
  // Cut the part behind the near plane so the projection stays a straight, finite segment.
  if (a.z() < kNearPlaneM) a = a + (b - a) * ((kNearPlaneM - a.z()) / (b.z() - a.z()));
  if (b.z() < kNearPlaneM) b = b + (a - b) * ((kNearPlaneM - b.z()) / (a.z() - b.z()));
  return std::make_pair(toPixel(a), toPixel(b));
}

std::optional<std::pair<Eigen::Vector2d, Eigen::Vector2d>> FrameProjector::segment(
    const Eigen::Vector3d& a_f, const Eigen::Vector3d& b_f) const {
  auto s = segmentUnclipped(a_f, b_f);
  if (!s) return std::nullopt;
  if (!clipToRect(s->first, s->second, width(), height())) return std::nullopt;
  return s;
}

namespace {

BallInImage ballInImage(const WorldState& w, const FrameProjector& proj, bool use_map,
                        const ScoringParams& params) {
  BallInImage b;
  const Eigen::Vector3d centre = w.ball.position_m;
  const double r = w.ball.radius_m;
  b.position_in_field = centre.head<2>();
  b.distance_m = (centre.head<2>() - Eigen::Vector2d(w.observer.x_m, w.observer.y_m)).norm();
  const Eigen::Vector3d cam = proj.cameraPosition();
  const Eigen::Vector3d to_ball = centre - cam;
  const double d = to_ball.norm();
  if (d <= r * 1.0001) return b;
  // The outline is the circle where the cone from the camera touches the sphere.
  const Eigen::Vector3d axis = to_ball / d;
  const Eigen::Vector3d q = cam + to_ball * (1 - r * r / (d * d));
  const double rho = r * std::sqrt(d * d - r * r) / d;
  const Eigen::Vector3d u = axis.unitOrthogonal();
  const Eigen::Vector3d v = axis.cross(u);
  for (int i = 0; i < kOutlinePoints; ++i) {
    const double t = 2 * kPi * i / kOutlinePoints;
    const auto p = proj.project(q + rho * (std::cos(t) * u + std::sin(t) * v));
    if (!p) {
      b.outline_px.clear();
      return b;
    }
    b.outline_px.push_back(*p);
  }
  const PixelBox box = boxOf(b.outline_px);
  b.centre_px = box.centre();
  for (const auto& p : b.outline_px) b.radius_px = std::max(b.radius_px, (p - b.centre_px).norm());
  b.projected_area_px = polygonArea(b.outline_px);
  const double inside_area =
      polygonArea(clipPolygonToRect(b.outline_px, proj.width(), proj.height()));
  b.in_view = inside_area > 0;
  if (!b.in_view) return b;
  if (use_map) {
    const PixelBox c = clipBox(box, proj.width(), proj.height());
    for (int y = static_cast<int>(c.y0); y < static_cast<int>(std::ceil(c.y1)); ++y) {
      for (int x = static_cast<int>(c.x0); x < static_cast<int>(std::ceil(c.x1)); ++x) {
        if (w.object_map.at(x, y) == kObjectBall) ++b.visible_px;
      }
    }
    b.visible_fraction = std::min(1.0, b.visible_px / std::max(1e-9, b.projected_area_px));
  } else {
    b.visible_fraction = inside_area / std::max(1e-9, b.projected_area_px);
  }
  b.should_detect = b.visible_fraction >= params.ball_min_visible_fraction &&
                    b.distance_m >= params.ball_min_distance_m &&
                    b.distance_m <= params.ball_max_distance_m &&
                    b.radius_px >= params.ball_min_radius_px && proj.inImage(b.centre_px);
  return b;
}

RobotInImage robotInImage(const WorldState& w, std::size_t i, const FrameProjector& proj,
                          bool use_map, const FieldDimensions& dims, const ScoringParams& params) {
  const RobotTruth& t = w.robots[i];
  RobotInImage r;
  r.index = t.index;
  r.speed_mps = t.speed_mps;
  r.position_in_field = {t.pose.x_m, t.pose.y_m};
  const Eigen::Vector2d obs(w.observer.x_m, w.observer.y_m);
  r.distance_m = (r.position_in_field - obs).norm();
  const Eigen::Vector2d los = r.position_in_field - proj.cameraPosition().head<2>();
  r.heading_rel_rad = wrapAngle(t.pose.heading_rad - std::atan2(-los.y(), -los.x()));
  r.side_seen = sideSeen(r.heading_rel_rad);
  r.heading_in_observer_rad = wrapAngle(t.pose.heading_rad - w.observer.heading_rad);

  const auto pts = projectOutline(
      proj, bodyOutline(t.pose, params.robot_depth_m, dims.robot_width_m, dims.robot_height_m));
  if (pts.empty()) return r;
  const auto feet_pts =
      projectOutline(proj, bodyOutline(t.pose, params.robot_depth_m, dims.robot_width_m,
                                       params.robot_feet_region_height_m));
  const double W = proj.width(), H = proj.height();
  const PixelBox full = boxOf(pts);
  r.box = clipBox(full, W, H);
  if (!feet_pts.empty()) r.feet_box = clipBox(boxOf(feet_pts), W, H);
  const Eigen::Vector2d f(std::cos(t.pose.heading_rad), std::sin(t.pose.heading_rad));
  const Eigen::Vector2d l(-f.y(), f.x());
  auto ground = [&](const Eigen::Vector2d& g) {
    return proj.project(Eigen::Vector3d(g.x(), g.y(), 0)).value_or(Eigen::Vector2d(-1, -1));
  };
  r.ground_px = ground(r.position_in_field);
  r.left_foot_px = ground(r.position_in_field + params.foot_lateral_offset_m * l);
  r.right_foot_px = ground(r.position_in_field - params.foot_lateral_offset_m * l);

  const auto hull = convexHull(pts);
  r.projected_area_px = polygonArea(hull);
  const double inside_area = polygonArea(clipPolygonToRect(hull, W, H));
  r.in_view = inside_area > 0 && r.box.width() > 0 && r.box.height() > 0;
  if (!r.in_view) return r;
  const double in_image_share = inside_area / std::max(1e-9, r.projected_area_px);
  if (use_map) {
    const std::uint16_t own = static_cast<std::uint16_t>(kObjectRobotBase + i);
    const double ball_dist = (w.ball.position_m - proj.cameraPosition()).norm();
    const double my_dist =
        (Eigen::Vector3d(t.pose.x_m, t.pose.y_m, 0) - proj.cameraPosition()).norm();
    std::vector<bool> nearer(w.robots.size(), false);
    for (std::size_t j = 0; j < w.robots.size(); ++j) {
      const Eigen::Vector3d pj(w.robots[j].pose.x_m, w.robots[j].pose.y_m, 0);
      nearer[j] = j != i && (pj - proj.cameraPosition()).norm() < my_dist;
    }
    for (int y = static_cast<int>(r.box.y0); y < static_cast<int>(std::ceil(r.box.y1)); ++y) {
      for (int x = static_cast<int>(r.box.x0); x < static_cast<int>(std::ceil(r.box.x1)); ++x) {
        const std::uint16_t label = w.object_map.at(x, y);
        if (label == own) {
          ++r.visible_px;
          continue;
        }
        if (!insideConvex(hull, Eigen::Vector2d(x + 0.5, y + 0.5))) continue;
        const bool occluder = label == kObjectOwnBody ||
                              (label == kObjectBall && w.ball.present && ball_dist < my_dist) ||
                              (label >= kObjectRobotBase &&
                               label - kObjectRobotBase < static_cast<int>(nearer.size()) &&
                               nearer[label - kObjectRobotBase]);
        if (occluder) ++r.occluded_px;
      }
    }
    const int seen = r.visible_px + r.occluded_px;
    r.visible_fraction = seen > 0 ? in_image_share * r.visible_px / seen : 0.0;
  } else {
    r.visible_fraction = in_image_share;
  }
  r.should_detect = r.visible_fraction >= params.robot_min_visible_fraction &&
                    r.distance_m >= params.robot_min_distance_m &&
                    r.distance_m <= params.robot_max_distance_m &&
                    full.height() >= params.robot_min_height_px && proj.inImage(r.box.centre());
  return r;
}

double visibleLength(const ObjectMap& map, bool use_map, const Eigen::Vector2d& a,
                     const Eigen::Vector2d& b, int window) {
  const double len = (b - a).norm();
  if (!use_map) return len;
  const int n = std::max(1, static_cast<int>(std::ceil(len / kLineSampleStepPx)));
  int seen = 0;
  for (int k = 0; k <= n; ++k) {
    if (hasLabelNear(map, a + (b - a) * (static_cast<double>(k) / n), window, kObjectLine)) ++seen;
  }
  return len * seen / (n + 1);
}

// The part of the ground segment a-b within `radius` of `centre`; empty when none.
std::optional<std::pair<Eigen::Vector2d, Eigen::Vector2d>> clipToDisc(const Eigen::Vector2d& a,
                                                                      const Eigen::Vector2d& b,
                                                                      const Eigen::Vector2d& centre,
                                                                      double radius) {
  const Eigen::Vector2d d = b - a, m = a - centre;
  const double qa = d.squaredNorm(), qb = 2 * m.dot(d), qc = m.squaredNorm() - radius * radius;
  if (qa <= 0) return qc <= 0 ? std::make_optional(std::make_pair(a, b)) : std::nullopt;
  const double disc = qb * qb - 4 * qa * qc;
  if (disc < 0) return std::nullopt;
  const double t0 = std::max(0.0, (-qb - std::sqrt(disc)) / (2 * qa));
  const double t1 = std::min(1.0, (-qb + std::sqrt(disc)) / (2 * qa));
  if (t0 >= t1) return std::nullopt;
  return std::make_pair(Eigen::Vector2d(a + t0 * d), Eigen::Vector2d(a + t1 * d));
}

FieldInImage fieldInImage(const WorldState& w, const FrameProjector& proj, bool use_map,
                          const FieldMarkings& model, const ScoringParams& params) {
  FieldInImage f;
  const int win = params.feature_visibility_window_px;
  const Eigen::Vector2d observer(w.observer.x_m, w.observer.y_m);
  const double max_d = params.field_feature_max_distance_m;
  // Field markings beyond the feature distance are left out, on the ground.
  auto project =
      [&](const Eigen::Vector2d& a,
          const Eigen::Vector2d& b) -> std::optional<std::pair<Eigen::Vector2d, Eigen::Vector2d>> {
    const auto near = clipToDisc(a, b, observer, max_d);
    if (!near) return std::nullopt;
    return proj.segment({near->first.x(), near->first.y(), 0},
                        {near->second.x(), near->second.y(), 0});
  };
  for (const auto& line : model.lines) {
    const auto s = project(line.start, line.end);
    if (!s) continue;
    LineInImage li{line.name, false, s->first, s->second, 0};
    li.visible_length_px = visibleLength(w.object_map, use_map, s->first, s->second, win);
    if (li.visible_length_px >= params.line_min_length_px) f.lines.push_back(li);
  }
  constexpr int kCirclePieces = 64;
  double circle_visible = 0;
  const Eigen::Vector2d cc = model.centre_circle_centre;
  for (int k = 0; k < kCirclePieces; ++k) {
    const double t0 = 2 * kPi * k / kCirclePieces, t1 = 2 * kPi * (k + 1) / kCirclePieces;
    const Eigen::Vector2d a =
        cc + model.centre_circle_radius_m * Eigen::Vector2d(std::cos(t0), std::sin(t0));
    const Eigen::Vector2d b =
        cc + model.centre_circle_radius_m * Eigen::Vector2d(std::cos(t1), std::sin(t1));
    const auto s = project(a, b);
    if (!s) continue;
    LineInImage li{"centre circle", true, s->first, s->second, 0};
    li.visible_length_px = visibleLength(w.object_map, use_map, s->first, s->second, win);
    circle_visible += li.visible_length_px;
    f.circle_pieces.push_back(li);
  }
  f.centre_circle_in_view = circle_visible >= params.line_min_length_px;
  f.circle_centre_px = proj.project({cc.x(), cc.y(), 0});
  auto pointInView = [&](const Eigen::Vector2d& g) -> std::optional<Eigen::Vector2d> {
    if ((g - observer).norm() > max_d) return std::nullopt;
    const auto p = proj.project({g.x(), g.y(), 0});
    if (!p || !proj.inImage(*p) || p->x() >= proj.width() || p->y() >= proj.height())
      return std::nullopt;
    if (use_map && !hasLabelNear(w.object_map, *p, win, kObjectLine)) return std::nullopt;
    return p;
  };
  for (const auto& x : model.intersections) {
    if (const auto p = pointInView(x.position)) f.intersections.push_back({x.type, *p, x.position});
  }
  for (const auto& m : model.penalty_marks) {
    if (const auto p = pointInView(m)) f.penalty_marks.push_back({IntersectionType::kX, *p, m});
  }
  return f;
}

}  // namespace

FrameTruth computeFrameTruth(const WorldState& world, const FieldMarkings& field,
                             const FieldDimensions& dims, const ScoringParams& params) {
  FrameTruth t;
  t.frame_index = world.frame_index;
  t.observer = world.observer;
  const FrameProjector proj(world.camera);
  const bool use_map = mapUsable(world.object_map, proj);
  t.ball_present = world.ball.present;
  if (world.ball.present) t.ball = ballInImage(world, proj, use_map, params);
  for (std::size_t i = 0; i < world.robots.size(); ++i) {
    t.robots.push_back(robotInImage(world, i, proj, use_map, dims, params));
  }
  t.field = fieldInImage(world, proj, use_map, field, params);
  return t;
}

}  // namespace colorfree
