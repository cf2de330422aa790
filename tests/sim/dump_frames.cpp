// Dev tool: renders a game-like scene from the top and bottom camera under every lighting preset
// and writes the frames (and object maps) as PNG, to look at them next to real NAO frames.
// Usage: sim_dump_frames OUT_DIR [WIDTH HEIGHT]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "colorfree/perception/error.h"
#include "colorfree/perception/image.h"
#include "colorfree/sim/world.h"

using namespace colorfree;
using namespace colorfree::sim;

namespace {

GrayImage labelImage(const ObjectMap& map) {
  GrayImage img(map.width, map.height);
  for (int y = 0; y < map.height; ++y) {
    for (int x = 0; x < map.width; ++x) {
      const int l = map.at(x, y);
      img.at(x, y) =
          std::uint8_t(l >= kObjectRobotBase ? 120 + 12 * (l - kObjectRobotBase) : l * 40);
    }
  }
  return img;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s OUT_DIR [WIDTH HEIGHT]\n", argv[0]);
    return 2;
  }
  const std::string out = argv[1];
  const int width = argc > 3 ? std::atoi(argv[2]) : 640;
  const int height = argc > 3 ? std::atoi(argv[3]) : 480;
  try {
    std::filesystem::create_directories(out);
    for (const char* preset :
         {"normal", "dim", "overexposed", "directional", "uneven", "flicker"}) {
      SceneSpec spec;
      spec.field = FieldDimensions::loadDefault();
      spec.robot_count = 5;
      spec.jersey_gray = {0.15, 0.15, 0.8, 0.8, 0.5};
      spec.lighting = lightingPresetFromName(preset);
      spec.seed = 7;
      const auto t0 = std::chrono::steady_clock::now();
      World world(spec);
      const auto t1 = std::chrono::steady_clock::now();
      std::printf("%s: world built in %.0f ms\n", preset,
                  std::chrono::duration<double, std::milli>(t1 - t0).count());
      NaoState obs;
      obs.pose = {1.6, -0.6, 0.15};
      obs.posture = walkPosture(0.3, 0.15);
      obs.posture.head_pitch = 0.25;
      obs.posture.head_yaw = 0.1;
      world.setObserver(obs);
      const FieldPose poses[] = {
          {3.4, 0.2, 3.0}, {2.6, -0.5, 1.6}, {3.9, 0.9, 3.3}, {2.3, 0.55, -2.3}, {4.3, 0.0, 3.14}};
      for (int i = 0; i < 5; ++i) {
        NaoState r;
        r.pose = poses[i];
        r.posture = walkPosture(0.17 * i, i % 2 == 0 ? 0.15 : 0.0);
        world.setRobot(i, r);
      }
      world.setBall(
          Eigen::Vector3d(1.98, -0.62, spec.field.ballRadius()),
          Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())));
      if (std::string(preset) == "flicker") world.setLighting({flickerScale(spec.seed, 3)});
      for (const auto cam : {NaoCamera::kTop, NaoCamera::kBottom, NaoCamera::kTop}) {
        const bool wide = cam == NaoCamera::kTop && obs.posture.head_pitch == 0.45;
        const std::string name = out + "/" + preset +
                                 (wide                     ? "_wide"
                                  : cam == NaoCamera::kTop ? "_top"
                                                           : "_bottom");
        if (wide) {
          // From the centre circle towards the side with the people and the goal.
          obs.pose = {-1.2, -0.4, 0.5};
          obs.posture.head_yaw = 0.2;
        }
        // The bottom camera with the head pitched down, so the own feet show.
        obs.posture.head_pitch = wide ? 0.1 : cam == NaoCamera::kTop ? 0.2 : 0.45;
        world.setObserver(obs);
        const RenderOutput r = world.render(cam, width, height, true);
        writeGrayPng(name + ".png", r.gray.view());
        // Mean luma per object label, to compare grey levels with real frames.
        double sum[32] = {}, count[32] = {};
        for (int y = 0; y < r.gray.height(); ++y) {
          for (int x = 0; x < r.gray.width(); ++x) {
            const int l = std::min<int>(r.object_map.at(x, y), kObjectRobotBase);
            sum[l] += r.gray.at(x, y);
            count[l] += 1;
          }
        }
        std::printf(
            "  %s: none %.0f carpet %.0f line %.0f goal %.0f ball %.0f own %.0f robots %.0f\n",
            wide                     ? "wide"
            : cam == NaoCamera::kTop ? "top"
                                     : "bottom",
            sum[0] / std::max(1.0, count[0]), sum[1] / std::max(1.0, count[1]),
            sum[2] / std::max(1.0, count[2]), sum[3] / std::max(1.0, count[3]),
            sum[4] / std::max(1.0, count[4]), sum[5] / std::max(1.0, count[5]),
            sum[16] / std::max(1.0, count[16]));
        writeGrayPng(name + "_objects.png", labelImage(r.object_map).view());
      }
    }
  } catch (const std::exception& e) {  // colorfree's Error, or the folder that cannot be made
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  return 0;
}
