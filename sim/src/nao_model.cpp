#include "nao_model.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "colorfree/perception/error.h"

namespace colorfree::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Mass-less links would be rejected by MuJoCo's compiler; the model is only posed, never
// simulated, so every jointed body gets the same tiny inertia.
constexpr const char* kInertial =
    R"(<inertial pos="0 0 0" mass="0.05" diaginertia="1e-4 1e-4 1e-4"/>)";

class Writer {
 public:
  explicit Writer(const NaoLook& look) : look_(look) {
    os_.setf(std::ios::fixed);
    os_.precision(8);
  }

  void open(const std::string& body, const Eigen::Vector3d& pos, const char* joint,
            const Eigen::Vector3d& axis) {
    os_ << "<body name=\"" << look_.prefix << body << "\" pos=\"" << v(pos) << "\">" << kInertial;
    os_ << "<joint name=\"" << look_.prefix << joint << "\" type=\"hinge\" axis=\"" << v(axis)
        << "\" limited=\"false\"/>\n";
  }
  void close() { os_ << "</body>\n"; }

  void geom(const std::string& type, const std::string& attrs, const std::string& material,
            bool hidden = false) {
    os_ << "<geom name=\"" << look_.prefix << "g" << count_++ << "\" type=\"" << type << "\" "
        << attrs << " material=\"" << material << "\"";
    if (hidden) os_ << " group=\"" << kHiddenGeomGroup << "\"";
    os_ << "/>\n";
  }
  void capsule(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double r,
               const std::string& mat) {
    geom("capsule", "fromto=\"" + v(a) + " " + v(b) + "\" size=\"" + s(r) + "\"", mat);
  }
  void sphere(const Eigen::Vector3d& p, double r, const std::string& mat) {
    geom("sphere", "pos=\"" + v(p) + "\" size=\"" + s(r) + "\"", mat);
  }
  void ellipsoid(const Eigen::Vector3d& p, const Eigen::Vector3d& r, const std::string& mat,
                 bool hidden = false) {
    geom("ellipsoid", "pos=\"" + v(p) + "\" size=\"" + v(r) + "\"", mat, hidden);
  }
  void box(const Eigen::Vector3d& p, const Eigen::Vector3d& half, const std::string& mat) {
    geom("box", "pos=\"" + v(p) + "\" size=\"" + v(half) + "\"", mat);
  }
  // Cylinder with its axis along z (zaxis changes it).
  void cylinder(const Eigen::Vector3d& p, double r, double half_len, const std::string& mat,
                const std::string& zaxis = "0 0 1", bool hidden = false) {
    geom("cylinder",
         "pos=\"" + v(p) + "\" size=\"" + s(r) + " " + s(half_len) + "\" zaxis=\"" + zaxis + "\"",
         mat, hidden);
  }
  void raw(const std::string& text) { os_ << text; }
  std::string str() const { return os_.str(); }

  static std::string s(double x) {
    std::ostringstream o;
    o.setf(std::ios::fixed);
    o.precision(8);
    o << x;
    return o.str();
  }
  static std::string v(const Eigen::Vector3d& p) {
    return s(p.x()) + " " + s(p.y()) + " " + s(p.z());
  }

 private:
  const NaoLook& look_;
  std::ostringstream os_;
  int count_ = 0;
};

using V = Eigen::Vector3d;

void writeArm(Writer& w, const NaoDimensions& n, double side) {
  const std::string sp = side > 0 ? "L" : "R";
  w.open(sp + "_shoulder", V(0, side * n.shoulder_offset_y, n.shoulder_offset_z),
         (sp + "ShoulderPitch").c_str(), V(0, 1, 0));
  w.sphere(V(0, 0, 0), 0.042, "nao_grey");
  w.open(sp + "_upper_arm", V(0, 0, 0), (sp + "ShoulderRoll").c_str(), V(0, 0, 1));
  w.capsule(V(0.015, side * 0.005, 0), V(n.upper_arm_length - 0.025, side * 0.008, 0), 0.033,
            "nao_white");
  w.open(sp + "_elbow", V(n.upper_arm_length, side * n.elbow_offset_y, 0),
         (sp + "ElbowYaw").c_str(), V(1, 0, 0));
  w.sphere(V(0, 0, 0), 0.028, "nao_grey");
  w.open(sp + "_forearm", V(0, 0, 0), (sp + "ElbowRoll").c_str(), V(0, 0, 1));
  w.capsule(V(0.012, 0, 0), V(n.lower_arm_length + 0.01, 0, 0), 0.03, "nao_white");
  w.ellipsoid(V(n.lower_arm_length + n.hand_offset_x * 0.55, 0, n.hand_offset_z * 0.5),
              V(0.035, 0.022, 0.025), "nao_grey");
  w.close();
  w.close();
  w.close();
  w.close();
}

