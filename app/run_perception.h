#pragma once

#include <memory>

#include "colorfree/groundtruth/scorer.h"
#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/image.h"

namespace colorfree::app {

/// Runs the perception pipeline on one frame and hands its outputs to the scorer's FramePercepts.
/// Stages the pipeline does not have yet are left empty, so the scorer reports them as absent.
class PerceptionRunner {
 public:
  PerceptionRunner();
  FramePercepts process(const GrayImage& image, const CameraModel& camera);

 private:
  struct Impl;
  std::shared_ptr<Impl> impl_;
};

}  // namespace colorfree::app
