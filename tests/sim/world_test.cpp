#include "colorfree/sim/world.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "colorfree/perception/error.h"
#include "colorfree/sim/mjcf_loader.h"
#include "test_support.h"

namespace colorfree::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

SceneSpec smallSpec(int robots = 0) {
  SceneSpec spec;
  spec.field = FieldDimensions::loadDefault();
  spec.robot_count = robots;
  spec.seed = 11;
  spec.max_width_px = 640;
  spec.max_height_px = 480;
  return spec;
}

// A field line as a rectangle on the ground: centre, direction, half length and half width.
struct LineRect {
  Eigen::Vector2d a, b;  // centre-line end points
  double half_width;
  bool contains(const Eigen::Vector2d& p) const {
    const Eigen::Vector2d d = (b - a).normalized();
    const double t = (p - a).dot(d);
    const double len = (b - a).norm();
    const double n = std::abs((p - a).x() * d.y() - (p - a).y() * d.x());
    return t >= -half_width && t <= len + half_width && n <= half_width;
  }
};

// The field's lines from the rule book, written here independently of the scene builder.
bool onFieldLine(const FieldDimensions& fd, const Eigen::Vector2d& p) {
  const double L = fd.halfLength(), W = fd.halfWidth(), h = fd.line_width_m / 2;
  std::vector<LineRect> rects = {
      {{-L, W}, {L, W}, h}, {{-L, -W}, {L, -W}, h}, {{0, -W}, {0, W}, h}};
  for (double s : {-1.0, 1.0}) {
    const double pa = s * (L - fd.penalty_area_length_m), pw = fd.penalty_area_width_m / 2;
    const double ga = s * (L - fd.goal_area_length_m), gw = fd.goal_area_width_m / 2;
    const double pm = s * (L - fd.penalty_mark_distance_m), arm = fd.penalty_mark_size_m / 2;
    rects.push_back({{s * L, -W}, {s * L, W}, h});
    rects.push_back({{pa, -pw}, {pa, pw}, h});
    rects.push_back({{pa, pw}, {s * L, pw}, h});
    rects.push_back({{pa, -pw}, {s * L, -pw}, h});
    rects.push_back({{ga, -gw}, {ga, gw}, h});
    rects.push_back({{ga, gw}, {s * L, gw}, h});
    rects.push_back({{ga, -gw}, {s * L, -gw}, h});
    rects.push_back({{pm - arm, 0}, {pm + arm, 0}, 0});
    rects.back().half_width = h;
    rects.push_back({{pm, -arm}, {pm, arm}, h});
  }
  // The penalty cross's arms end at the mark size, not beyond it.
  for (auto& r : rects) {
    if ((r.b - r.a).norm() <= fd.penalty_mark_size_m + 1e-9 && r.contains(p)) {
      const Eigen::Vector2d d = (r.b - r.a).normalized();
      const double t = (p - r.a).dot(d);
      if (t >= 0 && t <= (r.b - r.a).norm()) return true;
    } else if (r.contains(p)) {
      return true;
    }
  }
  return std::abs(p.norm() - fd.centre_circle_diameter_m / 2) <= h;
}

struct LineCheck {
  int compared = 0, line_pixels = 0, wrong = 0;
};

// Compares the object map's line and carpet pixels with the lines `model` projects: a pixel may
// disagree only within one pixel of a predicted line edge.
LineCheck checkLines(const RenderOutput& out, const CameraModel& model, const FieldPose& observer,
                     const FieldDimensions& fd, int stop_after_wrong = 1 << 30) {
  const int w = out.object_map.width, h = out.object_map.height;
  const Eigen::Isometry3d robot_to_field = robotToField(observer);
  // Predicted label per pixel: 1 line, 0 carpet, -1 not on the ground.
  std::vector<int> predicted(std::size_t(w) * h, -1);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const auto g = model.pixelToGround(Eigen::Vector2d(x + 0.5, y + 0.5));
      if (!g) continue;
      const Eigen::Vector3d f = robot_to_field * Eigen::Vector3d(g->x(), g->y(), 0);
      predicted[std::size_t(y) * w + x] = onFieldLine(fd, f.head<2>()) ? 1 : 0;
    }
  }
  LineCheck c;
  for (int y = 1; y < h - 1; ++y) {
    for (int x = 1; x < w - 1; ++x) {
      const auto label = out.object_map.at(x, y);
      if (label != kObjectCarpet && label != kObjectLine) continue;
      const int p = predicted[std::size_t(y) * w + x];
      if (p < 0) continue;
      ++c.compared;
      const int rendered = label == kObjectLine ? 1 : 0;
      c.line_pixels += rendered;
      if (rendered == p) continue;
      // A mismatch is allowed only within one pixel of a predicted edge: somewhere within a pixel
      // of this pixel's centre the prediction agrees with the render.
      bool near_edge = false;
      for (double dy = -1; dy <= 1 && !near_edge; dy += 0.125) {
        for (double dx = -1; dx <= 1 && !near_edge; dx += 0.125) {
          const auto g = model.pixelToGround(Eigen::Vector2d(x + 0.5 + dx, y + 0.5 + dy));
          if (!g) continue;
          const Eigen::Vector3d f = robot_to_field * Eigen::Vector3d(g->x(), g->y(), 0);
          near_edge = (onFieldLine(fd, f.head<2>()) ? 1 : 0) == rendered;
        }
      }
      if (!near_edge && ++c.wrong >= stop_after_wrong) return c;
    }
  }
  return c;
}

