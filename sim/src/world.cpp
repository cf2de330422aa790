#include "colorfree/sim/world.h"

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <random>

#include "colorfree/perception/error.h"
#include "colorfree/sim/mjcf_loader.h"
#include "colorfree/sim/mujoco_errors.h"
#include "gl_context.h"
#include "nao_model.h"
#include "scene_builder.h"

namespace colorfree::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;

bool startsWith(const char* s, const char* prefix) {
  return s != nullptr && std::strncmp(s, prefix, std::strlen(prefix)) == 0;
}

void checkFinite(const FieldPose& p, const char* what) {
  if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !std::isfinite(p.heading_rad)) {
    throw Error(std::string(what) + ": pose is not finite");
  }
}

// The MuJoCo addresses of one NAO: mocap slot of its torso and the qpos of each joint.
struct NaoHandles {
  int mocap = -1;
  std::vector<int> qpos;  // in naoJoints() order
};

NaoHandles findNao(const mjModel* m, const std::string& prefix) {
  NaoHandles h;
  const int body = mj_name2id(m, mjOBJ_BODY, (prefix + "torso").c_str());
  if (body < 0) throw Error("world: model has no body " + prefix + "torso");
  h.mocap = m->body_mocapid[body];
  for (const auto& j : naoJoints()) {
    const int id = mj_name2id(m, mjOBJ_JOINT, (prefix + j.name).c_str());
    if (id < 0) throw Error("world: model has no joint " + prefix + j.name);
    h.qpos.push_back(m->jnt_qposadr[id]);
  }
  return h;
}

// Objects further outside the view than this may still cast a shadow into it (a standing NAO
// under a light 35° above the horizon).
constexpr double kShadowCasterMarginM = 1.0;

// Drops the scene's geoms whose bounding spheres lie outside the camera's view (widened by
// `margin_m`): llvmpipe transforms and lights every vertex it is given, seen or not.
void cullOutsideView(mjvScene& scn, const CameraIntrinsics& k, double margin_m) {
  const mjvGLCamera& c = scn.camera[0];
  const Eigen::Vector3d pos(c.pos[0], c.pos[1], c.pos[2]);
  const Eigen::Vector3d forward =
      Eigen::Vector3d(c.forward[0], c.forward[1], c.forward[2]).normalized();
  const Eigen::Vector3d up = Eigen::Vector3d(c.up[0], c.up[1], c.up[2]).normalized();
  const Eigen::Vector3d right = forward.cross(up);
  const double tan_x = (k.width_px / 2.0) / k.focal_x_px;
  const double tan_y = (k.height_px / 2.0) / k.focal_y_px;
  const double sec_x = std::sqrt(1 + tan_x * tan_x), sec_y = std::sqrt(1 + tan_y * tan_y);
  int kept = 0;
  for (int i = 0; i < scn.ngeom; ++i) {
    const mjvGeom& g = scn.geoms[i];
    bool visible = true;
    // Planes and decor have no bounding sphere: always drawn.
    if (g.modelrbound > 0) {
      const Eigen::Vector3d d = Eigen::Vector3d(g.pos[0], g.pos[1], g.pos[2]) - pos;
      const double r = g.modelrbound + margin_m;
      const double z = d.dot(forward);
      visible = z > -r && std::abs(d.dot(right)) <= z * tan_x + r * sec_x &&
                std::abs(d.dot(up)) <= z * tan_y + r * sec_y;
    }
    if (visible) scn.geoms[kept++] = g;
  }
  scn.ngeom = kept;
}

}  // namespace

LightingPreset lightingPresetFromName(const std::string& name) {
  if (name == "normal") return LightingPreset::kNormal;
  if (name == "dim") return LightingPreset::kDim;
  if (name == "overexposed") return LightingPreset::kOverexposed;
  if (name == "directional") return LightingPreset::kDirectional;
  if (name == "uneven") return LightingPreset::kUneven;
  if (name == "flicker") return LightingPreset::kFlicker;
  throw Error("unknown lighting preset '" + name +
              "' (normal, dim, overexposed, directional, uneven, flicker)");
}

