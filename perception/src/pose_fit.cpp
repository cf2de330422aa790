#include "colorfree/perception/pose_fit.h"

#include <Eigen/Dense>
#include <cmath>

#include "colorfree/perception/param_file.h"

namespace colorfree {

FieldModel::FieldModel(const FieldDimensions& f) {
  const double hl = f.halfLength(), hw = f.halfWidth();
  const double pa_x = hl - f.penalty_area_length_m, pa_y = f.penalty_area_width_m / 2;
  const double ga_x = hl - f.goal_area_length_m, ga_y = f.goal_area_width_m / 2;
  using V = Eigen::Vector2d;
  lines = {{V(-hl, hw), V(hl, hw)}, {V(-hl, -hw), V(hl, -hw)}, {V(0, -hw), V(0, hw)}};
  for (double sx : {-1.0, 1.0}) {
    lines.push_back({V(sx * hl, -hw), V(sx * hl, hw)});
    lines.push_back({V(sx * pa_x, -pa_y), V(sx * pa_x, pa_y)});
    lines.push_back({V(sx * pa_x, pa_y), V(sx * hl, pa_y)});
    lines.push_back({V(sx * pa_x, -pa_y), V(sx * hl, -pa_y)});
    lines.push_back({V(sx * ga_x, -ga_y), V(sx * ga_x, ga_y)});
    lines.push_back({V(sx * ga_x, ga_y), V(sx * hl, ga_y)});
    lines.push_back({V(sx * ga_x, -ga_y), V(sx * hl, -ga_y)});
    penalty_marks.emplace_back(sx * (hl - f.penalty_mark_distance_m), 0);
    for (double sy : {-1.0, 1.0}) {
      intersections.push_back({IntersectionType::kL, V(sx * hl, sy * hw)});
      intersections.push_back({IntersectionType::kL, V(sx * pa_x, sy * pa_y)});
      intersections.push_back({IntersectionType::kL, V(sx * ga_x, sy * ga_y)});
      intersections.push_back({IntersectionType::kT, V(sx * hl, sy * pa_y)});
      intersections.push_back({IntersectionType::kT, V(sx * hl, sy * ga_y)});
    }
  }
  centre_circle_radius_m = f.centre_circle_diameter_m / 2;
  for (double sy : {-1.0, 1.0}) {
    intersections.push_back({IntersectionType::kT, V(0, sy * hw)});
    intersections.push_back({IntersectionType::kX, V(0, sy * centre_circle_radius_m)});
  }
}

PoseFitParams PoseFitParams::load(const std::string& path) {
  ParamFile f(path);
  PoseFitParams p;
  p.iterations = static_cast<int>(f.getInRange("iterations", 1, 1000));
  p.line_sample_spacing_m = f.getInRange("line_sample_spacing_m", 0.01, 5);
  p.huber_m = f.getInRange("huber_m", 0.001, 10);
  p.max_association_m = f.getInRange("max_association_m", 0.01, 20);
  p.intersection_weight = f.getInRange("intersection_weight", 0, 1000);
  p.heading_prior_min_line_m = f.getInRange("heading_prior_min_line_m", 0, 10);
  p.heading_prior_max_correction_deg = f.getInRange("heading_prior_max_correction_deg", 0, 45);
  p.circle_weight = f.getInRange("circle_weight", 0, 1000);
  p.penalty_mark_weight = f.getInRange("penalty_mark_weight", 0, 1000);
  p.converged_step_m = f.getInRange("converged_step_m", 0, 1);
  f.finish();
  return p;
}

PoseFitParams PoseFitParams::loadDefault() { return load(defaultParamDir() + "/pose_fit.yaml"); }

PoseFitter::PoseFitter(PoseFitParams params, FieldDimensions field)
    : params_(params), model_(field) {}

namespace {

struct Normal {
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  double squared = 0;
  int count = 0;
};

// Adds one scalar residual r with Jacobian j and base weight w, Huber-weighted.
void addResidual(Normal& n, double r, const Eigen::Vector3d& j, double w, double huber) {
  const double a = std::abs(r);
  const double robust = a <= huber ? 1.0 : huber / a;
  n.h += w * robust * j * j.transpose();
  n.g += w * robust * j * r;
}

}  // namespace

PoseFitResult PoseFitter::fit(const FieldFeatures& features, const FieldPose& guess) const {
  const auto& p = params_;
  // Points along the detected lines, with their line's direction, robot frame.
  struct Sample {
    Eigen::Vector2d point, direction;
  };
  std::vector<Sample> samples;
  for (const auto& l : features.lines) {
    const Eigen::Vector2d d = l.end_in_robot - l.start_in_robot;
    const double len = d.norm();
    if (len < 1e-6) continue;
    const int n = std::max(2, static_cast<int>(std::ceil(len / p.line_sample_spacing_m)) + 1);
    for (int i = 0; i < n; ++i) {
      samples.push_back({l.start_in_robot + d * (static_cast<double>(i) / (n - 1)), d / len});
    }
  }

  PoseFitResult result;
  FieldPose pose = guess;
  // Every line of an SPL field runs along x or y, so the detected lines' directions give the
  // heading modulo 90 degrees whatever the translation. Correcting the guess's heading with them
  // first matters: 5 degrees of heading error moves lines 4 m away sideways by 0.35 m, enough to
  // drag the fit onto a neighbouring pattern (the goal area's side lines onto the penalty area's).
  double sin4 = 0, cos4 = 0;
  for (const auto& l : features.lines) {
    const Eigen::Vector2d d = l.end_in_robot - l.start_in_robot;
    const double len = d.norm();
    if (len < p.heading_prior_min_line_m) continue;
    const double a = 4 * (pose.heading_rad + std::atan2(d.y(), d.x()));
    sin4 += len * std::sin(a);
    cos4 += len * std::cos(a);
  }
  if (sin4 != 0 || cos4 != 0) {
    const double correction = -std::atan2(sin4, cos4) / 4;
    if (std::abs(correction) <= p.heading_prior_max_correction_deg * 3.14159265358979323846 / 180) {
      pose.heading_rad += correction;
    }
  }
  for (int it = 0; it < p.iterations; ++it) {
    const double c = std::cos(pose.heading_rad), s = std::sin(pose.heading_rad);
    // d(field point)/dθ for a robot-frame point.
    const auto dRotated = [&](const Eigen::Vector2d& q) {
      return Eigen::Vector2d(-s * q.x() - c * q.y(), c * q.x() - s * q.y());
    };
    Normal n;
    double squared = 0;
    int used = 0;
    const auto add2d = [&](const Eigen::Vector2d& q_robot, const Eigen::Vector2d& target, double w) {
      const Eigen::Vector2d e = pose.toField(q_robot) - target;
      if (e.norm() > p.max_association_m) return;
      const Eigen::Vector2d dr = dRotated(q_robot);
      addResidual(n, e.x(), {1, 0, dr.x()}, w, p.huber_m);
      addResidual(n, e.y(), {0, 1, dr.y()}, w, p.huber_m);
      squared += e.squaredNorm();
      ++used;
    };

    for (const Sample& sm : samples) {
      const Eigen::Vector2d q = pose.toField(sm.point);
      const Eigen::Vector2d dir(c * sm.direction.x() - s * sm.direction.y(),
                                s * sm.direction.x() + c * sm.direction.y());
      double best = p.max_association_m;
      const FieldModel::Segment* match = nullptr;
      for (const auto& seg : model_.lines) {
        const Eigen::Vector2d ab = seg.b - seg.a;
        const double len = ab.norm();
        const Eigen::Vector2d u = ab / len;
        // Only a model line of about the same direction (within 30 degrees) explains a sample.
        if (std::abs(u.dot(dir)) < 0.866) continue;
        const double t = std::clamp((q - seg.a).dot(u), 0.0, len);
        const double dist = (q - (seg.a + t * u)).norm();
        if (dist < best) best = dist, match = &seg;
      }
      if (!match) continue;
      const Eigen::Vector2d u = (match->b - match->a).normalized();
      const Eigen::Vector2d normal(-u.y(), u.x());
      const double r = normal.dot(q - match->a);
      const Eigen::Vector2d dr = dRotated(sm.point);
      addResidual(n, r, {normal.x(), normal.y(), normal.dot(dr)}, 1.0, p.huber_m);
      squared += r * r;
      ++used;
    }
    for (const auto& x : features.intersections) {
      const Eigen::Vector2d q = pose.toField(x.position_in_robot);
      const FieldModel::Intersection* match = nullptr;
      double best = p.max_association_m;
      for (const auto& m : model_.intersections) {
        if (m.type != x.type) continue;
        const double d = (q - m.position).norm();
        if (d < best) best = d, match = &m;
      }
      if (match) add2d(x.position_in_robot, match->position, p.intersection_weight);
    }
    if (features.centre_circle) {
      add2d(features.centre_circle->centre_in_robot, model_.centre_circle_centre, p.circle_weight);
    }
    for (const auto& m : features.penalty_marks) {
      const Eigen::Vector2d q = pose.toField(m.centre_in_robot);
      const Eigen::Vector2d* match = nullptr;
      double best = p.max_association_m;
      for (const auto& pm : model_.penalty_marks) {
        if ((q - pm).norm() < best) best = (q - pm).norm(), match = &pm;
      }
      if (match) add2d(m.centre_in_robot, *match, p.penalty_mark_weight);
    }

    result.used_observations = used;
    result.rms_residual_m = used > 0 ? std::sqrt(squared / used) : 0;
    result.iterations = it + 1;
    // The pose is determined only when all three directions are constrained.
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(n.h);
    if (used < 3 || eig.eigenvalues().minCoeff() < 1e-6 * std::max(1.0, eig.eigenvalues().maxCoeff())) {
      result.ok = false;
      break;
    }
    const Eigen::Vector3d step = -n.h.ldlt().solve(n.g);
    pose.x_m += step.x();
    pose.y_m += step.y();
    pose.heading_rad = std::remainder(pose.heading_rad + step.z(), 2 * 3.14159265358979323846);
    result.ok = true;
    if (step.head<2>().norm() < p.converged_step_m && std::abs(step.z()) < p.converged_step_m) break;
  }
  result.pose = pose;
  return result;
}

}  // namespace colorfree
