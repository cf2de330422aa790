#pragma once

#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "colorfree/sim/world.h"

namespace colorfree::sim {

/// NAO H25 link lengths and camera mounts (Aldebaran documentation; see REFERENCE.md). Metres.
struct NaoDimensions {
  double neck_offset_z = 0.1265;
  double shoulder_offset_y = 0.098;
  double shoulder_offset_z = 0.100;
  double upper_arm_length = 0.105;
  double elbow_offset_y = 0.015;
  double lower_arm_length = 0.05595;
  double hand_offset_x = 0.05775;
  double hand_offset_z = 0.01231;
  double hip_offset_y = 0.050;
  double hip_offset_z = 0.085;
  double thigh_length = 0.100;
  double tibia_length = 0.1029;
  double foot_height = 0.04519;
  double sole_front = 0.100;  ///< sole length in front of the ankle
  double sole_back = 0.050;   ///< behind the ankle
  double sole_width = 0.089;
  Eigen::Vector3d top_camera_in_head{0.05871, 0, 0.06364};
  double top_camera_pitch_rad = 1.2 * 3.14159265358979323846 / 180;
  Eigen::Vector3d bottom_camera_in_head{0.05071, 0, 0.01774};
  double bottom_camera_pitch_rad = 39.7 * 3.14159265358979323846 / 180;
};
inline const NaoDimensions kNao{};

/// How one NAO of the scene looks and is named in the MJCF.
struct NaoLook {
  std::string prefix;  ///< name prefix of its bodies, joints, geoms, cameras
  std::string jersey_material;
  bool observer = false;  ///< carries the cameras; its head is hidden from its own cameras
};

/// Geom group of the observer's head, hidden when rendering its cameras.
inline constexpr int kHiddenGeomGroup = 3;

/// MJCF of one NAO as a mocap torso body (children of <worldbody>). Uses the materials nao_white,
/// nao_grey, nao_dark and look.jersey_material.
std::string naoMjcf(const NaoLook& look);

/// The NAO's joint names (NAO naming) with a member pointer into NaoPosture each.
struct NaoJoint {
  const char* name;
  double NaoPosture::*angle;
};
const std::vector<NaoJoint>& naoJoints();

/// Sole centre of each foot (left, right) in the torso frame, for a posture.
std::pair<Eigen::Vector3d, Eigen::Vector3d> soleCentresInTorso(const NaoPosture& posture);

/// Height of the torso origin above the ground so that the lower sole touches it.
double torsoHeight(const NaoPosture& posture);

}  // namespace colorfree::sim
