#include "colorfree/groundtruth/world_state_json.h"

#include <gtest/gtest.h>

#include "colorfree/perception/error.h"

namespace colorfree {
namespace {

WorldState sampleState() {
  WorldState s;
  s.frame_index = 17;
  s.time_s = 17.0 / 30.0;
  s.observer = {-1.234567890123, 0.1 + 0.2, 2.0 / 3.0};
  s.observer_head_yaw_rad = 0.3;
  s.observer_head_pitch_rad = -0.1234;
  s.camera.name = "bottom";
  CameraPose pose;
  pose.height_m = 0.47;
  pose.pitch_rad = 0.69;
  pose.yaw_rad = 0.3;
  s.camera.model = CameraModel(CameraIntrinsics::fromHorizontalFov(320, 240, 1.0625), pose);
  s.camera.camera_to_field = robotToField(s.observer) * s.camera.model.cameraToRobot();
  RobotTruth r;
  r.index = 0;
  r.pose = {1.2, -0.4, 3.0};
  r.speed_mps = 0.12;
  r.walk_direction_rad = 3.0;
  r.posture = "walking";
  r.jersey_gray = 0.25;
  s.robots.push_back(r);
  r.index = 1;
  r.posture = "turning";
  r.turn_rate_radps = -0.5;
  s.robots.push_back(r);
  s.ball.present = true;
  s.ball.position_m = {0.1, 1e-17, 0.05};
  s.ball.velocity_mps = {-0.3, 0.7, 0};
  s.object_map.width = 2;
  s.object_map.height = 1;
  s.object_map.labels = {1, 4};
  return s;
}

void expectSameIsometry(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  EXPECT_EQ(a.matrix(), b.matrix());
}

TEST(WorldStateJsonTest, RoundTripIsExact) {
  const WorldState s = sampleState();
  const std::string line = worldStateToJsonLine(s);
  EXPECT_EQ(line.find('\n'), std::string::npos);
  const WorldState t = worldStateFromJson(nlohmann::json::parse(line), "truth.jsonl:1");
  EXPECT_EQ(t.frame_index, s.frame_index);
  EXPECT_EQ(t.time_s, s.time_s);
  EXPECT_EQ(t.observer.x_m, s.observer.x_m);
  EXPECT_EQ(t.observer.y_m, s.observer.y_m);
  EXPECT_EQ(t.observer.heading_rad, s.observer.heading_rad);
  EXPECT_EQ(t.observer_head_yaw_rad, s.observer_head_yaw_rad);
  EXPECT_EQ(t.observer_head_pitch_rad, s.observer_head_pitch_rad);
  EXPECT_EQ(t.camera.name, "bottom");
  const CameraIntrinsics& a = s.camera.model.intrinsics();
  const CameraIntrinsics& b = t.camera.model.intrinsics();
  EXPECT_EQ(a.width_px, b.width_px);
  EXPECT_EQ(a.height_px, b.height_px);
  EXPECT_EQ(a.focal_x_px, b.focal_x_px);
  EXPECT_EQ(a.focal_y_px, b.focal_y_px);
  EXPECT_EQ(a.center_x_px, b.center_x_px);
  EXPECT_EQ(a.center_y_px, b.center_y_px);
  expectSameIsometry(s.camera.model.cameraToRobot(), t.camera.model.cameraToRobot());
  expectSameIsometry(s.camera.camera_to_field, t.camera.camera_to_field);
  ASSERT_EQ(t.robots.size(), 2u);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_EQ(t.robots[i].index, s.robots[i].index);
    EXPECT_EQ(t.robots[i].pose.x_m, s.robots[i].pose.x_m);
    EXPECT_EQ(t.robots[i].pose.heading_rad, s.robots[i].pose.heading_rad);
    EXPECT_EQ(t.robots[i].speed_mps, s.robots[i].speed_mps);
    EXPECT_EQ(t.robots[i].walk_direction_rad, s.robots[i].walk_direction_rad);
    EXPECT_EQ(t.robots[i].turn_rate_radps, s.robots[i].turn_rate_radps);
    EXPECT_EQ(t.robots[i].posture, s.robots[i].posture);
    EXPECT_EQ(t.robots[i].jersey_gray, s.robots[i].jersey_gray);
  }
  EXPECT_TRUE(t.ball.present);
  EXPECT_EQ(t.ball.position_m, s.ball.position_m);
  EXPECT_EQ(t.ball.velocity_mps, s.ball.velocity_mps);
  EXPECT_EQ(t.ball.radius_m, s.ball.radius_m);
  // The object map's pixels are not in the JSON.
  EXPECT_TRUE(t.object_map.labels.empty());
  // Written again, the same text.
  EXPECT_EQ(worldStateToJsonLine(t), line);
}

TEST(WorldStateJsonTest, DefaultCameraModelIsNull) {
  const WorldState s;
  const nlohmann::json j = worldStateToJson(s);
  EXPECT_TRUE(j["camera"]["model"].is_null());
  const WorldState t = worldStateFromJson(j, "x");
  EXPECT_EQ(t.camera.model.intrinsics().focal_x_px, 0);
}

TEST(WorldStateJsonTest, ExtraKeysAreIgnored) {
  nlohmann::json j = worldStateToJson(sampleState());
  j["image"] = "frame_000017.png";
  EXPECT_EQ(worldStateFromJson(j, "x").frame_index, 17);
}

std::string errorOf(const nlohmann::json& j) {
  try {
    worldStateFromJson(j, "truth.jsonl:3");
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

TEST(WorldStateJsonTest, BadJsonNamesTheKey) {
  const nlohmann::json good = worldStateToJson(sampleState());
  nlohmann::json j = good;
  j.erase("time_s");
  EXPECT_EQ(errorOf(j), "truth.jsonl:3: 'time_s' is missing");
  j = good;
  j["robots"][1]["pose"]["x_m"] = "far";
  EXPECT_EQ(errorOf(j), "truth.jsonl:3: 'robots[1].pose.x_m' expected a number");
  j = good;
  j["ball"]["position_m"] = {1, 2};
  EXPECT_EQ(errorOf(j), "truth.jsonl:3: 'ball.position_m' expected [x, y, z]");
  j = good;
  j["camera"]["camera_to_field"]["rotation"][0][0] = 5.0;
  EXPECT_EQ(errorOf(j),
            "truth.jsonl:3: 'camera.camera_to_field.rotation' is not a rotation matrix");
  j = good;
  j["camera"]["model"]["focal_x_px"] = 0.0;
  EXPECT_NE(errorOf(j).find("truth.jsonl:3: 'camera.model':"), std::string::npos);
  EXPECT_NE(errorOf(nlohmann::json::array()).find("expected an object"), std::string::npos);
}

}  // namespace
}  // namespace colorfree
