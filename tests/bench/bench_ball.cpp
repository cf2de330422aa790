// Ball proposals and ball classification per frame, on one core (issue 6 speed goals: proposals
// ≤ 0.06 ms, classification ≤ 0.04 ms on a typical 640×480 frame). The frames are rendered at
// start: a typical one from scenes/ball_game.yaml (case 0, frame 1) and every frame of
// scenes/ball_hard.yaml, of which the mean and the maximum are printed at the end.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <ctime>
#include <optional>
#include <cstdio>
#include <string>
#include <vector>

#include "colorfree/perception/ball_detector.h"
#include "colorfree/perception/ball_proposer.h"
#include "colorfree/perception/pipeline.h"
#include "colorfree/sim/runner.h"
#include "colorfree/sim/scenario.h"
#include "colorfree/sim/world_renderer.h"

namespace {

using namespace colorfree;

struct BenchFrame {
  std::string name;
  GrayImage image;
  CameraModel camera;
  IgnoreMask ignore;
  ContrastRegions regions;
  // The frame's pixel noise and light, which the pipeline estimates once (its "ignore regions"
  // stage) for every stage that uses them, and gives the ball proposals.
  std::optional<double> noise_gray, light_gray;
  std::vector<BallProposal> proposals;
};

BenchFrame prepare(const std::string& name, sim::RenderedFrame f) {
  static const Pipeline early = [] {
    PipelineConfig c = PipelineConfig::loadDefault();
    c.ball_stages = false;
    return Pipeline(c);
  }();
  BenchFrame b;
  b.name = name;
  b.image = std::move(f.image);
  b.camera = f.perception_camera;
  Frame frame(b.image.view(), b.camera);
  early.process(frame);
  b.ignore = *frame.ignore_mask;
  b.regions = *frame.contrast_regions;
  b.noise_gray = frame.pixel_noise_gray;
  b.light_gray = frame.light_gray;
  return b;
}

const BallProposer& proposer() {
  static const BallProposer p(BallProposerParams::loadDefault());
  return p;
}
// The shipped proposer with the centre taken from the best vote cell alone (the centring before
// centre_ridge_fraction): the ridge's cost, measured in the same run.
const BallProposer& bestCellProposer() {
  static const BallProposer p([] {
    BallProposerParams q = BallProposerParams::loadDefault();
    q.centre_ridge_fraction = 0;
    return q;
  }());
  return p;
}
const BallDetector& detector() {
  static const BallDetector d = BallDetector::load(BallDetectorParams::loadDefault());
  return d;
}

std::vector<BenchFrame>& typicalFrames() {
  static std::vector<BenchFrame> frames;
  return frames;
}
std::vector<BenchFrame>& hardFrames() {
  static std::vector<BenchFrame> frames;
  return frames;
}

std::vector<BallProposal> propose(const BallProposer& p, const BenchFrame& f) {
  return p.run(f.image.view(), f.camera, f.ignore, f.regions, nullptr, f.noise_gray, f.light_gray);
}

// As in the pipeline: the frame's noise and light given.
void BM_BallProposals(benchmark::State& state, const BenchFrame* f) {
  for (auto _ : state) {
    auto p = propose(proposer(), *f);
    benchmark::DoNotOptimize(p.data());
  }
}

// The proposals estimating the frame's noise and light themselves (the benchmark before session 45
// timed this): the estimates' cost, measured in the same run.
void BM_BallProposalsOwnEstimates(benchmark::State& state, const BenchFrame* f) {
  for (auto _ : state) {
    auto p = proposer().run(f->image.view(), f->camera, f->ignore, f->regions, nullptr);
    benchmark::DoNotOptimize(p.data());
  }
}

void BM_BallProposalsBestCell(benchmark::State& state, const BenchFrame* f) {
  for (auto _ : state) {
    auto p = propose(bestCellProposer(), *f);
    benchmark::DoNotOptimize(p.data());
  }
}

void BM_BallClassification(benchmark::State& state, const BenchFrame* f) {
  for (auto _ : state) {
    auto b = detector().run(f->image.view(), f->camera, f->proposals);
    benchmark::DoNotOptimize(b.data());
  }
  state.counters["proposals"] = static_cast<double>(f->proposals.size());
}

// This thread's CPU time, ms (the machine is shared: wall-clock time would count the others' work).
double threadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

// Median of `reps` CPU timings of `fn`, ms.
template <typename F>
double medianMs(F&& fn, int reps) {
  std::vector<double> t;
  for (int i = 0; i < reps; ++i) {
    const double s = threadCpuMs();
    fn();
    t.push_back(threadCpuMs() - s);
  }
  std::nth_element(t.begin(), t.begin() + reps / 2, t.end());
  return t[reps / 2];
}

}  // namespace

int main(int argc, char** argv) {
  const std::string src = COLORFREE_SOURCE_DIR;
  {
    sim::ScenarioRunner game(sim::Scenario::load(src + "/scenes/ball_game.yaml"), sim::worldRendererFactory());
    typicalFrames().push_back(prepare("game case_000 frame 1", game.render(0, 1, false)));
    sim::ScenarioRunner hard(sim::Scenario::load(src + "/scenes/ball_hard.yaml"), sim::worldRendererFactory());
    for (int c = 0; c < hard.caseCount(); ++c) {
      hard.runCase(c, -1, false, [&](const sim::RenderedFrame& f) {
        hardFrames().push_back(prepare(hard.scenarioCase(c).name() + " frame " + std::to_string(f.frame_index), f));
      });
    }
  }
  for (auto* set : {&typicalFrames(), &hardFrames()}) {
    for (BenchFrame& f : *set) f.proposals = propose(proposer(), f);
  }
  const BenchFrame* typical = &typicalFrames().front();
  benchmark::RegisterBenchmark("BM_BallProposals/typical", BM_BallProposals, typical);
  benchmark::RegisterBenchmark("BM_BallProposalsOwnEstimates/typical", BM_BallProposalsOwnEstimates, typical);
  benchmark::RegisterBenchmark("BM_BallProposalsBestCell/typical", BM_BallProposalsBestCell, typical);
  benchmark::RegisterBenchmark("BM_BallClassification/typical", BM_BallClassification, typical);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();

  // The hard set: per frame the median of 200 runs; mean and maximum over the frames.
  double prop_sum = 0, prop_max = 0, cls_sum = 0, cls_max = 0;
  std::string prop_worst, cls_worst;
  for (const BenchFrame& f : hardFrames()) {
    const double p = medianMs([&] { benchmark::DoNotOptimize(propose(proposer(), f).size()); }, 200);
    const double c = medianMs([&] { benchmark::DoNotOptimize(detector().run(f.image.view(), f.camera, f.proposals).size()); }, 200);
    prop_sum += p;
    cls_sum += c;
    if (p > prop_max) prop_max = p, prop_worst = f.name;
    if (c > cls_max) cls_max = c, cls_worst = f.name;
  }
  const double n = static_cast<double>(std::max<std::size_t>(1, hardFrames().size()));
  std::printf("\nball_hard (%zu frames, median CPU time of 200 runs per frame):\n", hardFrames().size());
  std::printf("  ball proposals       mean %.4f ms  max %.4f ms (%s)   goal 0.06 ms typical\n", prop_sum / n, prop_max, prop_worst.c_str());
  std::printf("  ball classification  mean %.4f ms  max %.4f ms (%s)   goal 0.04 ms typical\n", cls_sum / n, cls_max, cls_worst.c_str());
  benchmark::Shutdown();
  return 0;
}
