#pragma once

#include "colorfree/groundtruth/scorer.h"
#include "colorfree/groundtruth/world_state.h"
#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/image.h"
#include "colorfree/perception/pipeline.h"

namespace colorfree::app {

/// Runs the perception pipeline on one frame and hands its outputs to the scorer's FramePercepts.
/// Stages the pipeline does not have yet are left empty, so the scorer reports them as absent.
class PerceptionRunner {
 public:
  PerceptionRunner();
  /// `pose_guess` starts the feature-based pose fit (the truth moved by the scoring offset, so a
  /// fit that does not move shows that offset as its error).
  FramePercepts process(const GrayImage& image, const CameraModel& camera,
                        const FieldPose& pose_guess);
  /// Timing over all frames so far, as the pipeline keeps it.
  const PipelineStats& stats() const { return stats_; }

 private:
  Pipeline pipeline_;
  PipelineStats stats_;
};

/// results.json's key for a pipeline stage (the paper's rows: high_contrast, field_features, ...).
std::string stageKey(Stage stage);

}  // namespace colorfree::app