std::string lightingPresetName(LightingPreset preset) {
  switch (preset) {
    case LightingPreset::kNormal:
      return "normal";
    case LightingPreset::kDim:
      return "dim";
    case LightingPreset::kOverexposed:
      return "overexposed";
    case LightingPreset::kDirectional:
      return "directional";
    case LightingPreset::kUneven:
      return "uneven";
    case LightingPreset::kFlicker:
      return "flicker";
  }
  return "normal";
}

double flickerScale(std::uint64_t seed, int frame_index) {
  // A slow beat between the lamps' 100 Hz and the camera's frame rate, plus rare deep dips.
  std::mt19937_64 rng(seed * 6364136223846793005ULL +
                      std::uint64_t(frame_index) * 1442695040888963407ULL);
  std::uniform_real_distribution<double> u(0, 1);
  const double beat = 0.85 + 0.15 * std::sin(2 * kPi * frame_index / 7.3 + double(seed % 97));
  const double dip = u(rng) < 0.15 ? 0.65 + 0.2 * u(rng) : 1.0;
  return beat * dip + 0.08 * (u(rng) - 0.5);
}

struct World::Impl {
  SceneSpec spec;
  SceneModel scene;
  std::unique_ptr<GlContext> gl;
  MjModelPtr model;
  mjData* data = nullptr;
  mjvScene scn;
  mjvOption opt;
  mjvCamera cam;
  mjrContext con;
  // The object map is drawn without anti-aliasing: a second renderer context without MSAA.
  mjrContext con_segment;
  bool scene_made = false, context_made = false, segment_context_made = false;
  std::vector<std::uint16_t> geom_label;
  NaoHandles observer;
  std::vector<NaoHandles> robots;
  FieldPose observer_pose;
  int ball_mocap = -1;
  int camera_id[2] = {-1, -1};
  std::vector<std::uint8_t> rgb;

  ~Impl() {
    if (context_made || segment_context_made) gl->makeCurrent();
    if (context_made) mjr_freeContext(&con);
    if (segment_context_made) mjr_freeContext(&con_segment);
    if (scene_made) mjv_freeScene(&scn);
    if (data != nullptr) mj_deleteData(data);
  }

  void place(const NaoHandles& h, const NaoState& s) {
    const double z = torsoHeight(s.posture);
    mjtNum* pos = data->mocap_pos + 3 * h.mocap;
    mjtNum* quat = data->mocap_quat + 4 * h.mocap;
    pos[0] = s.pose.x_m;
    pos[1] = s.pose.y_m;
    pos[2] = z;
    quat[0] = std::cos(s.pose.heading_rad / 2);
    quat[1] = 0;
    quat[2] = 0;
    quat[3] = std::sin(s.pose.heading_rad / 2);
    const auto& joints = naoJoints();
    for (std::size_t i = 0; i < joints.size(); ++i) {
      const double a = s.posture.*(joints[i].angle);
      if (!std::isfinite(a))
        throw Error(std::string("world: joint ") + joints[i].name + " is not finite");
      data->qpos[h.qpos[i]] = a;
    }
  }

  void update() {
    mj_kinematics(model.get(), data);
    mj_comPos(model.get(), data);
    mj_camlight(model.get(), data);
  }

  Eigen::Isometry3d cameraToField(NaoCamera c) const {
    const int id = camera_id[c == NaoCamera::kTop ? 0 : 1];
    Eigen::Matrix3d r;
    // MuJoCo's camera looks along -z with +y up; the optical frame looks along +z with +y down.
    const mjtNum* xm = data->cam_xmat + 9 * id;
    for (int i = 0; i < 3; ++i) {
      r(i, 0) = xm[3 * i + 0];
      r(i, 1) = -xm[3 * i + 1];
      r(i, 2) = -xm[3 * i + 2];
    }
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.linear() = r;
    t.translation() = Eigen::Vector3d(data->cam_xpos[3 * id], data->cam_xpos[3 * id + 1],
                                      data->cam_xpos[3 * id + 2]);
    return t;
  }
};