void expectLinesWhereProjected(World& world, const FieldPose& observer, NaoCamera camera,
                               const FieldDimensions& fd, int w, int h) {
  const RenderOutput out = world.render(camera, w, h);
  const CameraModel model = world.cameraModel(camera, w, h);
  const LineCheck c = checkLines(out, model, observer, fd);
  EXPECT_GT(c.compared, w * h / 4);
  EXPECT_GT(c.line_pixels, w * h / 800) << "too few line pixels to check the projection";
  EXPECT_EQ(c.wrong, 0)
      << "pixels more than a pixel away from where the camera model puts the lines";
  // The check sees a camera model that is off by two pixels.
  CameraIntrinsics shifted = model.intrinsics();
  shifted.center_x_px += 2;
  shifted.center_y_px += 2;
  EXPECT_GE(checkLines(out, CameraModel(shifted, model.cameraToRobot()), observer, fd, 50).wrong,
            50);
}

TEST(World, FieldLinesLandWhereTheCameraModelProjectsThem) {
  const SceneSpec spec = smallSpec();
  World world(spec);
  NaoState obs;
  // Looking at the penalty area, mark and goal area at an angle, and at the centre circle.
  obs.pose = {2.0, 0.9, -0.35};
  obs.posture.head_pitch = 0.3;
  world.setObserver(obs);
  expectLinesWhereProjected(world, obs.pose, NaoCamera::kTop, spec.field, 640, 480);
  // Close to the penalty area's corner for the bottom camera, full buffer and sub-viewport.
  obs.pose = {2.45, 1.7, 0.4};
  world.setObserver(obs);
  expectLinesWhereProjected(world, obs.pose, NaoCamera::kBottom, spec.field, 640, 480);
  expectLinesWhereProjected(world, obs.pose, NaoCamera::kBottom, spec.field, 320, 240);
  obs.pose = {-1.2, -0.4, 0.5};
  obs.posture.head_yaw = 0.2;
  obs.posture.head_pitch = 0.1;
  world.setObserver(obs);
  expectLinesWhereProjected(world, obs.pose, NaoCamera::kTop, spec.field, 640, 480);
  expectLinesWhereProjected(world, obs.pose, NaoCamera::kTop, spec.field, 320, 240);
}

TEST(World, BallIsRenderedWhereTheCameraModelProjectsIt) {
  const SceneSpec spec = smallSpec();
  World world(spec);
  NaoState obs;
  obs.pose = {-0.5, 0.3, 0.2};
  obs.posture.head_pitch = 0.25;
  world.setObserver(obs);
  const CameraModel camera = world.cameraModel(NaoCamera::kTop, 640, 480);
  const double r = spec.field.ballRadius();
  // Near the image centre a small sphere's silhouette is centred on its projected centre.
  for (const Eigen::Vector3d& ball_in_robot :
       {Eigen::Vector3d(1.4, 0.0, r), Eigen::Vector3d(1.2, 0.1, r),
        Eigen::Vector3d(2.0, -0.15, r)}) {
    const Eigen::Vector3d ball_in_field = robotToField(obs.pose) * ball_in_robot;
    world.setBall(ball_in_field, Eigen::Quaterniond::Identity());
    const RenderOutput out = world.render(NaoCamera::kTop, 640, 480);
    double sx = 0, sy = 0;
    int n = 0;
    for (int y = 0; y < 480; ++y) {
      for (int x = 0; x < 640; ++x) {
        if (out.object_map.at(x, y) != kObjectBall) continue;
        sx += x + 0.5;
        sy += y + 0.5;
        ++n;
      }
    }
    ASSERT_GT(n, 50);
    const Eigen::Vector2d projected = *camera.robotToPixel(ball_in_robot);
    EXPECT_NEAR(sx / n, projected.x(), 0.5);
    EXPECT_NEAR(sy / n, projected.y(), 0.5);
    // Its size is what the camera model expects for a ball on the ground.
    const double radius_px = *camera.ballRadiusPx(projected, r);
    EXPECT_NEAR(std::sqrt(n / kPi), radius_px, 0.05 * radius_px);
  }
}