void writeLeg(Writer& w, const NaoDimensions& n, double side) {
  const std::string sp = side > 0 ? "L" : "R";
  // HipYawPitch turns about an axis 45° between y and z (mirrored on the right leg).
  w.open(sp + "_hip", V(0, side * n.hip_offset_y, -n.hip_offset_z), (sp + "HipYawPitch").c_str(),
         V(0, std::sqrt(0.5), -side * std::sqrt(0.5)));
  w.open(sp + "_hip_roll", V(0, 0, 0), (sp + "HipRoll").c_str(), V(1, 0, 0));
  w.open(sp + "_thigh", V(0, 0, 0), (sp + "HipPitch").c_str(), V(0, 1, 0));
  w.sphere(V(0, 0, -0.005), 0.04, "nao_grey");
  w.capsule(V(0.005, 0, -0.02), V(0.005, 0, -n.thigh_length + 0.03), 0.043, "nao_white");
  w.open(sp + "_tibia", V(0, 0, -n.thigh_length), (sp + "KneePitch").c_str(), V(0, 1, 0));
  w.cylinder(V(0.005, 0, 0), 0.035, 0.03, "nao_grey", "0 1 0");
  w.capsule(V(-0.003, 0, -0.025), V(-0.003, 0, -n.tibia_length + 0.025), 0.04, "nao_white");
  w.open(sp + "_ankle", V(0, 0, -n.tibia_length), (sp + "AnklePitch").c_str(), V(0, 1, 0));
  w.open(sp + "_foot", V(0, 0, 0), (sp + "AnkleRoll").c_str(), V(1, 0, 0));
  // Ankle block, then the foot: square heel with a dark heel plate, rounded toe, dark sole rim.
  w.box(V(0, 0, -0.018), V(0.03, 0.03, 0.018), "nao_grey");
  const double sole_z = -n.foot_height;
  const double half_w = n.sole_width / 2;
  const double toe_x = n.sole_front - half_w;
  const double shell_h = 0.0135;
  const double box_cx = (toe_x - n.sole_back) / 2;
  const double box_hx = (toe_x + n.sole_back) / 2;
  w.box(V(box_cx, 0, sole_z + 0.006 + shell_h), V(box_hx, half_w, shell_h), "nao_white");
  w.cylinder(V(toe_x, 0, sole_z + 0.006 + shell_h), half_w, shell_h, "nao_white");
  w.box(V(box_cx, 0, sole_z + 0.003), V(box_hx + 0.001, half_w + 0.001, 0.003), "nao_dark");
  w.cylinder(V(toe_x, 0, sole_z + 0.003), half_w + 0.001, 0.003, "nao_dark");
  w.box(V(-n.sole_back + 0.004, 0, sole_z + 0.02), V(0.005, half_w * 0.8, 0.014), "nao_dark");
  w.close();
  w.close();
  w.close();
  w.close();
  w.close();
  w.close();
}

}  // namespace

