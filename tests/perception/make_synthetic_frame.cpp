// Writes a synthetic field frame and its camera file, to try `colorfree detect` on:
//   make_synthetic_frame OUT.png OUT_CAMERA.yaml [x_m y_m theta_deg pitch_deg gradient seed pixel_noise]
#include <cstdio>
#include <cstdlib>
#include <string>

#include "colorfree/perception/error.h"
#include "synthetic_field.h"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s OUT.png OUT_CAMERA.yaml [x_m y_m theta_deg pitch_deg gradient seed pixel_noise]\n", argv[0]);
    return 2;
  }
  const auto arg = [&](int i, double fallback) { return argc > i ? std::atof(argv[i]) : fallback; };
  try {
    const colorfree::FieldPose pose{arg(3, -2.0), arg(4, 0.0), arg(5, 0.0) * 3.14159265358979323846 / 180};
    const colorfree::CameraModel camera = colorfree::test::testCamera(arg(6, 22));
    colorfree::test::SyntheticScene scene =
        colorfree::test::sceneFromField(colorfree::FieldDimensions::loadDefault(), pose);
    scene.gradient = arg(7, 0);
    scene.seed = static_cast<std::uint64_t>(arg(8, 1));
    scene.carpet_edge_m = 1e9;
    scene.pixel_noise = arg(9, scene.pixel_noise);
    const colorfree::GrayImage image = colorfree::test::renderScene(camera, scene);
    colorfree::writeGrayPng(argv[1], image.view());
    camera.save(argv[2]);
  } catch (const colorfree::Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 2;
  }
  return 0;
}
