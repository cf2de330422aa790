#pragma once
// Drawn test scenes for the robot stages and the robot training kinds: a dark noisy carpet and
// robots drawn as bright legs and a body where a camera 0.5 m high, pitched 14 degrees, sees them.

#include <opencv2/imgproc.hpp>

#include <Eigen/Core>
#include <algorithm>
#include <cstdint>
#include <numbers>
#include <random>

#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/field_dimensions.h"
#include "colorfree/perception/image.h"

namespace colorfree {

inline CameraModel testCamera() {
  CameraPose pose;
  pose.height_m = 0.5;
  pose.pitch_rad = 14 * std::numbers::pi / 180;
  return CameraModel(CameraIntrinsics::fromHorizontalFov(640, 480, 60.9 * std::numbers::pi / 180), pose);
}

// Dark, slightly noisy carpet.
inline GrayImage carpet(std::uint64_t seed, int level = 60) {
  GrayImage img(640, 480);
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0, 3);
  for (int y = 0; y < 480; ++y)
    for (int x = 0; x < 640; ++x)
      img.at(x, y) = static_cast<std::uint8_t>(std::clamp(level + noise(rng), 0.0, 255.0));
  return img;
}

inline cv::Mat wrap(GrayImage& img) { return cv::Mat(img.height(), img.width(), CV_8UC1, img.data()); }

// A standing NAO's height and width in pixels with its feet at `feet_px` (FieldDimensions' sizes).
struct RobotSizePx {
  double h, w;
};
inline RobotSizePx robotSizePx(const CameraModel& cam, const Eigen::Vector2d& feet_px) {
  const FieldDimensions field = FieldDimensions::loadDefault();
  const double h = *cam.robotHeightPx(feet_px, field.robot_height_m);
  return {h, h * field.robot_width_m / field.robot_height_m};
}

// Two bright legs and the body of a robot standing at `ground` (robot frame), drawn as the camera
// sees them. The legs end where a NAO's do: its hips stand 0.25 m high (thigh 0.1 m, tibia 0.103 m,
// ankle 0.045 m) of its 0.574 m, the pelvis' lower edge between the thighs at about 0.37 of the
// height.
inline Eigen::Vector2d drawRobot(GrayImage& img, const CameraModel& cam, const Eigen::Vector2d& ground) {
  const Eigen::Vector2d feet = *cam.robotToPixel({ground.x(), ground.y(), 0});
  const auto [h, w] = robotSizePx(cam, feet);
  constexpr double kCrotchHeightFraction = 0.37;
  cv::Mat m = wrap(img);
  for (double side : {-0.3, 0.3}) {
    const double cx = feet.x() + side * w;
    cv::rectangle(m, cv::Point(int(cx - 0.12 * w), int(feet.y() - kCrotchHeightFraction * h)),
                  cv::Point(int(cx + 0.12 * w), int(feet.y()) - 1), cv::Scalar(200), cv::FILLED);
  }
  cv::rectangle(m, cv::Point(int(feet.x() - 0.45 * w), int(feet.y() - h)),
                cv::Point(int(feet.x() + 0.45 * w), int(feet.y() - kCrotchHeightFraction * h)),
                cv::Scalar(210), cv::FILLED);
  return feet;
}

}  // namespace colorfree
