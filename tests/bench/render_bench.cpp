// Render time per frame of the simulated NAO cameras: 640×480 and 320×240, with shadows and 4×
// anti-aliasing and without, frame only and frame plus object map.
#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <tuple>

#include "colorfree/sim/world.h"

namespace {

using colorfree::sim::NaoCamera;
using colorfree::sim::NaoState;
using colorfree::sim::SceneSpec;
using colorfree::sim::World;

// One world per quality setting, built once: building it (textures, GL context) is not rendering.
// quality: bit 0 shadows, bit 1 4× anti-aliasing.
World& worldFor(int quality) {
  static std::map<int, std::unique_ptr<World>> worlds;
  auto& w = worlds[quality];
  if (!w) {
    SceneSpec spec;
    spec.field = colorfree::FieldDimensions::loadDefault();
    spec.robot_count = 5;
    spec.shadows = (quality & 1) != 0;
    spec.multisamples = (quality & 2) != 0 ? 4 : 0;
    w = std::make_unique<World>(spec);
    NaoState obs;
    obs.pose = {1.6, -0.6, 0.15};
    obs.posture = colorfree::sim::walkPosture(0.3, 0.15);
    obs.posture.head_pitch = 0.2;
    w->setObserver(obs);
    const colorfree::FieldPose poses[] = {
        {3.4, 0.2, 3.0}, {2.6, -0.5, 1.6}, {3.9, 0.9, 3.3}, {2.3, 0.55, -2.3}, {4.3, 0.0, 3.14}};
    for (int i = 0; i < 5; ++i) {
      NaoState r;
      r.pose = poses[i];
      r.posture = colorfree::sim::walkPosture(0.17 * i, 0.15);
      w->setRobot(i, r);
    }
    w->setBall(Eigen::Vector3d(2.2, -0.75, 0.05), Eigen::Quaterniond::Identity());
  }
  return *w;
}

// Args: width, height, quality (0 plain, 1 shadows, 2 anti-aliasing, 3 both), object map (0/1).
void BM_Render(benchmark::State& state) {
  const int width = int(state.range(0)), height = int(state.range(1));
  World& world = worldFor(int(state.range(2)));
  const bool object_map = state.range(3) != 0;
  // The top camera: the view with the most in it (hall, goal, robots), at either size.
  const NaoCamera camera = NaoCamera::kTop;
  world.render(camera, width, height, object_map);  // first use compiles the GL state
  for (auto _ : state) {
    benchmark::DoNotOptimize(world.render(camera, width, height, object_map));
  }
  static const char* const kQuality[] = {"plain", "shadows", "msaa4", "shadows+msaa4"};
  state.SetLabel(std::string(kQuality[state.range(2) & 3]) + (object_map ? "+objectmap" : ""));
}
BENCHMARK(BM_Render)
    ->ArgNames({"w", "h", "quality", "objmap"})
    ->Args({640, 480, 3, 0})
    ->Args({640, 480, 1, 0})
    ->Args({640, 480, 2, 0})
    ->Args({640, 480, 0, 0})
    ->Args({320, 240, 3, 0})
    ->Args({320, 240, 0, 0})
    ->Args({640, 480, 3, 1})
    ->Args({320, 240, 0, 1})
    ->Args({640, 480, 0, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
