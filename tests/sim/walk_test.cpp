#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "colorfree/perception/error.h"
#include "colorfree/sim/world.h"
#include "nao_model.h"

namespace colorfree::sim {
namespace {

TEST(WalkPosture, StandingIsTheDefaultPosture) {
  const NaoPosture standing = walkPosture(0.37, 0);
  const NaoPosture def;
  for (const auto& j : naoJoints()) EXPECT_EQ(standing.*(j.angle), def.*(j.angle)) << j.name;
}

TEST(WalkPosture, FeetStayOnTheGroundWhileLegsArmsAndTorsoMove) {
  double min_height = 1, max_height = 0, max_lift = 0, min_arm = 10, max_arm = -10;
  double prev_left_x = 0;
  int left_moves_back = 0, left_stance_samples = 0;
  for (int i = 0; i < 100; ++i) {
    const double phase = i / 100.0;
    const NaoPosture p = walkPosture(phase, 0.2);
    const double torso = torsoHeight(p);
    const auto [l, r] = soleCentresInTorso(p);
    // One sole is on the ground (torso height puts the lower one at z = 0) ...
    EXPECT_NEAR(std::min(l.z(), r.z()) + torso, 0, 1e-12);
    // ... both soles stay flat and near it, the swing one lifts.
    max_lift = std::max(max_lift, std::abs(l.z() - r.z()));
    min_height = std::min(min_height, torso);
    max_height = std::max(max_height, torso);
    min_arm = std::min(min_arm, p.l_shoulder_pitch);
    max_arm = std::max(max_arm, p.l_shoulder_pitch);
    EXPECT_NEAR(p.l_hip_pitch + p.l_knee_pitch + p.l_ankle_pitch, 0, 1e-9);
    // The left foot is on the ground in the first half and moves back under the walking torso.
    if (phase > 0.01 && phase < 0.49) {
      ++left_stance_samples;
      left_moves_back += l.x() < prev_left_x ? 1 : 0;
    }
    prev_left_x = l.x();
  }
  EXPECT_GT(max_lift, 0.01);
  EXPECT_LT(max_lift, 0.03);
  EXPECT_GT(max_height - min_height, 0.002) << "the torso does not bob";
  EXPECT_GT(max_arm - min_arm, 0.2) << "the arms do not swing";
  EXPECT_EQ(left_moves_back, left_stance_samples);
}

TEST(WalkPosture, NonFiniteInputIsAnError) {
  EXPECT_THROW(walkPosture(std::nan(""), 0.1), Error);
  EXPECT_THROW(walkPosture(0.1, INFINITY), Error);
}

}  // namespace
}  // namespace colorfree::sim

namespace colorfree::sim {
namespace {

TEST(FlickerScale, IsSeededVariesOverFramesAndStaysInRange) {
  double lo = 10, hi = -10;
  for (int frame = 0; frame < 200; ++frame) {
    const double k = flickerScale(5, frame);
    EXPECT_EQ(k, flickerScale(5, frame));
    lo = std::min(lo, k);
    hi = std::max(hi, k);
  }
  EXPECT_GE(lo, 0.35);
  EXPECT_LE(hi, 1.1);
  EXPECT_GT(hi - lo, 0.3);
  EXPECT_NE(flickerScale(5, 3), flickerScale(6, 3));
}

}  // namespace
}  // namespace colorfree::sim