TEST(World, CameraSitsInTheHeadAtTheNaoMounts) {
  World world(smallSpec());
  NaoState obs;
  obs.pose = {1, 2, 0.5};
  world.setObserver(obs);
  const CameraModel top = world.cameraModel(NaoCamera::kTop, 640, 480);
  const CameraModel bottom = world.cameraModel(NaoCamera::kBottom, 320, 240);
  // Standing NAO: cameras about half a metre up, the bottom one 46 mm lower, 8 mm further back.
  EXPECT_NEAR(top.position().z() - bottom.position().z(), 0.06364 - 0.01774, 1e-6);
  EXPECT_NEAR(top.position().x() - bottom.position().x(), 0.05871 - 0.05071, 1e-6);
  EXPECT_GT(top.position().z(), 0.4);
  EXPECT_LT(top.position().z(), 0.6);
  // The optical axes point down by the mount pitches (head level).
  const Eigen::Vector3d top_axis = top.cameraToRobot().linear().col(2);
  const Eigen::Vector3d bottom_axis = bottom.cameraToRobot().linear().col(2);
  EXPECT_NEAR(std::asin(-top_axis.z()), 1.2 * kPi / 180, 1e-6);
  EXPECT_NEAR(std::asin(-bottom_axis.z()), 39.7 * kPi / 180, 1e-6);
  EXPECT_NEAR(top.intrinsics().horizontalFov(), 60.9 * kPi / 180, 1e-9);
  EXPECT_NEAR(bottom.intrinsics().verticalFov(), 47.6 * kPi / 180, 0.01);
  const Eigen::Isometry3d expected_field = robotToField(obs.pose) * top.cameraToRobot();
  EXPECT_TRUE(world.cameraToField(NaoCamera::kTop).isApprox(expected_field, 1e-9));
}

TEST(World, SameFrameRenderedTwiceIsByteIdentical) {
  SceneSpec spec = smallSpec(2);
  spec.lighting = LightingPreset::kDirectional;
  const auto render = [](World& world) {
    NaoState obs;
    obs.pose = {0.5, 0.2, 0.1};
    obs.posture = walkPosture(0.3, 0.15);
    world.setObserver(obs);
    NaoState r;
    r.pose = {1.6, 0.3, 2.5};
    r.posture = walkPosture(0.7, 0.1);
    world.setRobot(0, r);
    r.pose = {2.5, -0.6, 1.0};
    world.setRobot(1, r);
    world.setBall(Eigen::Vector3d(1.2, -0.2, 0.05), Eigen::Quaterniond::Identity());
    return world.render(NaoCamera::kTop, 320, 240);
  };
  World a(spec);
  const RenderOutput first = render(a);
  const RenderOutput second = render(a);
  EXPECT_EQ(first.gray.pixels(), second.gray.pixels());
  EXPECT_EQ(first.object_map.labels, second.object_map.labels);
  World b(spec);
  const RenderOutput other_world = render(b);
  EXPECT_EQ(first.gray.pixels(), other_world.gray.pixels());
  EXPECT_EQ(first.object_map.labels, other_world.object_map.labels);
  // The seed changes the textures: a different seed gives a different picture.
  spec.seed = 12;
  World c(spec);
  EXPECT_NE(first.gray.pixels(), render(c).gray.pixels());
}

// Labels and grey values of robot 0's lowest rows (its feet) seen from 1.2 m.
struct FeetView {
  std::vector<std::uint8_t> mask, gray;
  int pixels = 0;
};

