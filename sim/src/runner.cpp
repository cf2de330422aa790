#include "colorfree/sim/runner.h"

#include <numbers>
#include <random>
#include <utility>
#include <vector>

#include "colorfree/perception/error.h"

namespace colorfree::sim {

SceneSpec sceneSpecFor(const CaseSettings& settings) {
  SceneSpec spec;
  spec.field = FieldDimensions::loadDefault();
  spec.robot_count = static_cast<int>(settings.robots.size());
  for (const RobotSpec& r : settings.robots) spec.jersey_gray.push_back(r.jersey_gray);
  spec.ball = settings.ball.has_value();
  spec.lighting = settings.lighting.preset;
  spec.seed = settings.seed;
  spec.shadows = settings.shadows;
  spec.multisamples = settings.multisamples;
  spec.max_width_px = std::max(spec.max_width_px, settings.width_px);
  spec.max_height_px = std::max(spec.max_height_px, settings.height_px);
  spec.observer_jersey_gray = settings.observer.jersey_gray;
  spec.camera_horizontal_fov_deg = settings.camera_horizontal_fov_deg;
  return spec;
}

bool sameScene(const SceneSpec& a, const SceneSpec& b) {
  return a.robot_count == b.robot_count && a.jersey_gray == b.jersey_gray && a.ball == b.ball &&
         a.lighting == b.lighting && a.seed == b.seed && a.shadows == b.shadows &&
         a.multisamples == b.multisamples && a.max_width_px == b.max_width_px &&
         a.max_height_px == b.max_height_px && a.observer_jersey_gray == b.observer_jersey_gray &&
         a.camera_horizontal_fov_deg == b.camera_horizontal_fov_deg;
}

double frameTime(const CaseSettings& settings, int frame_index) {
  return frame_index / settings.frame_rate_hz;
}

Eigen::Quaterniond initialBallOrientation(std::uint64_t seed) {
  std::mt19937_64 rng(seed ^ 0xBA11BA11BA11BA11ULL);
  constexpr double kScale = 1.0 / 9007199254740992.0;
  // A uniformly random rotation (Shoemake) from three uniform numbers.
  const double u1 = static_cast<double>(rng() >> 11) * kScale;
  const double u2 = static_cast<double>(rng() >> 11) * kScale * 2 * std::numbers::pi;
  const double u3 = static_cast<double>(rng() >> 11) * kScale * 2 * std::numbers::pi;
  const double a = std::sqrt(1 - u1), b = std::sqrt(u1);
  Eigen::Quaterniond q(a * std::sin(u2), a * std::cos(u2), b * std::sin(u3), b * std::cos(u3));
  return q.normalized();
}

WorldState scenarioStateAt(const CaseSettings& settings, int frame_index) {
  WorldState s;
  s.frame_index = frame_index;
  s.time_s = frameTime(settings, frame_index);
  const RobotMotionState observer =
      robotMotionAt(settings.observer.pose, settings.observer.motion, s.time_s);
  s.observer = observer.pose;
  const HeadAngles head = headAt(settings.observer.head, s.time_s);
  s.observer_head_yaw_rad = head.yaw_rad;
  s.observer_head_pitch_rad = head.pitch_rad;
  s.camera.name = settings.camera == NaoCamera::kTop ? "top" : "bottom";
  for (std::size_t i = 0; i < settings.robots.size(); ++i) {
    const RobotSpec& spec = settings.robots[i];
    const RobotMotionState m = robotMotionAt(spec.pose, spec.motion, s.time_s);
    RobotTruth t;
    t.index = static_cast<int>(i);
    t.pose = m.pose;
    t.speed_mps = m.speed_mps;
    t.walk_direction_rad = m.walk_direction_rad;
    t.turn_rate_radps = m.turn_rate_radps;
    t.posture = motionKindName(spec.motion.kind);
    t.jersey_gray = spec.jersey_gray;
    s.robots.push_back(t);
  }
  const double radius = settings.ball_radius_m;
  s.ball.radius_m = radius;
  if (settings.ball) {
    const BallMotionState b =
        ballAt(*settings.ball, radius, initialBallOrientation(settings.seed), s.time_s);
    s.ball.present = true;
    s.ball.position_m = b.position_m;
    s.ball.velocity_mps = b.velocity_mps;
  }
  return s;
}

ScenarioRunner::ScenarioRunner(Scenario scenario, RendererFactory factory)
    : scenario_(std::move(scenario)), factory_(std::move(factory)) {
  if (!factory_) throw Error("scenario runner: no renderer");
}

const ScenarioCase& ScenarioRunner::scenarioCase(int case_index) const {
  if (case_index < 0 || case_index >= caseCount()) {
    throw Error(scenario_.path + ": no case " + std::to_string(case_index) + " (the scenario has " +
                std::to_string(caseCount()) + ")");
  }
  return scenario_.cases[static_cast<std::size_t>(case_index)];
}

SceneRenderer& ScenarioRunner::rendererFor(const CaseSettings& settings) {
  const SceneSpec spec = sceneSpecFor(settings);
  if (!renderer_ || !sameScene(spec, renderer_spec_)) {
    renderer_.reset();  // one GL context at a time
    renderer_ = factory_(spec);
    renderer_spec_ = spec;
  }
  return *renderer_;
}

double lightingScaleAt(const CaseSettings& settings, int frame_index, double t_s) {
  double scale = lightingScaleAt(settings.lighting, t_s);
  if (settings.lighting.preset == LightingPreset::kFlicker) {
    scale *= flickerScale(settings.seed, frame_index);
  }
  return scale;
}

void ScenarioRunner::setSceneAt(SceneRenderer& renderer, const CaseSettings& settings,
                                int frame_index, double t_s) const {
  renderer.setObserver(robotMotionAt(settings.observer.pose, settings.observer.motion, t_s),
                       headAt(settings.observer.head, t_s));
  for (std::size_t i = 0; i < settings.robots.size(); ++i) {
    const RobotSpec& r = settings.robots[i];
    renderer.setRobot(static_cast<int>(i), robotMotionAt(r.pose, r.motion, t_s));
  }
  if (settings.ball) {
    renderer.setBall(
        ballAt(*settings.ball, settings.ball_radius_m, initialBallOrientation(settings.seed), t_s));
  }
  renderer.setLighting(LightingState{lightingScaleAt(settings, frame_index, t_s)});
}

namespace {

// How far the image centre's scene (far away: the camera's turn, not its travel) moves in the image
// from one sub-frame to the next, averaged over the sub-frames.
Eigen::Vector2d meanSubframeStepPx(const std::vector<std::pair<CameraModel, Eigen::Isometry3d>>& cams) {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  int steps = 0;
  for (std::size_t j = 0; j + 1 < cams.size(); ++j) {
    const auto& [model_a, field_a] = cams[j];
    const auto& [model_b, field_b] = cams[j + 1];
    const Eigen::Vector2d centre(0.5 * model_a.width(), 0.5 * model_a.height());
    // Robot-frame ray of sub-frame j into the field, then into sub-frame j+1's robot frame.
    const Eigen::Matrix3d robot_to_field_a = (field_a * model_a.cameraToRobot().inverse()).linear();
    const Eigen::Matrix3d robot_to_field_b = (field_b * model_b.cameraToRobot().inverse()).linear();
    const Eigen::Vector3d ray_b =
        robot_to_field_b.transpose() * (robot_to_field_a * model_a.pixelRay(centre));
    const auto pixel = model_b.robotToPixel(model_b.position() + 1000.0 * ray_b);
    if (!pixel) continue;
    sum += *pixel - centre;
    ++steps;
  }
  return steps > 0 ? Eigen::Vector2d(sum / steps) : Eigen::Vector2d::Zero();
}

}  // namespace

RenderedFrame ScenarioRunner::render(int case_index, int frame_index, bool object_map) {
  const CaseSettings& settings = scenarioCase(case_index).settings;
  if (frame_index < 0) throw Error(scenario_.path + ": negative frame index");
  SceneRenderer& renderer = rendererFor(settings);
  const int w = settings.width_px;
  const int h = settings.height_px;
  const double t = frameTime(settings, frame_index);
  const ExposurePlan plan(settings.effects, h);

  RenderedFrame frame;
  frame.case_index = case_index;
  frame.frame_index = frame_index;
  frame.truth = scenarioStateAt(settings, frame_index);

  FloatImage exposure;
  // The camera's own turn over the exposure and over the rolling shutter's readout, in the image.
  Eigen::Vector2d exposure_smear = Eigen::Vector2d::Zero(), rolling_shift = Eigen::Vector2d::Zero();
  if (plan.isInstant()) {
    setSceneAt(renderer, settings, frame_index, t);
    RenderOutput out = renderer.render(settings.camera, w, h, object_map);
    exposure = toFloat(out.gray);
    if (object_map) frame.truth.object_map = std::move(out.object_map);
  } else {
    std::vector<GrayImage> subframes;
    std::vector<std::pair<CameraModel, Eigen::Isometry3d>> cameras;  // model, camera to field
    for (double dt : plan.subframeTimes()) {
      setSceneAt(renderer, settings, frame_index, t + dt);
      subframes.push_back(renderer.render(settings.camera, w, h, false).gray);
      cameras.emplace_back(renderer.cameraModel(settings.camera, w, h),
                           renderer.cameraToField(settings.camera));
    }
    exposure = composeSubframes(subframes, plan);
    // The camera's own turn between sub-frames leaves gaps between their copies; fill them.
    const Eigen::Vector2d step = meanSubframeStepPx(cameras);
    exposure = smearAlong(exposure, step.x(), step.y());
    // The sub-frames span the exposure and the rolling shutter's readout: the exposure alone is
    // exposure / spacing steps (none without blur, where the sub-frames are readout bands), the
    // readout readout / spacing (none with a global shutter).
    const std::vector<double>& times = plan.subframeTimes();
    if (times.size() > 1) {
      exposure_smear = step * (plan.exposureS() / (times[1] - times[0]));
      rolling_shift = step * (plan.readoutS() / (times[1] - times[0]));
    }
    // The truth and the object map are at the frame time (the middle of the exposure).
    setSceneAt(renderer, settings, frame_index, t);
    if (object_map)
      frame.truth.object_map = renderer.render(settings.camera, w, h, true).object_map;
  }
  frame.truth.camera.model = renderer.cameraModel(settings.camera, w, h);
  frame.truth.camera.camera_to_field = renderer.cameraToField(settings.camera);
  frame.perception_camera = perceivedCamera(frame.truth.camera.model, settings.camera_error);
  // What the robot's kinematics would tell it (head joint velocities times the exposure and the
  // readout times).
  frame.perception_camera.setExposureSmearPx(exposure_smear);
  frame.perception_camera.setRollingShutterShiftPx(rolling_shift);
  exposure = applyOptics(std::move(exposure), settings.effects);
  frame.image = applySensor(exposure, settings.effects, frameSeed(settings.seed, frame_index));
  return frame;
}

CameraModel perceivedCamera(const CameraModel& truth, const CameraErrorSpec& error) {
  if (!error.any()) return truth;
  const Eigen::Matrix3d body = truth.cameraToRobot().linear() * opticalToBody().transpose();
  Eigen::Isometry3d pose = truth.cameraToRobot();
  pose.linear() = Eigen::AngleAxisd(error.yaw_rad, Eigen::Vector3d::UnitZ()).toRotationMatrix() * body *
                  (Eigen::AngleAxisd(error.pitch_rad, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(error.roll_rad, Eigen::Vector3d::UnitX()))
                      .toRotationMatrix() *
                  opticalToBody();
  pose.translation().z() += error.height_m;
  return CameraModel(truth.intrinsics(), pose);
}

void ScenarioRunner::runCase(int case_index, int frames, bool object_map,
                             const std::function<void(const RenderedFrame&)>& sink) {
  const int count = frames < 0 ? scenarioCase(case_index).settings.frames : frames;
  for (int k = 0; k < count; ++k) sink(render(case_index, k, object_map));
}

}  // namespace colorfree::sim