World::World(const SceneSpec& spec) : impl_(std::make_unique<Impl>()) {
  installMujocoErrorHandlers();
  Impl& w = *impl_;
  w.spec = spec;
  w.scene = buildScene(spec);
  w.model = loadMjcf(w.scene.mjcf, w.scene.files, "scene (seed " + std::to_string(spec.seed) + ")");
  mjModel* m = w.model.get();
  if (m->nlight + 1 > 8) throw Error("world: more than 8 lights with the headlight");
  w.data = mj_makeData(m);
  if (w.data == nullptr) throw Error("world: MuJoCo could not allocate the model's data");

  // Label of every geom for the object map, from its name.
  w.geom_label.assign(m->ngeom, kObjectNone);
  std::vector<std::string> robot_prefixes;
  for (int i = 0; i < spec.robot_count; ++i) robot_prefixes.push_back(robotPrefix(i));
  for (int g = 0; g < m->ngeom; ++g) {
    const char* name = mj_id2name(m, mjOBJ_GEOM, g);
    std::uint16_t label = kObjectNone;
    if (startsWith(name, kCarpetPrefix))
      label = kObjectCarpet;
    else if (startsWith(name, kLinePrefix))
      label = kObjectLine;
    else if (startsWith(name, kGoalPrefix))
      label = kObjectGoal;
    else if (startsWith(name, kBallPrefix))
      label = kObjectBall;
    else if (startsWith(name, kObserverPrefix))
      label = kObjectOwnBody;
    for (int i = 0; i < spec.robot_count; ++i) {
      if (startsWith(name, robot_prefixes[i].c_str())) label = std::uint16_t(kObjectRobotBase + i);
    }
    w.geom_label[g] = label;
  }

  w.observer = findNao(m, kObserverPrefix);
  for (int i = 0; i < spec.robot_count; ++i) w.robots.push_back(findNao(m, robotPrefix(i)));
  if (spec.ball) w.ball_mocap = m->body_mocapid[mj_name2id(m, mjOBJ_BODY, "ball")];
  w.camera_id[0] =
      mj_name2id(m, mjOBJ_CAMERA, (std::string(kObserverPrefix) + "top_camera").c_str());
  w.camera_id[1] =
      mj_name2id(m, mjOBJ_CAMERA, (std::string(kObserverPrefix) + "bottom_camera").c_str());
  if (w.camera_id[0] < 0 || w.camera_id[1] < 0) throw Error("world: the observer has no cameras");

  // Robots start off the field, side by side, until placed.
  setObserver(NaoState{});
  for (int i = 0; i < spec.robot_count; ++i) {
    NaoState s;
    s.pose.x_m = -spec.field.halfLength() + 0.5 * i;
    s.pose.y_m = spec.field.carpetHalfWidth() + 0.3;
    setRobot(i, s);
  }
  if (spec.ball)
    setBall(Eigen::Vector3d(0, 0, spec.field.ballRadius()), Eigen::Quaterniond::Identity());

  w.gl = GlContext::create(spec.max_width_px, spec.max_height_px);
  mjv_defaultScene(&w.scn);
  mjv_makeScene(m, &w.scn, 2000);
  w.scene_made = true;
  mjv_defaultOption(&w.opt);
  w.opt.geomgroup[kHiddenGeomGroup] = 0;
  mjv_defaultCamera(&w.cam);
  mjr_defaultContext(&w.con);
  mjr_makeContext(m, &w.con, mjFONTSCALE_100);
  w.context_made = true;
  mjr_setBuffer(mjFB_OFFSCREEN, &w.con);
  if (w.con.currentBuffer != mjFB_OFFSCREEN) throw Error("world: no off-screen framebuffer");
  // The object map's context: no MSAA, and the smallest shadow map (it draws no shadows).
  const int samples = m->vis.quality.offsamples, shadow_px = m->vis.quality.shadowsize;
  m->vis.quality.offsamples = 0;
  m->vis.quality.shadowsize = 1;
  mjr_defaultContext(&w.con_segment);
  mjr_makeContext(m, &w.con_segment, mjFONTSCALE_100);
  w.segment_context_made = true;
  m->vis.quality.offsamples = samples;
  m->vis.quality.shadowsize = shadow_px;
  mjr_setBuffer(mjFB_OFFSCREEN, &w.con_segment);
  if (w.con_segment.currentBuffer != mjFB_OFFSCREEN)
    throw Error("world: no off-screen framebuffer");
  if (w.con.offWidth < spec.max_width_px || w.con.offHeight < spec.max_height_px) {
    throw Error("world: off-screen framebuffer is smaller than asked for");
  }
  w.rgb.resize(std::size_t(spec.max_width_px) * spec.max_height_px * 3);
  setLighting(LightingState{});
}

