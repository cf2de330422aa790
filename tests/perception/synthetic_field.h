#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/field_dimensions.h"
#include "colorfree/perception/image.h"
#include "colorfree/perception/pose_fit.h"

// Draws field markings on the ground plane as a camera sees them: each pixel's rays (2×2 per
// pixel) meet the ground, a painted marking covers them or not; the carpet gets a seeded texture.
namespace colorfree::test {

struct GroundSegment {
  Eigen::Vector2d a, b;  // centre line of a painted strip, robot frame
};
struct GroundRing {
  Eigen::Vector2d centre;
  double radius_m;
};

struct SyntheticScene {
  std::vector<GroundSegment> segments;
  std::vector<GroundRing> rings;
  double line_width_m = 0.05;
  double carpet = 70;          // gray level of the carpet
  double paint = 190;          // gray level of the lines
  double background = 150;     // above the carpet's edge (the hall)
  double pixel_noise = 5;      // std of per-pixel noise
  double texture = 8;          // amplitude of the carpet's low-frequency texture
  double gradient = 0;         // illumination falls by this fraction from left to right
  double carpet_edge_m = 1e9;  // the carpet ends this far from the robot (x), the hall beyond
  std::uint64_t seed = 1;
};

// The field's markings seen from a robot at `pose`, in its robot frame.
inline SyntheticScene sceneFromField(const FieldDimensions& field, const FieldPose& pose) {
  const FieldModel model(field);
  const double c = std::cos(pose.heading_rad), s = std::sin(pose.heading_rad);
  const auto toRobot = [&](const Eigen::Vector2d& p) {
    const Eigen::Vector2d d = p - Eigen::Vector2d(pose.x_m, pose.y_m);
    return Eigen::Vector2d(c * d.x() + s * d.y(), -s * d.x() + c * d.y());
  };
  SyntheticScene scene;
  scene.line_width_m = field.line_width_m;
  for (const auto& l : model.lines) scene.segments.push_back({toRobot(l.a), toRobot(l.b)});
  scene.rings.push_back({toRobot(model.centre_circle_centre), model.centre_circle_radius_m});
  const double arm = field.penalty_mark_size_m / 2;
  for (const auto& m : model.penalty_marks) {
    scene.segments.push_back({toRobot(m - Eigen::Vector2d(arm, 0)), toRobot(m + Eigen::Vector2d(arm, 0))});
    scene.segments.push_back({toRobot(m - Eigen::Vector2d(0, arm)), toRobot(m + Eigen::Vector2d(0, arm))});
  }
  return scene;
}

inline bool painted(const SyntheticScene& scene, const Eigen::Vector2d& p) {
  const double hw = scene.line_width_m / 2;
  for (const auto& sg : scene.segments) {
    // Cheap rejection by the strip's bounding box.
    if (p.x() < std::min(sg.a.x(), sg.b.x()) - hw || p.x() > std::max(sg.a.x(), sg.b.x()) + hw ||
        p.y() < std::min(sg.a.y(), sg.b.y()) - hw || p.y() > std::max(sg.a.y(), sg.b.y()) + hw) {
      continue;
    }
    const Eigen::Vector2d ab = sg.b - sg.a;
    const double len = ab.norm();
    const Eigen::Vector2d u = ab / len;
    const double t = (p - sg.a).dot(u);
    // A strip reaches half a line width past its end points, so corners are filled.
    if (t < -hw || t > len + hw) continue;
    if (std::abs((p - sg.a).dot(Eigen::Vector2d(-u.y(), u.x()))) <= hw) return true;
  }
  for (const auto& r : scene.rings) {
    const Eigen::Vector2d d = p - r.centre;
    if (std::abs(d.x()) > r.radius_m + hw || std::abs(d.y()) > r.radius_m + hw) continue;
    if (std::abs(d.norm() - r.radius_m) <= hw) return true;
  }
  return false;
}

inline GrayImage renderScene(const CameraModel& camera, const SyntheticScene& scene) {
  const int w = camera.width(), h = camera.height();
  GrayImage image(w, h);
  std::mt19937_64 rng(scene.seed);
  std::normal_distribution<double> noise(0, scene.pixel_noise);
  std::uniform_real_distribution<double> phase(0, 6.283);
  const double p1 = phase(rng), p2 = phase(rng), p3 = phase(rng);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      // The carpet's texture from the pixel's centre; paint coverage from 2×2 rays.
      const auto centre = camera.pixelToGround({x + 0.5, y + 0.5});
      const double carpet =
          centre ? scene.carpet + scene.texture * (std::sin(centre->x() * 7.1 + p2) * std::cos(centre->y() * 5.3 + p3))
                 : scene.carpet;
      double sum = 0;
      for (int sy = 0; sy < 2; ++sy) {
        for (int sx = 0; sx < 2; ++sx) {
          const Eigen::Vector2d px(x + 0.25 + 0.5 * sx, y + 0.25 + 0.5 * sy);
          const auto g = camera.pixelToGround(px);
          if (!g || g->x() > scene.carpet_edge_m) {
            // The hall: large blocks of varying brightness.
            const int bx = static_cast<int>(x / 24), by = static_cast<int>(y / 24);
            sum += scene.background + 40 * std::sin(bx * 1.7 + by * 2.3 + p1);
            continue;
          }
          sum += painted(scene, *g) ? scene.paint : carpet;
        }
      }
      const double light = 1.0 - scene.gradient * x / w;
      const double v = (sum / 4) * light + noise(rng);
      image.at(x, y) = static_cast<std::uint8_t>(std::clamp(std::lround(v), 0L, 255L));
    }
  }
  return image;
}

// Adds Gaussian sensor noise of `sigma` gray levels to every pixel (seeded; clamped, then truncated).
inline void addNoise(GrayImage& image, double sigma, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0, sigma);
  for (int y = 0; y < image.height(); ++y) {
    for (int x = 0; x < image.width(); ++x) {
      image.at(x, y) = static_cast<std::uint8_t>(std::clamp(image.at(x, y) + noise(rng), 0.0, 255.0));
    }
  }
}

// Pure noise on a carpet (no markings).
inline GrayImage noiseImage(int w, int h, double mean, double sigma, std::uint64_t seed) {
  GrayImage image(w, h);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(mean, sigma);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      image.at(x, y) = static_cast<std::uint8_t>(std::clamp(std::lround(noise(rng)), 0L, 255L));
    }
  }
  return image;
}

inline CameraModel testCamera(double pitch_deg, int width = 640, int height = 480,
                              double height_m = 0.5) {
  CameraPose pose;
  pose.x_m = 0.05;
  pose.height_m = height_m;
  pose.pitch_rad = pitch_deg * 3.14159265358979323846 / 180;
  return CameraModel(
      CameraIntrinsics::fromHorizontalFov(width, height, 60.9 * 3.14159265358979323846 / 180), pose);
}

}  // namespace colorfree::test
