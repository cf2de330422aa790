#include "run_perception.h"

namespace colorfree::app {

PerceptionRunner::PerceptionRunner() = default;

FramePercepts PerceptionRunner::process(const GrayImage& /*image*/, const CameraModel& /*camera*/) {
  // No perception stage has landed on this branch yet: everything stays absent.
  return FramePercepts{};
}

}  // namespace colorfree::app
