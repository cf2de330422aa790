#pragma once

#include "colorfree/sim/runner.h"

namespace colorfree::sim {

/// The NAO posture a robot's motion state gives (world.h's procedural walk), with head angles.
NaoPosture postureFor(const RobotMotionState& motion, const HeadAngles& head = {});

/// The scenario runner's renderer backed by the MuJoCo World.
RendererFactory worldRendererFactory();

}  // namespace colorfree::sim
