#pragma once

// A drawn ball (white with black pentagon patches, shaded) and a drawn robot foot on a synthetic
// field frame (tests/perception/synthetic_field.h), at known positions.

#include <array>
#include <cmath>

#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/image.h"

namespace colorfree::test {

struct DrawnBall {
  Eigen::Vector2d position_in_robot;  // on the ground
  double radius_m = 0.05;
  Eigen::Vector2d centre_px = Eigen::Vector2d::Zero();  // projection of the ball centre
  double radius_px = 0;
};

// The twelve pentagon centres of a football (icosahedron vertices).
inline std::array<Eigen::Vector3d, 12> pentagonCentres() {
  const double g = (1 + std::sqrt(5.0)) / 2;
  std::array<Eigen::Vector3d, 12> v = {
      Eigen::Vector3d(-1, g, 0), Eigen::Vector3d(1, g, 0), Eigen::Vector3d(-1, -g, 0), Eigen::Vector3d(1, -g, 0),
      Eigen::Vector3d(0, -1, g), Eigen::Vector3d(0, 1, g), Eigen::Vector3d(0, -1, -g), Eigen::Vector3d(0, 1, -g),
      Eigen::Vector3d(g, 0, -1), Eigen::Vector3d(g, 0, 1), Eigen::Vector3d(-g, 0, -1), Eigen::Vector3d(-g, 0, 1)};
  for (auto& x : v) x.normalize();
  return v;
}

// Draws the ball into `image` (4×4 supersampling at its outline) and returns where it is.
inline DrawnBall drawBall(GrayImage& image, const CameraModel& camera, const Eigen::Vector2d& ground,
                          double white = 215, double black = 35) {
  DrawnBall b;
  b.position_in_robot = ground;
  const Eigen::Vector3d c(ground.x(), ground.y(), b.radius_m);
  b.centre_px = *camera.robotToPixel(c);
  b.radius_px = *camera.ballRadiusPx(b.centre_px, b.radius_m);
  const auto pent = pentagonCentres();
  const Eigen::Vector3d eye = camera.position();
  const int x0 = std::max(0, static_cast<int>(b.centre_px.x() - b.radius_px - 2));
  const int x1 = std::min(image.width() - 1, static_cast<int>(b.centre_px.x() + b.radius_px + 2));
  const int y0 = std::max(0, static_cast<int>(b.centre_px.y() - b.radius_px - 2));
  const int y1 = std::min(image.height() - 1, static_cast<int>(b.centre_px.y() + b.radius_px + 2));
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      double sum = 0;
      int hits = 0;
      for (int s = 0; s < 16; ++s) {
        const Eigen::Vector2d px(x + 0.125 + 0.25 * (s % 4), y + 0.125 + 0.25 * (s / 4));
        const Eigen::Vector3d d = camera.pixelRay(px);
        const Eigen::Vector3d oc = eye - c;
        const double bq = oc.dot(d), cq = oc.squaredNorm() - b.radius_m * b.radius_m;
        const double disc = bq * bq - cq;
        if (disc < 0) continue;
        const Eigen::Vector3d n = (eye + d * (-bq - std::sqrt(disc)) - c).normalized();
        double best = -1;
        for (const auto& p : pent) best = std::max(best, n.dot(p));
        const double shade = 0.75 + 0.25 * n.z();
        sum += (best > 0.93 ? black : white) * shade;
        ++hits;
      }
      if (hits == 0) continue;
      const double v = (sum + (16 - hits) * image.at(x, y)) / 16;
      image.at(x, y) = static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
    }
  }
  return b;
}

// A robot's foot: a bright box (the foot's top) with a dark sole strip, standing on the ground
// at `ground` (its centre), `length_m` along x.
inline void drawFoot(GrayImage& image, const CameraModel& camera, const Eigen::Vector2d& ground,
                     double length_m = 0.16, double width_m = 0.09, double height_m = 0.05) {
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      // The pixel shows the foot when its ray passes through the box; cheap test on the box's
      // faces: walk the ray from the camera in small steps.
      const Eigen::Vector3d d = camera.pixelRay({x + 0.5, y + 0.5});
      if (d.z() >= 0) continue;
      const Eigen::Vector3d o = camera.position();
      const double t_top = (o.z() - height_m) / -d.z(), t_ground = o.z() / -d.z();
      bool hit = false;
      double value = 0;
      for (double t = t_top; t <= t_ground; t += 0.004) {
        const Eigen::Vector3d p = o + t * d;
        if (std::abs(p.x() - ground.x()) <= length_m / 2 && std::abs(p.y() - ground.y()) <= width_m / 2) {
          hit = true;
          value = p.z() < 0.012 ? 45 : 205;
          break;
        }
      }
      if (hit) image.at(x, y) = static_cast<std::uint8_t>(value);
    }
  }
}

}  // namespace colorfree::test