World::~World() = default;

void World::setObserver(const NaoState& observer) {
  checkFinite(observer.pose, "observer");
  impl_->observer_pose = observer.pose;
  impl_->place(impl_->observer, observer);
  impl_->update();
}

void World::setRobot(int index, const NaoState& robot) {
  if (index < 0 || index >= int(impl_->robots.size())) {
    throw Error("world: robot " + std::to_string(index) + " does not exist (scene has " +
                std::to_string(impl_->robots.size()) + ")");
  }
  checkFinite(robot.pose, "robot");
  impl_->place(impl_->robots[index], robot);
  impl_->update();
}

void World::setBall(const Eigen::Vector3d& centre, const Eigen::Quaterniond& orientation) {
  if (impl_->ball_mocap < 0) throw Error("world: the scene has no ball");
  if (!centre.allFinite() || !orientation.coeffs().allFinite())
    throw Error("world: ball pose is not finite");
  const Eigen::Quaterniond q = orientation.normalized();
  mjtNum* pos = impl_->data->mocap_pos + 3 * impl_->ball_mocap;
  mjtNum* quat = impl_->data->mocap_quat + 4 * impl_->ball_mocap;
  for (int i = 0; i < 3; ++i) pos[i] = centre[i];
  quat[0] = q.w();
  quat[1] = q.x();
  quat[2] = q.y();
  quat[3] = q.z();
  impl_->update();
}

void World::setLighting(const LightingState& lighting) {
  const double k = lighting.intensity_scale;
  if (!std::isfinite(k) || k < 0 || k > 10) {
    throw Error("world: light intensity scale " + std::to_string(k) + " is not in 0..10");
  }
  mjModel* m = impl_->model.get();
  const auto& bases = impl_->scene.lights;
  for (int i = 0; i < m->nlight && std::size_t(i) < bases.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      m->light_diffuse[3 * i + c] = float(bases[i].diffuse[c] * k);
      m->light_specular[3 * i + c] = float(bases[i].specular[c] * k);
    }
  }
  for (int c = 0; c < 3; ++c)
    m->vis.headlight.ambient[c] = float(impl_->scene.headlight_ambient * k);
}

CameraModel World::cameraModel(NaoCamera camera, int width_px, int height_px) const {
  const CameraIntrinsics k = CameraIntrinsics::fromHorizontalFov(
      width_px, height_px, impl_->spec.camera_horizontal_fov_deg * kPi / 180);
  const Eigen::Isometry3d camera_to_robot =
      robotToField(impl_->observer_pose).inverse() * impl_->cameraToField(camera);
  return CameraModel(k, camera_to_robot);
}

Eigen::Isometry3d World::cameraToField(NaoCamera camera) const {
  return impl_->cameraToField(camera);
}