std::string naoMjcf(const NaoLook& look) {
  const NaoDimensions& n = kNao;
  Writer w(look);
  const std::string p = look.prefix;
  w.raw("<body name=\"" + p + "torso\" mocap=\"true\" pos=\"0 0 0.33\">\n");
  // Chest, jersey over the belly, back pack, pelvis, neck.
  w.ellipsoid(V(-0.008, 0, 0.055), V(0.06, 0.076, 0.07), "nao_white");
  w.ellipsoid(V(-0.015, 0, 0.0), V(0.055, 0.08, 0.058), look.jersey_material);
  w.box(V(-0.06, 0, 0.04), V(0.012, 0.05, 0.055), "nao_grey");
  w.box(V(-0.01, 0, -n.hip_offset_z + 0.025), V(0.045, 0.075, 0.02), "nao_grey");
  w.cylinder(V(0, 0, n.neck_offset_z - 0.012), 0.022, 0.014, "nao_grey");
  w.open("head_yaw", V(0, 0, n.neck_offset_z), "HeadYaw", V(0, 0, 1));
  w.open("head", V(0, 0, 0), "HeadPitch", V(0, 1, 0));
  // The observer's cameras sit inside the head shell: hide the shell from its own cameras.
  const bool hide = look.observer;
  w.ellipsoid(V(0, 0, 0.05), V(0.058, 0.064, 0.062), "nao_white", hide);
  w.ellipsoid(V(0.038, 0, 0.035), V(0.024, 0.05, 0.026), "nao_dark", hide);
  w.cylinder(V(0, 0.061, 0.045), 0.034, 0.008, "nao_grey", "0 1 0", hide);
  w.cylinder(V(0, -0.061, 0.045), 0.034, 0.008, "nao_grey", "0 1 0", hide);
  if (look.observer) {
    const auto cam = [&](const char* name, const V& pos, double pitch) {
      w.raw("<camera name=\"" + p + name + "\" pos=\"" + Writer::v(pos) + "\" xyaxes=\"0 -1 0 " +
            Writer::s(std::sin(pitch)) + " 0 " + Writer::s(std::cos(pitch)) + "\"/>\n");
    };
    cam("top_camera", n.top_camera_in_head, n.top_camera_pitch_rad);
    cam("bottom_camera", n.bottom_camera_in_head, n.bottom_camera_pitch_rad);
  }
  w.close();
  w.close();
  writeArm(w, n, 1);
  writeArm(w, n, -1);
  writeLeg(w, n, 1);
  writeLeg(w, n, -1);
  w.raw("</body>\n");
  return w.str();
}

