#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace colorfree::sim {

/// An 8-bit grey texture, rows top-down, generated procedurally and deterministically from a seed.
struct GrayTexture {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;

  std::uint8_t& at(int x, int y) { return pixels[static_cast<std::size_t>(y) * width + x]; }
};

/// Tileable carpet: fibre strokes, fine grain and low-frequency uneven shading. `size_px` square.
GrayTexture carpetTexture(std::uint64_t seed, int size_px);
/// The six faces of a cube map of a soccer ball (12 black pentagons on white), in MuJoCo's order
/// right, left, up, down, front, back (OpenGL +X, -X, +Y, -Y, +Z, -Z).
std::vector<GrayTexture> ballCubeFaces(int face_px);

/// Hall textures; `variant` picks a different look of the same kind.
enum class HallTexture { kWall, kBoard, kFloor, kWood, kCloth, kCeiling };
GrayTexture hallTexture(HallTexture kind, std::uint64_t seed, int variant, int width_px,
                        int height_px);

/// The texture in MuJoCo's custom texture file format (int32 width, int32 height, then RGB bytes
/// row by row): what MuJoCo loads from its virtual file system without decoding a PNG.
std::vector<std::uint8_t> encodeMujocoCustom(const GrayTexture& texture);

}  // namespace colorfree::sim
