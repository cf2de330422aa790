#pragma once

#include <optional>

#include "colorfree/perception/percepts.h"

namespace colorfree::app {

/// A field pose as plain numbers. perception/pose_fit.h and groundtruth/world_state.h both define
/// a colorfree::FieldPose, so the pose fit is called from its own translation unit.
struct PoseNumbers {
  double x_m = 0;
  double y_m = 0;
  double heading_rad = 0;
};

/// The field pose that best explains the features (perception's PoseFitter with its shipped
/// parameters), starting from `guess`; empty when the fit is not constrained enough.
std::optional<PoseNumbers> fitPose(const FieldFeatures& features, const PoseNumbers& guess);

}  // namespace colorfree::app