const std::vector<NaoJoint>& naoJoints() {
  static const std::vector<NaoJoint> joints = {
      {"HeadYaw", &NaoPosture::head_yaw},
      {"HeadPitch", &NaoPosture::head_pitch},
      {"LShoulderPitch", &NaoPosture::l_shoulder_pitch},
      {"LShoulderRoll", &NaoPosture::l_shoulder_roll},
      {"LElbowYaw", &NaoPosture::l_elbow_yaw},
      {"LElbowRoll", &NaoPosture::l_elbow_roll},
      {"RShoulderPitch", &NaoPosture::r_shoulder_pitch},
      {"RShoulderRoll", &NaoPosture::r_shoulder_roll},
      {"RElbowYaw", &NaoPosture::r_elbow_yaw},
      {"RElbowRoll", &NaoPosture::r_elbow_roll},
      {"LHipYawPitch", &NaoPosture::l_hip_yaw_pitch},
      {"LHipRoll", &NaoPosture::l_hip_roll},
      {"LHipPitch", &NaoPosture::l_hip_pitch},
      {"LKneePitch", &NaoPosture::l_knee_pitch},
      {"LAnklePitch", &NaoPosture::l_ankle_pitch},
      {"LAnkleRoll", &NaoPosture::l_ankle_roll},
      {"RHipYawPitch", &NaoPosture::r_hip_yaw_pitch},
      {"RHipRoll", &NaoPosture::r_hip_roll},
      {"RHipPitch", &NaoPosture::r_hip_pitch},
      {"RKneePitch", &NaoPosture::r_knee_pitch},
      {"RAnklePitch", &NaoPosture::r_ankle_pitch},
      {"RAnkleRoll", &NaoPosture::r_ankle_roll},
  };
  return joints;
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> soleCentresInTorso(const NaoPosture& q) {
  const NaoDimensions& n = kNao;
  const auto leg = [&](double side, double hyp, double roll, double pitch, double knee,
                       double ankle_pitch, double ankle_roll) {
    using AA = Eigen::AngleAxisd;
    const Eigen::Vector3d hyp_axis(0, std::sqrt(0.5), -side * std::sqrt(0.5));
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    t.translate(Eigen::Vector3d(0, side * n.hip_offset_y, -n.hip_offset_z));
    t.rotate(AA(hyp, hyp_axis));
    t.rotate(AA(roll, Eigen::Vector3d::UnitX()));
    t.rotate(AA(pitch, Eigen::Vector3d::UnitY()));
    t.translate(Eigen::Vector3d(0, 0, -n.thigh_length));
    t.rotate(AA(knee, Eigen::Vector3d::UnitY()));
    t.translate(Eigen::Vector3d(0, 0, -n.tibia_length));
    t.rotate(AA(ankle_pitch, Eigen::Vector3d::UnitY()));
    t.rotate(AA(ankle_roll, Eigen::Vector3d::UnitX()));
    return Eigen::Vector3d(t * Eigen::Vector3d(0, 0, -n.foot_height));
  };
  return {leg(1, q.l_hip_yaw_pitch, q.l_hip_roll, q.l_hip_pitch, q.l_knee_pitch, q.l_ankle_pitch,
              q.l_ankle_roll),
          leg(-1, q.r_hip_yaw_pitch, q.r_hip_roll, q.r_hip_pitch, q.r_knee_pitch, q.r_ankle_pitch,
              q.r_ankle_roll)};
}

double torsoHeight(const NaoPosture& posture) {
  const auto [l, r] = soleCentresInTorso(posture);
  return -std::min(l.z(), r.z());
}

NaoPosture walkPosture(double phase, double speed_mps) {
  if (!std::isfinite(phase) || !std::isfinite(speed_mps)) {
    throw Error("walk posture: phase and speed must be finite numbers");
  }
  // Gait cycle of two steps; the swing foot's lift, the torso's bob and the arm swing grow with
  // speed up to a normal walking speed.
  constexpr double kCycleS = 0.5;
  constexpr double kFullSpeedMps = 0.2;
  constexpr double kLiftM = 0.018;
  constexpr double kBobM = 0.004;
  constexpr double kSwayRad = 0.035;
  constexpr double kArmSwingRad = 0.35;
  NaoPosture p;
  if (speed_mps == 0) return p;
  const NaoDimensions& n = kNao;
  phase -= std::floor(phase);
  const double effort = std::min(1.0, std::abs(speed_mps) / kFullSpeedMps);
  const double step_m = speed_mps * kCycleS / 2;

  // Ankle below the hip in the default stance, from the default posture's leg angles.
  const NaoPosture standing;
  const double standing_drop =
      n.thigh_length * std::cos(standing.l_hip_pitch) +
      n.tibia_length * std::cos(standing.l_hip_pitch + standing.l_knee_pitch);
  const double drop = standing_drop - kBobM * effort * 0.5 * (1 + std::cos(4 * kPi * phase));

  // Foot x relative to the hip: stance moves it back, swing brings it forward and lifts it.
  const auto foot = [&](double leg_phase, double& x, double& lift) {
    if (leg_phase < 0.5) {
      const double s = leg_phase / 0.5;
      x = step_m * (0.5 - s);
      lift = 0;
    } else {
      const double s = (leg_phase - 0.5) / 0.5;
      x = step_m * (-0.5 + 0.5 * (1 - std::cos(kPi * s)));
      lift = kLiftM * effort * std::sin(kPi * s);
    }
  };
  const auto ik = [&](double x, double z, double& hip, double& knee, double& ankle) {
    const double l1 = n.thigh_length, l2 = n.tibia_length;
    const double d = std::min(std::hypot(x, z), l1 + l2 - 1e-6);
    knee = kPi - std::acos(std::clamp((l1 * l1 + l2 * l2 - d * d) / (2 * l1 * l2), -1.0, 1.0));
    const double alpha = std::atan2(x, -z);
    const double beta =
        std::acos(std::clamp((l1 * l1 + d * d - l2 * l2) / (2 * l1 * d), -1.0, 1.0));
    hip = -(alpha + beta);
    ankle = -(hip + knee);
  };
  double lx, llift, rx, rlift;
  foot(phase, lx, llift);
  foot(std::fmod(phase + 0.5, 1.0), rx, rlift);
  ik(lx, -(drop - llift), p.l_hip_pitch, p.l_knee_pitch, p.l_ankle_pitch);
  ik(rx, -(drop - rlift), p.r_hip_pitch, p.r_knee_pitch, p.r_ankle_pitch);
  // Sideways sway over the stance foot, feet kept flat.
  const double sway = kSwayRad * effort * std::sin(2 * kPi * phase);
  p.l_hip_roll = p.r_hip_roll = sway;
  p.l_ankle_roll = p.r_ankle_roll = -sway;
  // Each arm swings with the opposite leg.
  const double half_step = std::max(1e-9, std::abs(step_m) / 2);
  const double sign = speed_mps > 0 ? 1 : -1;
  p.l_shoulder_pitch = standing.l_shoulder_pitch - kArmSwingRad * effort * sign * rx / half_step;
  p.r_shoulder_pitch = standing.r_shoulder_pitch - kArmSwingRad * effort * sign * lx / half_step;
  return p;
}

}  // namespace colorfree::sim
