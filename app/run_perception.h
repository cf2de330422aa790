#pragma once

#include "colorfree/groundtruth/scorer.h"
#include "colorfree/groundtruth/world_state.h"
#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/image.h"
#include "colorfree/perception/pipeline.h"
#include "colorfree/perception/pose_fit.h"
#include "colorfree/sim/runner.h"

namespace colorfree::app {

/// Runs the perception pipeline on one frame and hands its outputs to the scorer's FramePercepts.
/// Stages the pipeline does not have yet are left empty, so the scorer reports them as absent.
class PerceptionRunner {
 public:
  PerceptionRunner();
  /// A new case: the robots' orientation tracks start empty.
  void beginCase() { tracks_ = {}; }
  /// Runs the pipeline on a rendered frame (the image, its camera model and its time; nothing
  /// else of the truth reaches the perception except the pose fit's starting point: the true
  /// pose moved by the scoring offset, so a fit that does not move shows that offset as its error).
  FramePercepts process(const sim::RenderedFrame& rendered, const ScoringParams& scoring);
  /// Timing over all frames so far, as the pipeline keeps it.
  const PipelineStats& stats() const { return stats_; }

 private:
  Pipeline pipeline_;
  PoseFitter pose_fitter_;
  PipelineStats stats_;
  RobotTracks tracks_;
};

/// The scorer's description of a scenario case: its name and swept settings (numbers as numbers).
CaseInfo caseInfo(const sim::ScenarioCase& scenario_case);

/// results.json's key for a pipeline stage (the paper's rows: high_contrast, field_features, ...).
std::string stageKey(Stage stage);

}  // namespace colorfree::app