FeetView renderFeet(World& world, double heading, int feet_top, int feet_bottom) {
  NaoState r;
  r.pose = {1.2, 0, heading};
  world.setRobot(0, r);
  const RenderOutput out = world.render(NaoCamera::kTop, 640, 480);
  FeetView v;
  for (int y = feet_top; y < feet_bottom; ++y) {
    for (int x = 0; x < 640; ++x) {
      const bool robot = out.object_map.at(x, y) == kObjectRobotBase;
      v.mask.push_back(robot ? 1 : 0);
      v.gray.push_back(out.gray.at(x, y));
      v.pixels += robot ? 1 : 0;
    }
  }
  return v;
}

TEST(World, RobotTurnedBy90DegreesLooksDifferentAtTheFeet) {
  World world(smallSpec(1));
  NaoState obs;
  obs.posture.head_pitch = 0.35;
  world.setObserver(obs);
  // Where the feet are: rows from the sole's ground line up to the ankle, from the camera model.
  const CameraModel camera = world.cameraModel(NaoCamera::kTop, 640, 480);
  const double near_y = camera.robotToPixel(Eigen::Vector3d(1.2 - 0.1, 0, 0))->y();
  const double ankle_y = camera.robotToPixel(Eigen::Vector3d(1.2 + 0.1, 0, 0.05))->y();
  const int top = int(std::floor(ankle_y)), bottom = int(std::ceil(near_y)) + 1;
  ASSERT_LT(top, bottom);
  const FeetView front = renderFeet(world, kPi, top, bottom);
  const FeetView side = renderFeet(world, kPi / 2, top, bottom);
  const FeetView back = renderFeet(world, 0, top, bottom);
  const FeetView front_again = renderFeet(world, kPi, top, bottom);
  ASSERT_GT(front.pixels, 200);
  const auto differing = [](const std::vector<std::uint8_t>& a,
                            const std::vector<std::uint8_t>& b) {
    int n = 0;
    for (std::size_t i = 0; i < a.size(); ++i) n += a[i] != b[i] ? 1 : 0;
    return n;
  };
  // Front and side: different silhouettes (two soles side by side vs. one long sole).
  EXPECT_GT(differing(front.mask, side.mask), front.pixels / 5);
  // Front and back: similar outline, different look (rounded toes vs. square dark heels).
  double grey_difference = 0;
  int both = 0;
  for (std::size_t i = 0; i < front.mask.size(); ++i) {
    if (front.mask[i] && back.mask[i]) {
      grey_difference += std::abs(int(front.gray[i]) - int(back.gray[i]));
      ++both;
    }
  }
  ASSERT_GT(both, 100);
  EXPECT_GT(grey_difference / both, 10.0);
  EXPECT_EQ(differing(front.mask, front_again.mask), 0);
  EXPECT_EQ(front.gray, front_again.gray);
}

TEST(World, BottomCameraSeesTheOwnBodyWhenTheHeadLooksDown) {
  World world(smallSpec());
  NaoState obs;
  obs.posture.head_pitch = 0.45;
  world.setObserver(obs);
  const RenderOutput down = world.render(NaoCamera::kBottom, 320, 240);
  const auto own = [](const ObjectMap& m) {
    return std::count(m.labels.begin(), m.labels.end(), std::uint16_t(kObjectOwnBody));
  };
  EXPECT_GT(own(down.object_map), 320 * 240 / 20);
  // The own body is at the bottom of the image, not the top.
  int bottom_half = 0;
  for (int y = 120; y < 240; ++y) {
    for (int x = 0; x < 320; ++x) bottom_half += down.object_map.at(x, y) == kObjectOwnBody;
  }
  EXPECT_GT(bottom_half, own(down.object_map) * 9 / 10);
  obs.posture.head_pitch = -0.3;
  world.setObserver(obs);
  EXPECT_EQ(own(world.render(NaoCamera::kTop, 320, 240).object_map), 0);
}

TEST(World, LightingPresetsAndScaleChangeTheBrightness) {
  const auto carpet_mean = [](World& world) {
    NaoState obs;
    obs.posture.head_pitch = 0.3;
    world.setObserver(obs);
    const RenderOutput out = world.render(NaoCamera::kTop, 320, 240);
    double sum = 0;
    int n = 0;
    for (std::size_t i = 0; i < out.gray.pixels().size(); ++i) {
      if (out.object_map.labels[i] == kObjectCarpet) {
        sum += out.gray.pixels()[i];
        ++n;
      }
    }
    return sum / std::max(1, n);
  };
  SceneSpec spec = smallSpec();
  World normal(spec);
  const double normal_mean = carpet_mean(normal);
  normal.setLighting({0.5});
  EXPECT_LT(carpet_mean(normal), normal_mean * 0.7);
  spec.lighting = LightingPreset::kDim;
  World dim(spec);
  EXPECT_LT(carpet_mean(dim), normal_mean * 0.8);
  spec.lighting = LightingPreset::kOverexposed;
  World bright(spec);
  EXPECT_GT(carpet_mean(bright), normal_mean * 1.4);
}

