#include "colorfree/perception/robot_module.h"

#include <chrono>

#include "colorfree/perception/error.h"

namespace colorfree {

RobotModule::RobotModule(RobotProposer proposer, RobotDetector detector,
                         RobotOrientationEstimator orientation)
    : proposer_(std::move(proposer)), detector_(std::move(detector)), orientation_(std::move(orientation)) {}

RobotModule RobotModule::loadDefault() {
  return RobotModule(RobotProposer(RobotProposerParams::loadDefault(), FieldDimensions::loadDefault()),
                     RobotDetector::loadDefault(), RobotOrientationEstimator::loadDefault());
}

namespace {
template <typename F>
void timed(PipelineStats* stats, Stage stage, F&& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  if (stats) {
    stats->add(stage, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
  }
}
}  // namespace

void RobotModule::process(Frame& frame, RobotTracks& tracks, double time_s, PipelineStats* stats) const {
  if (!frame.ignore_mask || !frame.contrast_regions) {
    throw Error("robot module: run the pipeline first (ignore mask and contrast regions missing)");
  }
  timed(stats, Stage::kRobotProposals, [&] {
    frame.robot_proposals =
        proposer_.run(frame.image, frame.camera, *frame.ignore_mask, *frame.contrast_regions).proposals;
  });
  timed(stats, Stage::kRobotDetector,
        [&] { frame.robot_percepts = detector_.run(frame.image, frame.camera, *frame.robot_proposals); });
  timed(stats, Stage::kRobotOrientation,
        [&] { orientation_.run(frame.image, frame.camera, *frame.robot_percepts, tracks, time_s); });
}

}  // namespace colorfree
