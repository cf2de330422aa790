// The early perception stages (ignore regions, high-contrast regions, field lines and features)
// per 640×480 frame on frames the simulator renders (issue 4's speed goals are for rendered
// frames): scenes/game.yaml (both cameras, six lighting presets, three frames each) and the
// noisy and blurred ends of scenes/sweeps/camera_noise.yaml and motion_blur.yaml. The frames are
// rendered at start. Run pinned to one core:
//   taskset -c 0 build/bin/bench_perception_rendered --benchmark_repetitions=5
// After Google Benchmark's table, per stage the median, mean and max over the frames.
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "bench_perception_summary.h"
#include "colorfree/perception/field_lines.h"
#include "colorfree/perception/high_contrast.h"
#include "colorfree/perception/ignore_regions.h"
#include "colorfree/sim/runner.h"
#include "colorfree/sim/scenario.h"
#include "colorfree/sim/world_renderer.h"

namespace colorfree {
namespace {

struct BenchFrame {
  std::string name;
  GrayImage image;
  CameraModel camera;
  IgnoreMask ignore;
};

const FieldBoundaryDetector& boundary() {
  static const FieldBoundaryDetector d(FieldBoundaryParams::loadDefault());
  return d;
}
const BodyContourProvider& body() {
  static const BodyContourProvider d(BodyModelParams::loadDefault());
  return d;
}
const HighContrastDetector& highContrast() {
  static const HighContrastDetector d(HighContrastParams::loadDefault());
  return d;
}
const FieldLineDetector& fieldLines() {
  static const FieldLineDetector d(FieldLineParams::loadDefault(), FieldDimensions::loadDefault());
  return d;
}

std::vector<BenchFrame>& frames() {
  static std::vector<BenchFrame> all;
  return all;
}

void addFrames(const std::string& scenario, const std::vector<int>& cases, const std::vector<int>& frame_indices) {
  sim::ScenarioRunner runner(sim::Scenario::load(std::string(COLORFREE_SOURCE_DIR) + "/" + scenario),
                             sim::worldRendererFactory());
  std::vector<int> all_cases = cases;
  if (all_cases.empty()) {
    for (int c = 0; c < runner.caseCount(); ++c) all_cases.push_back(c);
  }
  for (int c : all_cases) {
    for (int f : frame_indices) {
      sim::RenderedFrame r = runner.render(c, f, false);
      BenchFrame b;
      b.name = runner.scenario().name + "_" + runner.scenarioCase(c).name() + "_f" + std::to_string(f);
      b.camera = r.perception_camera;
      b.image = std::move(r.image);
      b.ignore = IgnoreMask::combine(boundary().run(b.image.view(), b.camera), body().run(b.camera),
                                     b.image.width(), b.image.height());
      frames().push_back(std::move(b));
    }
  }
}

void bmIgnoreRegions(benchmark::State& state, const BenchFrame* f) {
  for (auto _ : state) {
    benchmark::DoNotOptimize(boundary().run(f->image.view(), f->camera));
    benchmark::DoNotOptimize(body().run(f->camera));
  }
}

void bmHighContrast(benchmark::State& state, const BenchFrame* f) {
  for (auto _ : state) benchmark::DoNotOptimize(highContrast().run(f->image.view(), f->ignore));
}

void bmFieldLines(benchmark::State& state, const BenchFrame* f) {
  std::size_t lines = 0;
  for (auto _ : state) {
    auto r = fieldLines().run(f->image.view(), f->camera, f->ignore);
    lines = r.features.lines.size();
    benchmark::DoNotOptimize(r);
  }
  state.counters["lines"] = static_cast<double>(lines);
}

}  // namespace
}  // namespace colorfree

int main(int argc, char** argv) {
  using namespace colorfree;
  addFrames("scenes/game.yaml", {}, {0, 7, 14});
  addFrames("scenes/sweeps/camera_noise.yaml", {3, 5, 6}, {1});  // noise sigma 10, 25, 40
  addFrames("scenes/sweeps/motion_blur.yaml", {2, 4}, {1});      // exposure 20 ms, 60 ms
  for (const BenchFrame& f : frames()) {
    benchmark::RegisterBenchmark(("IgnoreRegions/" + f.name).c_str(), bmIgnoreRegions, &f)->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("HighContrast/" + f.name).c_str(), bmHighContrast, &f)->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("FieldLines/" + f.name).c_str(), bmFieldLines, &f)->Unit(benchmark::kMicrosecond);
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  bench::StageSummaryReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  reporter.printSummary((std::to_string(frames().size()) + " rendered frames").c_str());
  benchmark::Shutdown();
  return 0;
}