TEST(World, TenNaosEachWithItsOwnLabel) {
  World world(smallSpec(9));
  NaoState obs;
  obs.posture.head_pitch = 0.15;
  world.setObserver(obs);
  // Nine robots in a row across the view, 2.5 m ahead.
  for (int i = 0; i < 9; ++i) {
    NaoState r;
    r.pose = {2.5, (i - 4) * 0.32, 0.4 * i};
    r.posture = walkPosture(0.1 * i, 0.1);
    world.setRobot(i, r);
  }
  const RenderOutput out = world.render(NaoCamera::kTop, 320, 240);
  const CameraModel camera = world.cameraModel(NaoCamera::kTop, 320, 240);
  for (int i = 0; i < 9; ++i) {
    // The robot's label at its own place: around its torso's projection.
    const Eigen::Vector2d torso = *camera.robotToPixel(Eigen::Vector3d(2.5, (i - 4) * 0.32, 0.3));
    int hits = 0;
    for (int dy = -3; dy <= 3; ++dy) {
      for (int dx = -3; dx <= 3; ++dx) {
        hits += out.object_map.at(int(torso.x()) + dx, int(torso.y()) + dy) == kObjectRobotBase + i;
      }
    }
    EXPECT_GT(hits, 10) << "robot " << i;
  }
}

TEST(World, ImpossibleSpecsAndCallsGiveErrors) {
  const auto fails = [](const SceneSpec& spec) { EXPECT_THROW(World w(spec), Error); };
  SceneSpec spec = smallSpec();
  spec.robot_count = 10;
  fails(spec);
  spec = smallSpec(2);
  spec.jersey_gray = {0.5, 1.5};
  fails(spec);
  spec = smallSpec();
  spec.field.field_length_m = std::numeric_limits<double>::quiet_NaN();
  fails(spec);
  spec = smallSpec();
  spec.field.penalty_area_width_m = 7;  // wider than the field
  fails(spec);
  spec = smallSpec();
  spec.max_width_px = 0;
  fails(spec);
  spec = smallSpec();
  spec.multisamples = -1;
  fails(spec);
  spec = smallSpec();
  spec.shadow_map_px = 10;
  fails(spec);
  spec = smallSpec();
  spec.camera_horizontal_fov_deg = 200;
  fails(spec);

  World world(smallSpec(1));
  EXPECT_THROW(world.render(NaoCamera::kTop, 1280, 960), Error);
  EXPECT_THROW(world.setRobot(1, NaoState{}), Error);
  NaoState bad;
  bad.pose.x_m = std::numeric_limits<double>::infinity();
  EXPECT_THROW(world.setObserver(bad), Error);
  EXPECT_THROW(world.setLighting({-1}), Error);
  EXPECT_THROW(lightingPresetFromName("sunny"), Error);
}

TEST(MjcfLoader, ModelsMujocoRejectsGiveErrorsWithItsMessage) {
  try {
    loadMjcf("<mujoco><worldbody><geom type=\"sphere\" size=\"-1\"/></worldbody>", {},
             "broken.xml");
    FAIL() << "a truncated model was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("broken.xml"), std::string::npos) << e.what();
  }
  // A texture file that is not there.
  EXPECT_THROW(loadMjcf(R"(<mujoco><asset><texture name="t" type="2d" file="missing.tex"/></asset>
                           <worldbody/></mujoco>)",
                        {}, "missing.xml"),
               Error);
  // A texture file whose size does not match its header.
  EXPECT_THROW(loadMjcf(R"(<mujoco><asset><texture name="t" type="2d" file="bad.tex"/></asset>
                           <worldbody/></mujoco>)",
                        {{"bad.tex", {4, 0, 0, 0, 4, 0, 0, 0, 1, 2, 3}}}, "bad.xml"),
               Error);
  // A valid model loads.
  EXPECT_NE(loadMjcf("<mujoco><worldbody><geom type=\"sphere\" size=\"1\"/></worldbody></mujoco>",
                     {}, "ok.xml"),
            nullptr);
}

}  // namespace
}  // namespace colorfree::sim
