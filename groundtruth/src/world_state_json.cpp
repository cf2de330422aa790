#include "colorfree/groundtruth/world_state_json.h"

#include <cmath>

#include "colorfree/perception/error.h"

namespace colorfree {
namespace {

using nlohmann::json;

json isometryToJson(const Eigen::Isometry3d& t) {
  json rotation = json::array();
  for (int r = 0; r < 3; ++r) {
    rotation.push_back({t.linear()(r, 0), t.linear()(r, 1), t.linear()(r, 2)});
  }
  const Eigen::Vector3d p = t.translation();
  return {{"rotation", rotation}, {"translation_m", {p.x(), p.y(), p.z()}}};
}

json vectorToJson(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

json poseToJson(const FieldPose& p) {
  return {{"x_m", p.x_m}, {"y_m", p.y_m}, {"heading_rad", p.heading_rad}};
}

// Strict access to one JSON object; `path` names the place in errors.
class Reader {
 public:
  Reader(const json& j, std::string path, const std::string& origin)
      : j_(j), path_(std::move(path)), origin_(origin) {
    if (!j_.is_object()) fail("", "expected an object");
  }

  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    std::string where = path_;
    if (!key.empty()) where += (where.empty() ? "" : ".") + key;
    throw Error(origin_ + ": " + (where.empty() ? "" : "'" + where + "' ") + what);
  }

  const json& at(const std::string& key) const {
    const auto it = j_.find(key);
    if (it == j_.end()) fail(key, "is missing");
    return *it;
  }

  double number(const json& v, const std::string& key) const {
    if (!v.is_number()) fail(key, "expected a number");
    const double d = v.get<double>();
    if (!std::isfinite(d)) fail(key, "is not a finite number");
    return d;
  }
  double number(const std::string& key) const { return number(at(key), key); }

  int integer(const std::string& key) const {
    const json& v = at(key);
    if (!v.is_number_integer()) fail(key, "expected an integer");
    return v.get<int>();
  }

  std::string string(const std::string& key) const {
    const json& v = at(key);
    if (!v.is_string()) fail(key, "expected a string");
    return v.get<std::string>();
  }

  bool boolean(const std::string& key) const {
    const json& v = at(key);
    if (!v.is_boolean()) fail(key, "expected true or false");
    return v.get<bool>();
  }

  Eigen::Vector3d vector3(const std::string& key) const {
    const json& v = at(key);
    if (!v.is_array() || v.size() != 3) fail(key, "expected [x, y, z]");
    return {number(v[0], key), number(v[1], key), number(v[2], key)};
  }

  Reader object(const std::string& key) const {
    return Reader(at(key), path_.empty() ? key : path_ + "." + key, origin_);
  }

  const json& raw() const { return j_; }
  const std::string& path() const { return path_; }
  const std::string& origin() const { return origin_; }

 private:
  const json& j_;
  std::string path_;
  const std::string& origin_;
};

Eigen::Isometry3d isometryFromJson(const Reader& r) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  const json& rot = r.at("rotation");
  if (!rot.is_array() || rot.size() != 3) r.fail("rotation", "expected 3 rows of 3 numbers");
  for (int i = 0; i < 3; ++i) {
    if (!rot[i].is_array() || rot[i].size() != 3)
      r.fail("rotation", "expected 3 rows of 3 numbers");
    for (int c = 0; c < 3; ++c) t.linear()(i, c) = r.number(rot[i][c], "rotation");
  }
  const Eigen::Matrix3d should_be_identity = t.linear() * t.linear().transpose();
  if (!should_be_identity.isIdentity(1e-6)) r.fail("rotation", "is not a rotation matrix");
  t.translation() = r.vector3("translation_m");
  return t;
}

FieldPose poseFromJson(const Reader& r) {
  return {r.number("x_m"), r.number("y_m"), r.number("heading_rad")};
}

}  // namespace

