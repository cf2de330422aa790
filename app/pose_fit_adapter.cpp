#include "pose_fit_adapter.h"

#include "colorfree/perception/pose_fit.h"

namespace colorfree::app {

std::optional<PoseNumbers> fitPose(const FieldFeatures& features, const PoseNumbers& guess) {
  static const PoseFitter fitter(PoseFitParams::loadDefault(), FieldDimensions::loadDefault());
  const PoseFitResult r = fitter.fit(features, {guess.x_m, guess.y_m, guess.heading_rad});
  if (!r.ok) return std::nullopt;
  return PoseNumbers{r.pose.x_m, r.pose.y_m, r.pose.theta_rad};
}

}  // namespace colorfree::app
