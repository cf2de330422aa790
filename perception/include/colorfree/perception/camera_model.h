#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <string>

namespace colorfree {

/// Pinhole intrinsics in pixels. Pixel centres are at integer + 0.5 (the top-left pixel's
/// centre is (0.5, 0.5)); x right, y down.
struct CameraIntrinsics {
  int width_px = 640;
  int height_px = 480;
  double focal_x_px = 0;
  double focal_y_px = 0;
  double center_x_px = 320;
  double center_y_px = 240;

  /// Square pixels, principal point at the image centre, from the horizontal field of view.
  static CameraIntrinsics fromHorizontalFov(int width_px, int height_px, double fov_horizontal_rad);
  double horizontalFov() const;
  double verticalFov() const;
};

/// Camera pose relative to the ground under the robot, as a team's kinematics gives it.
/// Robot frame: origin on the ground below the torso, x forward, y left, z up.
/// Yaw turns left about z, pitch is positive looking down (as the NAO's HeadPitch), roll turns
/// about the viewing axis.
struct CameraPose {
  double x_m = 0;
  double y_m = 0;
  double height_m = 0.5;
  double roll_rad = 0;
  double pitch_rad = 0;
  double yaw_rad = 0;
};

/// A calibrated camera above the ground plane: projects between pixels and points in the robot
/// frame. Camera (optical) frame: x right, y down, z forward.
class CameraModel {
 public:
  CameraModel() = default;
  /// Throws colorfree::Error when the intrinsics or the pose are impossible (zero or NaN focal
  /// length, empty image, a camera at or below the ground).
  CameraModel(const CameraIntrinsics& intrinsics, const Eigen::Isometry3d& camera_to_robot);
  CameraModel(const CameraIntrinsics& intrinsics, const CameraPose& pose);

  /// Reads a camera file (YAML, keys documented in docs/camera_file.md); errors name the file.
  static CameraModel load(const std::string& path);
  /// Writes the same keys `load` reads.
  void save(const std::string& path) const;

  const CameraIntrinsics& intrinsics() const { return intrinsics_; }
  const Eigen::Isometry3d& cameraToRobot() const { return camera_to_robot_; }
  int width() const { return intrinsics_.width_px; }
  int height() const { return intrinsics_.height_px; }

  /// Unit ray through a pixel, in the robot frame.
  Eigen::Vector3d pixelRay(const Eigen::Vector2d& pixel) const;
  /// Where the ray through `pixel` meets the plane z = height_m (robot frame); empty when the ray
  /// does not go down to it (at or above the horizon for height 0).
  std::optional<Eigen::Vector2d> pixelToGround(const Eigen::Vector2d& pixel,
                                               double height_m = 0) const;
  /// Projects a robot-frame point; empty when it is behind the camera (or on its plane).
  std::optional<Eigen::Vector2d> robotToPixel(const Eigen::Vector3d& point_in_robot) const;
  /// Image row of the horizon (the ground plane's vanishing line) at column x; empty when the
  /// camera looks straight down or up.
  std::optional<double> horizonY(double x) const;
  /// Pixel radius of a ball of radius `ball_radius_m` resting on the ground with its centre seen
  /// at `pixel`; empty above the horizon.
  std::optional<double> ballRadiusPx(const Eigen::Vector2d& pixel, double ball_radius_m) const;
  /// Pixel height of a standing robot of `robot_height_m` whose feet are at `feet_pixel`; empty
  /// above the horizon.
  std::optional<double> robotHeightPx(const Eigen::Vector2d& feet_pixel,
                                      double robot_height_m) const;
  /// The camera's optical centre in the robot frame.
  Eigen::Vector3d position() const { return camera_to_robot_.translation(); }

  /// How far the still scene moved in the image during the exposure, from the camera's own turn
  /// (pixels, at the image centre; zero when the camera was still or the motion is not known).
  /// A team gets it from its kinematics: the camera's angular velocity times the exposure time
  /// times the focal length (HeadYaw at 100 deg/s for 20 ms on a 560-px focal length: 19.5 px).
  const Eigen::Vector2d& exposureSmearPx() const { return exposure_smear_px_; }
  /// Throws colorfree::Error when a component is not finite or beyond 10,000 px.
  void setExposureSmearPx(const Eigen::Vector2d& smear_px);
  /// A rolling shutter reads the rows one after the other: how far the still scene moved in the
  /// image from the first row's reading to the last's, from the camera's own turn (pixels; zero
  /// for a global shutter, a still camera or when not known). The frame's time is the middle
  /// row's. A team gets it as the exposure smear, with the readout time for the exposure time.
  const Eigen::Vector2d& rollingShutterShiftPx() const { return rolling_shutter_shift_px_; }
  /// Throws colorfree::Error when a component is not finite or beyond 10,000 px.
  void setRollingShutterShiftPx(const Eigen::Vector2d& shift_px);
  /// Where a still point seen at `pixel` would have been seen at the frame's time: `pixel` less
  /// the shift the rows between the middle one and its own were read over (the pixel itself
  /// without a rolling-shutter shift).
  Eigen::Vector2d atFrameTime(const Eigen::Vector2d& pixel) const;

 private:
  void validate(const std::string& origin) const;

  CameraIntrinsics intrinsics_;
  Eigen::Isometry3d camera_to_robot_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d robot_to_camera_ = Eigen::Isometry3d::Identity();
  Eigen::Vector2d exposure_smear_px_ = Eigen::Vector2d::Zero();
  Eigen::Vector2d rolling_shutter_shift_px_ = Eigen::Vector2d::Zero();
};

/// Rotation from the optical frame (x right, y down, z forward) to a body frame (x forward,
/// y left, z up) looking along its x axis.
Eigen::Matrix3d opticalToBody();
/// camera_to_robot from a pose: translation, then yaw about z, pitch about y (down positive),
/// roll about the viewing axis.
Eigen::Isometry3d cameraToRobotFromPose(const CameraPose& pose);

}  // namespace colorfree
