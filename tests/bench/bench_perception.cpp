// Perception stages per 640×480 frame on a varied set of synthetic field frames (poses, light
// gradients, noise). Run pinned to one core: `taskset -c 0 build/bin/bench_perception`.
// After Google Benchmark's own table, a summary per stage (bench_perception_summary.h).
// bench_perception_rendered does the same on frames the simulator renders.
#include <benchmark/benchmark.h>

#include <memory>
#include <string>
#include <vector>

#include "colorfree/perception/field_lines.h"
#include "colorfree/perception/high_contrast.h"
#include "colorfree/perception/ignore_regions.h"
#include "colorfree/perception/pipeline.h"
#include "bench_perception_summary.h"
#include "synthetic_field.h"

namespace colorfree {
namespace {

constexpr double kPi = 3.14159265358979323846;

struct BenchFrame {
  std::string name;
  CameraModel camera;
  GrayImage image;
  IgnoreMask ignore;
};

const std::vector<BenchFrame>& frames() {
  static const std::vector<BenchFrame> all = [] {
    struct Spec {
      FieldPose pose;
      double pitch_deg, gradient;
      std::uint64_t seed;
      double carpet_edge_m;
    };
    const Spec specs[] = {
        {{-2.0, 0.0, 0.0}, 22, 0.0, 1, 1e9},
        {{1.6, 0.4, -10 * kPi / 180}, 25, 0.3, 2, 1e9},
        {{2.3, 1.0, 20 * kPi / 180}, 25, 0.0, 3, 1e9},
        {{-3.5, 2.0, 150 * kPi / 180}, 22, 0.5, 4, 1e9},
        {{0.0, -1.5, 90 * kPi / 180}, 20, 0.0, 5, 1e9},
        {{-1.0, 0.5, 0.4}, 12, 0.2, 6, 4.0},
        {{3.0, -2.0, 0.8}, 30, 0.4, 7, 1e9},
        {{-4.0, -2.5, -2.6}, 20, 0.0, 8, 1e9},
        {{0.5, 0.0, 3.1}, 18, 0.6, 9, 5.0},
        {{-2.5, 2.8, -1.2}, 24, 0.1, 10, 1e9},
        {{4.0, 0.0, 0.0}, 35, 0.0, 11, 1e9},
        {{-0.8, -0.8, 0.8}, 16, 0.3, 12, 3.5},
    };
    std::vector<BenchFrame> out;
    int i = 0;
    for (const Spec& s : specs) {
      const CameraModel cam = test::testCamera(s.pitch_deg);
      test::SyntheticScene scene = test::sceneFromField(FieldDimensions{}, s.pose);
      scene.gradient = s.gradient;
      scene.seed = s.seed;
      scene.carpet_edge_m = s.carpet_edge_m;
      GrayImage image = test::renderScene(cam, scene);
      IgnoreMask ignore = IgnoreMask::combine(FieldBoundaryDetector().run(image.view(), cam),
                                              BodyContourProvider().run(cam), 640, 480);
      out.push_back({"frame" + std::to_string(i++), cam, std::move(image), std::move(ignore)});
    }
    return out;
  }();
  return all;
}

void bmHighContrast(benchmark::State& state, int i) {
  const BenchFrame& f = frames()[i];
  const HighContrastDetector detector;
  for (auto _ : state) benchmark::DoNotOptimize(detector.run(f.image.view(), f.ignore));
}

void bmFieldLines(benchmark::State& state, int i) {
  const BenchFrame& f = frames()[i];
  const FieldLineDetector detector;
  std::size_t lines = 0;
  for (auto _ : state) {
    auto r = detector.run(f.image.view(), f.camera, f.ignore);
    lines = r.features.lines.size();
    benchmark::DoNotOptimize(r);
  }
  state.counters["lines"] = static_cast<double>(lines);
}

void bmIgnoreRegions(benchmark::State& state, int i) {
  const BenchFrame& f = frames()[i];
  const FieldBoundaryDetector boundary;
  const BodyContourProvider body;
  for (auto _ : state) {
    benchmark::DoNotOptimize(boundary.run(f.image.view(), f.camera));
    benchmark::DoNotOptimize(body.run(f.camera));
  }
}

void bmPipeline(benchmark::State& state, int i) {
  const BenchFrame& f = frames()[i];
  const Pipeline pipeline(PipelineConfig{});
  for (auto _ : state) {
    Frame frame(f.image.view(), f.camera);
    pipeline.process(frame);
    benchmark::DoNotOptimize(frame.field_lines);
  }
}

}  // namespace
}  // namespace colorfree

int main(int argc, char** argv) {
  using namespace colorfree;
  const int n = static_cast<int>(frames().size());
  for (int i = 0; i < n; ++i) {
    benchmark::RegisterBenchmark(("HighContrast/" + frames()[i].name).c_str(), bmHighContrast, i)->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("FieldLines/" + frames()[i].name).c_str(), bmFieldLines, i)->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("IgnoreRegions/" + frames()[i].name).c_str(), bmIgnoreRegions, i)->Unit(benchmark::kMicrosecond);
    benchmark::RegisterBenchmark(("Pipeline/" + frames()[i].name).c_str(), bmPipeline, i)->Unit(benchmark::kMicrosecond);
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  bench::StageSummaryReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  reporter.printSummary((std::to_string(frames().size()) + " synthetic frames").c_str());
  benchmark::Shutdown();
  return 0;
}