RenderOutput World::render(NaoCamera camera, int width_px, int height_px, bool object_map) {
  Impl& w = *impl_;
  if (width_px <= 0 || height_px <= 0 || width_px > w.spec.max_width_px ||
      height_px > w.spec.max_height_px) {
    throw Error("world: cannot render " + std::to_string(width_px) + "x" +
                std::to_string(height_px) + " in a " + std::to_string(w.spec.max_width_px) + "x" +
                std::to_string(w.spec.max_height_px) + " off-screen buffer");
  }
  mjModel* m = w.model.get();
  const int id = w.camera_id[camera == NaoCamera::kTop ? 0 : 1];
  // The vertical field of view that makes the pixels square and the horizontal one exact.
  const CameraIntrinsics k = CameraIntrinsics::fromHorizontalFov(
      width_px, height_px, w.spec.camera_horizontal_fov_deg * kPi / 180);
  m->cam_fovy[id] = k.verticalFov() * 180 / kPi;
  w.cam.type = mjCAMERA_FIXED;
  w.cam.fixedcamid = id;

  w.gl->makeCurrent();
  w.scn.flags[mjRND_SHADOW] = w.spec.shadows ? 1 : 0;
  w.scn.flags[mjRND_SKYBOX] = 0;
  w.scn.flags[mjRND_REFLECTION] = 0;
  w.scn.flags[mjRND_SEGMENT] = 0;
  w.scn.flags[mjRND_IDCOLOR] = 0;
  mjv_updateScene(m, w.data, &w.opt, nullptr, &w.cam, mjCAT_ALL, &w.scn);
  cullOutsideView(w.scn, k, w.spec.shadows ? kShadowCasterMarginM : 0.0);
  const mjrRect viewport{0, 0, width_px, height_px};
  mjr_setBuffer(mjFB_OFFSCREEN, &w.con);
  mjr_render(viewport, &w.scn, &w.con);
  mjr_readPixels(w.rgb.data(), nullptr, viewport, &w.con);

  RenderOutput out;
  out.gray = GrayImage(width_px, height_px);
  for (int y = 0; y < height_px; ++y) {
    // Read-back rows are bottom-up.
    const std::uint8_t* src = w.rgb.data() + std::size_t(height_px - 1 - y) * width_px * 3;
    std::uint8_t* dst = out.gray.data() + std::size_t(y) * width_px;
    for (int x = 0; x < width_px; ++x) {
      const int r = src[3 * x], g = src[3 * x + 1], b = src[3 * x + 2];
      dst[x] = std::uint8_t((77 * r + 150 * g + 29 * b + 128) >> 8);
    }
  }

  if (object_map) {
    w.scn.flags[mjRND_SHADOW] = 0;
    w.scn.flags[mjRND_SEGMENT] = 1;
    w.scn.flags[mjRND_IDCOLOR] = 1;
    mjr_setBuffer(mjFB_OFFSCREEN, &w.con_segment);
    mjr_render(viewport, &w.scn, &w.con_segment);
    mjr_readPixels(w.rgb.data(), nullptr, viewport, &w.con_segment);
    w.scn.flags[mjRND_SEGMENT] = 0;
    w.scn.flags[mjRND_IDCOLOR] = 0;
    // segid + 1 per pixel; segid indexes the scene's geoms.
    int max_segid = 0;
    for (int i = 0; i < w.scn.ngeom; ++i) max_segid = std::max(max_segid, w.scn.geoms[i].segid);
    std::vector<std::uint16_t> seg_label(std::size_t(max_segid) + 2, kObjectNone);
    for (int i = 0; i < w.scn.ngeom; ++i) {
      const mjvGeom& g = w.scn.geoms[i];
      if (g.segid < 0 || g.objtype != mjOBJ_GEOM || g.objid < 0 || g.objid >= m->ngeom) continue;
      if (std::size_t(g.segid) + 1 < seg_label.size())
        seg_label[g.segid + 1] = w.geom_label[g.objid];
    }
    out.object_map.width = width_px;
    out.object_map.height = height_px;
    out.object_map.labels.resize(std::size_t(width_px) * height_px);
    for (int y = 0; y < height_px; ++y) {
      const std::uint8_t* src = w.rgb.data() + std::size_t(height_px - 1 - y) * width_px * 3;
      std::uint16_t* dst = out.object_map.labels.data() + std::size_t(y) * width_px;
      for (int x = 0; x < width_px; ++x) {
        const std::size_t id_plus_one = std::size_t(src[3 * x]) |
                                        (std::size_t(src[3 * x + 1]) << 8) |
                                        (std::size_t(src[3 * x + 2]) << 16);
        if (id_plus_one >= seg_label.size()) {
          throw Error("world: segmentation rendering gave an unknown id " +
                      std::to_string(id_plus_one));
        }
        dst[x] = seg_label[id_plus_one];
      }
    }
  }
  return out;
}

const std::string& World::mjcf() const { return impl_->scene.mjcf; }

}  // namespace colorfree::sim
