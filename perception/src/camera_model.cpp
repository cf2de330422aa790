#include "colorfree/perception/camera_model.h"

#include <cmath>
#include <fstream>
#include <yaml-cpp/yaml.h>

#include "colorfree/perception/error.h"
#include "colorfree/perception/param_file.h"

namespace colorfree {

namespace {
constexpr double kPi = 3.14159265358979323846;
constexpr double kMinDirectionZ = 1e-9;
// The exposure smear's bound (a sanity check, not a limit met in use).
constexpr double kMaxSmearPx = 10000;
}  // namespace

CameraIntrinsics CameraIntrinsics::fromHorizontalFov(int width_px, int height_px,
                                                     double fov_horizontal_rad) {
  CameraIntrinsics k;
  k.width_px = width_px;
  k.height_px = height_px;
  k.focal_x_px = (width_px / 2.0) / std::tan(fov_horizontal_rad / 2);
  k.focal_y_px = k.focal_x_px;
  k.center_x_px = width_px / 2.0;
  k.center_y_px = height_px / 2.0;
  return k;
}

double CameraIntrinsics::horizontalFov() const { return 2 * std::atan(width_px / 2.0 / focal_x_px); }
double CameraIntrinsics::verticalFov() const { return 2 * std::atan(height_px / 2.0 / focal_y_px); }

Eigen::Matrix3d opticalToBody() {
  Eigen::Matrix3d r;
  // Columns: the optical x, y, z axes expressed in the body frame.
  r << 0, 0, 1,  //
      -1, 0, 0,  //
      0, -1, 0;
  return r;
}

Eigen::Isometry3d cameraToRobotFromPose(const CameraPose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(p.x_m, p.y_m, p.height_m);
  t.linear() = (Eigen::AngleAxisd(p.yaw_rad, Eigen::Vector3d::UnitZ()) *
                Eigen::AngleAxisd(p.pitch_rad, Eigen::Vector3d::UnitY()) *
                Eigen::AngleAxisd(p.roll_rad, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix() *
               opticalToBody();
  return t;
}

CameraModel::CameraModel(const CameraIntrinsics& intrinsics,
                         const Eigen::Isometry3d& camera_to_robot)
    : intrinsics_(intrinsics), camera_to_robot_(camera_to_robot) {
  validate("camera model");
  robot_to_camera_ = camera_to_robot_.inverse();
}

CameraModel::CameraModel(const CameraIntrinsics& intrinsics, const CameraPose& pose)
    : CameraModel(intrinsics, cameraToRobotFromPose(pose)) {}

void CameraModel::validate(const std::string& origin) const {
  const auto& k = intrinsics_;
  if (k.width_px <= 0 || k.height_px <= 0 || k.width_px > 8192 || k.height_px > 8192) {
    throw Error(origin + ": image size " + std::to_string(k.width_px) + "x" +
                std::to_string(k.height_px) + " is impossible");
  }
  for (double v : {k.focal_x_px, k.focal_y_px}) {
    if (!std::isfinite(v) || v <= 0) throw Error(origin + ": focal length must be positive");
  }
  for (double v : {k.center_x_px, k.center_y_px}) {
    if (!std::isfinite(v)) throw Error(origin + ": principal point is not a number");
  }
  if (!camera_to_robot_.matrix().allFinite()) throw Error(origin + ": camera pose is not finite");
  if (camera_to_robot_.translation().z() <= 0) {
    throw Error(origin + ": camera is at or below the ground (height " +
                std::to_string(camera_to_robot_.translation().z()) + " m)");
  }
}

namespace {
// A camera-motion shift in pixels, checked; `what` names it in the error.
Eigen::Vector2d checkedShiftPx(const Eigen::Vector2d& shift_px, const std::string& what) {
  if (!shift_px.allFinite() || shift_px.cwiseAbs().maxCoeff() > kMaxSmearPx) {
    throw Error("camera model: " + what + " must be finite and within 10000 px");
  }
  return shift_px;
}
}  // namespace

void CameraModel::setExposureSmearPx(const Eigen::Vector2d& smear_px) {
  exposure_smear_px_ = checkedShiftPx(smear_px, "exposure smear");
}

void CameraModel::setRollingShutterShiftPx(const Eigen::Vector2d& shift_px) {
  rolling_shutter_shift_px_ = checkedShiftPx(shift_px, "rolling shutter shift");
}

Eigen::Vector2d CameraModel::atFrameTime(const Eigen::Vector2d& pixel) const {
  // Row r, whose pixels' centres lie at y = r + 0.5, is read (y / height - 0.5) of the readout
  // after the frame's time (the middle row's).
  return pixel - (pixel.y() / intrinsics_.height_px - 0.5) * rolling_shutter_shift_px_;
}

CameraModel CameraModel::load(const std::string& path) {
  ParamFile f(path);
  CameraIntrinsics k;
  k.width_px = f.get<int>("width_px");
  k.height_px = f.get<int>("height_px");
  k.focal_x_px = f.get<double>("focal_x_px");
  k.focal_y_px = f.get<double>("focal_y_px");
  k.center_x_px = f.get<double>("center_x_px");
  k.center_y_px = f.get<double>("center_y_px");
  CameraPose p;
  p.x_m = f.getInRange("x_m", -10, 10);
  p.y_m = f.getInRange("y_m", -10, 10);
  p.height_m = f.get<double>("height_m");
  p.roll_rad = f.getInRange("roll_deg", -180, 180) * kPi / 180;
  p.pitch_rad = f.getInRange("pitch_deg", -90, 90) * kPi / 180;
  p.yaw_rad = f.getInRange("yaw_deg", -180, 180) * kPi / 180;
  // Optional pairs (zero when absent): the camera's own smear over the exposure and its shift
  // over a rolling shutter's readout.
  const auto optionalPair = [&](const std::string& x, const std::string& y) {
    if (!f.has(x) && !f.has(y)) return Eigen::Vector2d::Zero().eval();
    return Eigen::Vector2d(f.getInRange(x, -kMaxSmearPx, kMaxSmearPx),
                           f.getInRange(y, -kMaxSmearPx, kMaxSmearPx));
  };
  const Eigen::Vector2d smear = optionalPair("exposure_smear_x_px", "exposure_smear_y_px");
  const Eigen::Vector2d shift = optionalPair("rolling_shift_x_px", "rolling_shift_y_px");
  f.finish();
  CameraModel m;
  m.intrinsics_ = k;
  m.camera_to_robot_ = cameraToRobotFromPose(p);
  m.validate(path);
  m.robot_to_camera_ = m.camera_to_robot_.inverse();
  m.exposure_smear_px_ = smear;
  m.rolling_shutter_shift_px_ = shift;
  return m;
}

void CameraModel::save(const std::string& path) const {
  // Recover yaw, pitch, roll from R = Rz(yaw) Ry(pitch) Rx(roll) opticalToBody().
  const Eigen::Matrix3d r = camera_to_robot_.linear() * opticalToBody().transpose();
  const double pitch = std::asin(std::clamp(-r(2, 0), -1.0, 1.0));
  const double yaw = std::atan2(r(1, 0), r(0, 0));
  const double roll = std::atan2(r(2, 1), r(2, 2));
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << YAML::BeginMap;
  out << YAML::Key << "width_px" << YAML::Value << intrinsics_.width_px;
  out << YAML::Key << "height_px" << YAML::Value << intrinsics_.height_px;
  out << YAML::Key << "focal_x_px" << YAML::Value << intrinsics_.focal_x_px;
  out << YAML::Key << "focal_y_px" << YAML::Value << intrinsics_.focal_y_px;
  out << YAML::Key << "center_x_px" << YAML::Value << intrinsics_.center_x_px;
  out << YAML::Key << "center_y_px" << YAML::Value << intrinsics_.center_y_px;
  out << YAML::Key << "x_m" << YAML::Value << camera_to_robot_.translation().x();
  out << YAML::Key << "y_m" << YAML::Value << camera_to_robot_.translation().y();
  out << YAML::Key << "height_m" << YAML::Value << camera_to_robot_.translation().z();
  out << YAML::Key << "roll_deg" << YAML::Value << roll * 180 / kPi;
  out << YAML::Key << "pitch_deg" << YAML::Value << pitch * 180 / kPi;
  out << YAML::Key << "yaw_deg" << YAML::Value << yaw * 180 / kPi;
  if (!exposure_smear_px_.isZero(0)) {
    out << YAML::Key << "exposure_smear_x_px" << YAML::Value << exposure_smear_px_.x();
    out << YAML::Key << "exposure_smear_y_px" << YAML::Value << exposure_smear_px_.y();
  }
  if (!rolling_shutter_shift_px_.isZero(0)) {
    out << YAML::Key << "rolling_shift_x_px" << YAML::Value << rolling_shutter_shift_px_.x();
    out << YAML::Key << "rolling_shift_y_px" << YAML::Value << rolling_shutter_shift_px_.y();
  }
  out << YAML::EndMap;
  std::ofstream file(path);
  file << out.c_str() << "\n";
  if (!file) throw Error(path + ": cannot write camera file");
}

Eigen::Vector3d CameraModel::pixelRay(const Eigen::Vector2d& pixel) const {
  const auto& k = intrinsics_;
  const Eigen::Vector3d d_cam((pixel.x() - k.center_x_px) / k.focal_x_px,
                              (pixel.y() - k.center_y_px) / k.focal_y_px, 1.0);
  return (camera_to_robot_.linear() * d_cam).normalized();
}

std::optional<Eigen::Vector2d> CameraModel::pixelToGround(const Eigen::Vector2d& pixel,
                                                          double height_m) const {
  const Eigen::Vector3d d = pixelRay(pixel);
  const Eigen::Vector3d o = camera_to_robot_.translation();
  const double dz = height_m - o.z();
  // The ray must head towards the plane.
  if (d.z() * dz <= kMinDirectionZ * std::abs(dz)) return std::nullopt;
  const double t = dz / d.z();
  const Eigen::Vector3d p = o + t * d;
  return Eigen::Vector2d(p.x(), p.y());
}

std::optional<Eigen::Vector2d> CameraModel::robotToPixel(const Eigen::Vector3d& point) const {
  const Eigen::Vector3d c = robot_to_camera_ * point;
  if (c.z() <= 1e-9) return std::nullopt;
  const auto& k = intrinsics_;
  return Eigen::Vector2d(k.center_x_px + k.focal_x_px * c.x() / c.z(),
                         k.center_y_px + k.focal_y_px * c.y() / c.z());
}

std::optional<double> CameraModel::horizonY(double x) const {
  // A pixel is on the horizon when its ray is level: row 2 of R times the optical direction is 0.
  const Eigen::Matrix3d& r = camera_to_robot_.linear();
  const auto& k = intrinsics_;
  const double a = r(2, 0) / k.focal_x_px;
  const double b = r(2, 1) / k.focal_y_px;
  if (std::abs(b) < 1e-12) return std::nullopt;
  return k.center_y_px - (r(2, 2) + a * (x - k.center_x_px)) / b;
}

namespace {

// The ray through a pixel towards a horizontal plane `below` the camera (negative: the plane is
// under it), for the closed forms below, multiplied through by f_x f_y to spare divisions. With
// a and b the pixel's offsets from the principal point, the optical ray d = (a / f_x, b / f_y, 1)
// and g = R^T z (the robot frame's up in the optical frame): towards = f_x f_y (g . d) and
// length_sq = f_x^2 f_y^2 |d|^2. Empty when the unit ray does not head to the plane by more than
// kMinDirectionZ (pixelToGround's test).
struct PlaneRay {
  double a, b, towards, length_sq;
};

std::optional<PlaneRay> planeRay(const CameraIntrinsics& k, const Eigen::Isometry3d& camera_to_robot,
                                 const Eigen::Vector2d& pixel, double below) {
  const Eigen::Matrix3d& r = camera_to_robot.linear();
  PlaneRay ray;
  ray.a = pixel.x() - k.center_x_px;
  ray.b = pixel.y() - k.center_y_px;
  const double fxy = k.focal_x_px * k.focal_y_px;
  ray.towards = r(2, 0) * ray.a * k.focal_y_px + r(2, 1) * ray.b * k.focal_x_px + r(2, 2) * fxy;
  ray.length_sq = ray.a * ray.a * k.focal_y_px * k.focal_y_px +
                  ray.b * ray.b * k.focal_x_px * k.focal_x_px + fxy * fxy;
  const double down = ray.towards * below;
  if (down <= 0 || down * down <= kMinDirectionZ * kMinDirectionZ * below * below * ray.length_sq) {
    return std::nullopt;
  }
  return ray;
}

}  // namespace

std::optional<double> CameraModel::ballRadiusPx(const Eigen::Vector2d& pixel,
                                                double ball_radius_m) const {
  // Closed form (the ball proposer asks this per scan row and window): the centre's plane lies at
  // dist = below |d| / (g . d) along the unit ray (planeRay's terms), and a sphere of radius R seen
  // from dist subtends f_y tan(asin(R / dist)) = f_y R / sqrt(dist^2 - R^2). Empty, besides
  // planeRay's test, when the sphere is not in front of the camera (dist <= R).
  const double below = ball_radius_m - camera_to_robot_.translation().z();
  const auto ray = planeRay(intrinsics_, camera_to_robot_, pixel, below);
  if (!ray) return std::nullopt;
  const double towards = ray->towards;
  // (dist^2 - R^2) towards^2
  const double rest = below * below * ray->length_sq - ball_radius_m * ball_radius_m * towards * towards;
  if (rest <= 0) return std::nullopt;
  return intrinsics_.focal_y_px * ball_radius_m * std::abs(towards) / std::sqrt(rest);
}

std::optional<double> CameraModel::robotHeightPx(const Eigen::Vector2d& feet_pixel,
                                                 double robot_height_m) const {
  // Closed form, one division (the proposer asks this for every lit pixel its scan lines meet):
  // the ray meets the ground at t d with t = below / (g . d), and the head above it projects
  // through c = t d + h g, whose offset from the feet pixel is
  //   (h (g . d) / (below + h g_z (g . d))) (f_x g_x - a g_z, f_y g_y - b g_z),
  // that is h towards / n times the vector, with n = below f_x f_y + h g_z towards (planeRay's
  // terms). Empty, besides planeRay's test, when the head is not in front of the camera
  // (c_z = n / towards <= 1e-9, as robotToPixel).
  const auto& k = intrinsics_;
  const double below = -camera_to_robot_.translation().z();
  const auto ray = planeRay(k, camera_to_robot_, feet_pixel, below);
  if (!ray) return std::nullopt;
  const Eigen::Matrix3d& r = camera_to_robot_.linear();
  const double gx = r(2, 0), gy = r(2, 1), gz = r(2, 2);
  const double towards = ray->towards;
  const double n = below * k.focal_x_px * k.focal_y_px + robot_height_m * gz * towards;
  if (towards > 0 ? n <= 1e-9 * towards : n >= 1e-9 * towards) return std::nullopt;
  const double p = k.focal_x_px * gx - ray->a * gz, q = k.focal_y_px * gy - ray->b * gz;
  return std::abs(robot_height_m * towards / n) * std::sqrt(p * p + q * q);
}

}  // namespace colorfree