json worldStateToJson(const WorldState& s) {
  json j;
  j["frame_index"] = s.frame_index;
  j["time_s"] = s.time_s;
  j["observer"] = poseToJson(s.observer);
  j["observer_head_yaw_rad"] = s.observer_head_yaw_rad;
  j["observer_head_pitch_rad"] = s.observer_head_pitch_rad;

  json camera;
  camera["name"] = s.camera.name;
  const CameraIntrinsics& in = s.camera.model.intrinsics();
  // A default CameraModel (no focal length) is not a camera: it is written as null.
  if (in.focal_x_px > 0) {
    camera["model"] = {{"width_px", in.width_px},
                       {"height_px", in.height_px},
                       {"focal_x_px", in.focal_x_px},
                       {"focal_y_px", in.focal_y_px},
                       {"center_x_px", in.center_x_px},
                       {"center_y_px", in.center_y_px},
                       {"camera_to_robot", isometryToJson(s.camera.model.cameraToRobot())}};
  } else {
    camera["model"] = nullptr;
  }
  camera["camera_to_field"] = isometryToJson(s.camera.camera_to_field);
  j["camera"] = camera;

  json robots = json::array();
  for (const RobotTruth& r : s.robots) {
    robots.push_back({{"index", r.index},
                      {"pose", poseToJson(r.pose)},
                      {"speed_mps", r.speed_mps},
                      {"walk_direction_rad", r.walk_direction_rad},
                      {"turn_rate_radps", r.turn_rate_radps},
                      {"posture", r.posture},
                      {"jersey_gray", r.jersey_gray}});
  }
  j["robots"] = robots;
  j["ball"] = {{"present", s.ball.present},
               {"position_m", vectorToJson(s.ball.position_m)},
               {"velocity_mps", vectorToJson(s.ball.velocity_mps)},
               {"radius_m", s.ball.radius_m}};
  return j;
}

WorldState worldStateFromJson(const json& j, const std::string& origin) {
  const Reader r(j, "", origin);
  WorldState s;
  s.frame_index = r.integer("frame_index");
  s.time_s = r.number("time_s");
  s.observer = poseFromJson(r.object("observer"));
  s.observer_head_yaw_rad = r.number("observer_head_yaw_rad");
  s.observer_head_pitch_rad = r.number("observer_head_pitch_rad");

  const Reader cam = r.object("camera");
  s.camera.name = cam.string("name");
  if (!cam.at("model").is_null()) {
    const Reader m = cam.object("model");
    CameraIntrinsics in;
    in.width_px = m.integer("width_px");
    in.height_px = m.integer("height_px");
    in.focal_x_px = m.number("focal_x_px");
    in.focal_y_px = m.number("focal_y_px");
    in.center_x_px = m.number("center_x_px");
    in.center_y_px = m.number("center_y_px");
    const Eigen::Isometry3d camera_to_robot = isometryFromJson(m.object("camera_to_robot"));
    try {
      s.camera.model = CameraModel(in, camera_to_robot);
    } catch (const Error& e) {
      throw Error(origin + ": 'camera.model': " + e.what());
    }
  }
  s.camera.camera_to_field = isometryFromJson(cam.object("camera_to_field"));

  const json& robots = r.at("robots");
  if (!robots.is_array()) r.fail("robots", "expected a list");
  for (std::size_t i = 0; i < robots.size(); ++i) {
    const Reader rr(robots[i], "robots[" + std::to_string(i) + "]", origin);
    RobotTruth t;
    t.index = rr.integer("index");
    t.pose = poseFromJson(rr.object("pose"));
    t.speed_mps = rr.number("speed_mps");
    t.walk_direction_rad = rr.number("walk_direction_rad");
    t.turn_rate_radps = rr.number("turn_rate_radps");
    t.posture = rr.string("posture");
    t.jersey_gray = rr.number("jersey_gray");
    s.robots.push_back(t);
  }

  const Reader b = r.object("ball");
  s.ball.present = b.boolean("present");
  s.ball.position_m = b.vector3("position_m");
  s.ball.velocity_mps = b.vector3("velocity_mps");
  s.ball.radius_m = b.number("radius_m");
  return s;
}

std::string worldStateToJsonLine(const WorldState& state) { return worldStateToJson(state).dump(); }

}  // namespace colorfree
