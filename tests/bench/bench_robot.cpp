// Robot stages per 640x480 frame with robots in view (issue 7 goals: proposals <= 0.06 ms,
// classification <= 0.04 ms, orientation <= 0.06 ms with two robots). The frame is rendered once
// from scenes/ci/robot_bench.yaml (two robots 1.2 m and 2 m away).
#include <benchmark/benchmark.h>

#include <cstdio>

#include "colorfree/perception/pipeline.h"
#include "colorfree/perception/robot_detector.h"
#include "colorfree/perception/robot_orientation.h"
#include "colorfree/perception/robot_proposer.h"
#include "colorfree/sim/runner.h"
#include "colorfree/sim/world_renderer.h"
#include "synthetic_field.h"

namespace colorfree {
namespace {

struct Fixture {
  sim::RenderedFrame rendered;
  std::unique_ptr<Frame> frame;
  RobotProposer proposer{RobotProposerParams::loadDefault(), FieldDimensions::loadDefault()};
  RobotDetector detector = RobotDetector::loadDefault();
  RobotOrientationEstimator orientation = RobotOrientationEstimator::loadDefault();
  RobotProposals proposals;
  std::vector<RobotPercept> robots;
  // The same frame with Gaussian noise of sigma 30 gray levels (a dark hall's high gain), with its
  // own contrast regions and noise estimate, for the proposer's smoothed scan.
  GrayImage noisy;
  std::unique_ptr<Frame> noisy_frame;

  Fixture() {
    sim::ScenarioRunner runner(sim::Scenario::load(std::string(COLORFREE_SOURCE_DIR) + "/scenes/ci/robot_bench.yaml"),
                               sim::worldRendererFactory());
    rendered = runner.render(0, 0, false);
    frame = std::make_unique<Frame>(rendered.image.view(), rendered.perception_camera);
    Pipeline(PipelineConfig::loadDefault()).process(*frame);
    proposals = proposer.run(frame->image, frame->camera, *frame->ignore_mask, *frame->contrast_regions);
    std::vector<RobotProposal> classified;
    robots = detector.run(frame->image, frame->camera, proposals.proposals, proposals.held_back,
                          &classified);
    noisy = rendered.image;
    test::addNoise(noisy, 30, 30);
    noisy_frame = std::make_unique<Frame>(noisy.view(), rendered.perception_camera);
    Pipeline(PipelineConfig::loadDefault()).process(*noisy_frame);
    std::fprintf(
        stderr, "bench frame: %zu proposals, %zu held back, %zu classified, %zu robots detected\n",
        proposals.proposals.size(), proposals.held_back.size(), classified.size(), robots.size());
  }
};

Fixture& fixture() {
  static Fixture f;
  return f;
}

void bmRobotProposals(benchmark::State& state) {
  Fixture& f = fixture();
  // With the frame's noise estimate, as the pipeline calls the stage (it estimates the noise once
  // per frame for the proposers).
  for (auto _ : state) {
    auto out = f.proposer.run(f.frame->image, f.frame->camera, *f.frame->ignore_mask,
                              *f.frame->contrast_regions, false, f.frame->pixel_noise_gray);
    benchmark::DoNotOptimize(out);
  }
  state.counters["proposals"] = static_cast<double>(f.proposals.proposals.size());
}

void bmRobotProposalsNoisy(benchmark::State& state) {
  Fixture& f = fixture();
  const Frame& n = *f.noisy_frame;
  for (auto _ : state) {
    auto out = f.proposer.run(n.image, n.camera, *n.ignore_mask, *n.contrast_regions, false,
                              n.pixel_noise_gray);
    benchmark::DoNotOptimize(out);
  }
  state.counters["proposals"] = static_cast<double>(n.robot_proposals->size());
}

void bmRobotClassification(benchmark::State& state) {
  Fixture& f = fixture();
  for (auto _ : state) {
    std::vector<RobotProposal> classified;
    auto out = f.detector.run(f.frame->image, f.frame->camera, f.proposals.proposals,
                              f.proposals.held_back, &classified);
    benchmark::DoNotOptimize(out);
  }
}

void bmRobotOrientation(benchmark::State& state) {
  Fixture& f = fixture();
  RobotTracks tracks;
  double t = 0;
  // The frame's field lines and features, as the pipeline gives them (the stage drops their edges
  // near feet).
  const FieldFeatures& field = f.frame->fieldFeatures();
  for (auto _ : state) {
    std::vector<RobotPercept> robots = f.robots;
    f.orientation.run(f.frame->image, f.frame->camera, robots, tracks, t, field);
    t += 1.0 / 30;
    benchmark::DoNotOptimize(robots);
  }
  state.counters["robots"] = static_cast<double>(f.robots.size());
}

BENCHMARK(bmRobotProposals)->Unit(benchmark::kMillisecond);
BENCHMARK(bmRobotProposalsNoisy)->Unit(benchmark::kMillisecond);
BENCHMARK(bmRobotClassification)->Unit(benchmark::kMillisecond);
BENCHMARK(bmRobotOrientation)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace colorfree

BENCHMARK_MAIN();
