#include "textures.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <random>

#include "colorfree/perception/error.h"

namespace colorfree::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;

// A float image with wrap-around access, so that the textures tile without seams.
struct Canvas {
  int w, h;
  std::vector<float> v;
  Canvas(int width, int height, float fill)
      : w(width), h(height), v(std::size_t(width) * height, fill) {}
  float& at(int x, int y) {
    x = ((x % w) + w) % w;
    y = ((y % h) + h) % h;
    return v[std::size_t(y) * w + x];
  }
};

double smooth(double t) { return t * t * (3 - 2 * t); }

// Periodic value noise with `cells_x` × `cells_y` lattice cells over the canvas, amplitude ±amp.
void addValueNoise(Canvas& c, std::mt19937_64& rng, int cells_x, int cells_y, double amp) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> lattice(std::size_t(cells_x) * cells_y);
  for (auto& l : lattice) l = u(rng);
  const auto lat = [&](int i, int j) {
    return lattice[std::size_t((j + cells_y) % cells_y) * cells_x + (i + cells_x) % cells_x];
  };
  for (int y = 0; y < c.h; ++y) {
    const double fy = double(y) / c.h * cells_y;
    const int j = int(fy);
    const double ty = smooth(fy - j);
    for (int x = 0; x < c.w; ++x) {
      const double fx = double(x) / c.w * cells_x;
      const int i = int(fx);
      const double tx = smooth(fx - i);
      const double a = lat(i, j) + (lat(i + 1, j) - lat(i, j)) * tx;
      const double b = lat(i, j + 1) + (lat(i + 1, j + 1) - lat(i, j + 1)) * tx;
      c.v[std::size_t(y) * c.w + x] += float(amp * (a + (b - a) * ty));
    }
  }
}

void addGrain(Canvas& c, std::mt19937_64& rng, double amp) {
  std::uniform_real_distribution<double> u(-amp, amp);
  for (auto& p : c.v) p += float(u(rng));
}

// Short straight strokes of random direction: carpet fibres, wood grain, fabric.
void addStrokes(Canvas& c, std::mt19937_64& rng, int count, double min_len, double max_len,
                double min_delta, double max_delta, double angle_mean, double angle_spread) {
  std::uniform_real_distribution<double> ux(0, c.w), uy(0, c.h), ul(min_len, max_len),
      ud(min_delta, max_delta), ua(angle_mean - angle_spread, angle_mean + angle_spread),
      usign(0, 1);
  for (int k = 0; k < count; ++k) {
    const double x0 = ux(rng), y0 = uy(rng), len = ul(rng), a = ua(rng);
    const double delta = ud(rng) * (usign(rng) < 0.5 ? -1 : 1);
    const int steps = std::max(1, int(len));
    for (int s = 0; s <= steps; ++s) {
      const double t = double(s) / steps;
      // Fibres fade towards their tips.
      const double fade = 1.0 - 0.6 * std::abs(2 * t - 1);
      c.at(int(std::floor(x0 + t * len * std::cos(a))),
           int(std::floor(y0 + t * len * std::sin(a)))) += float(delta * fade);
    }
  }
}

GrayTexture toTexture(const Canvas& c) {
  GrayTexture t;
  t.width = c.w;
  t.height = c.h;
  t.pixels.resize(c.v.size());
  for (std::size_t i = 0; i < c.v.size(); ++i) {
    t.pixels[i] = std::uint8_t(std::lround(std::clamp(double(c.v[i]), 0.0, 1.0) * 255));
  }
  return t;
}

void fillRect(Canvas& c, int x0, int y0, int x1, int y1, float value) {
  for (int y = std::max(0, y0); y < std::min(c.h, y1); ++y) {
    for (int x = std::max(0, x0); x < std::min(c.w, x1); ++x) c.v[std::size_t(y) * c.w + x] = value;
  }
}

}  // namespace

GrayTexture carpetTexture(std::uint64_t seed, int size_px) {
  if (size_px < 16) throw Error("carpet texture: size must be at least 16 px");
  std::mt19937_64 rng(seed ^ 0xC0A7E7ULL);
  Canvas c(size_px, size_px, 0.5f);
  // Uneven shading over the tile (worn, brushed patches), then fibres and grain.
  addValueNoise(c, rng, 2, 2, 0.10);
  addValueNoise(c, rng, 5, 5, 0.07);
  addValueNoise(c, rng, 13, 13, 0.05);
  addValueNoise(c, rng, size_px / 24, size_px / 24, 0.05);
  addGrain(c, rng, 0.07);
  const int area = size_px * size_px;
  addStrokes(c, rng, area / 5, 2, 6, 0.04, 0.14, 0, kPi);
  // A few bright loose fibres as seen in real bottom-camera frames.
  addStrokes(c, rng, area / 400, 2, 5, 0.25, 0.35, 0, kPi);
  return toTexture(c);
}

std::vector<GrayTexture> ballCubeFaces(int face_px) {
  if (face_px < 8) throw Error("ball texture: face size must be at least 8 px");
  // Icosahedron vertices: the centres of the 12 pentagons of a truncated icosahedron.
  const double phi = (1 + std::sqrt(5.0)) / 2;
  std::vector<std::array<double, 3>> verts;
  for (int s1 : {-1, 1}) {
    for (int s2 : {-1, 1}) {
      verts.push_back({0, double(s1), s2 * phi});
      verts.push_back({double(s1), s2 * phi, 0});
      verts.push_back({s2 * phi, 0, double(s1)});
    }
  }
  for (auto& v : verts) {
    const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    for (auto& x : v) x /= n;
  }
  const auto dot = [](const std::array<double, 3>& a, const std::array<double, 3>& b) {
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  };
  // For each pentagon: the tangent-plane directions to its five neighbours (the pentagon's
  // corners point at them; its edge normals point away from them).
  const double neighbour_dot = 1 / std::sqrt(5.0);
  std::vector<std::vector<std::array<double, 3>>> corner_dirs(verts.size());
  for (std::size_t i = 0; i < verts.size(); ++i) {
    for (std::size_t j = 0; j < verts.size(); ++j) {
      if (i == j || std::abs(dot(verts[i], verts[j]) - neighbour_dot) > 1e-6) continue;
      std::array<double, 3> t;
      const double d = dot(verts[i], verts[j]);
      for (int k = 0; k < 3; ++k) t[k] = verts[j][k] - d * verts[i][k];
      const double n = std::sqrt(dot(t, t));
      for (auto& x : t) x /= n;
      corner_dirs[i].push_back(t);
    }
  }
  // Pentagon circumradius in the gnomonic tangent plane (truncated icosahedron, unit sphere).
  const double circum = std::tan(20.07 * kPi / 180);
  const double apothem = circum * std::cos(kPi / 5);
  // Samples per texel for smooth pentagon edges.
  constexpr int kSuper = 3;
  std::vector<GrayTexture> faces(6);
  for (int f = 0; f < 6; ++f) {
    GrayTexture& tex = faces[f];
    tex.width = tex.height = face_px;
    tex.pixels.assign(std::size_t(face_px) * face_px, 0);
    for (int y = 0; y < face_px; ++y) {
      for (int x = 0; x < face_px; ++x) {
        int black = 0;
        for (int sy = 0; sy < kSuper; ++sy) {
          for (int sx = 0; sx < kSuper; ++sx) {
            const double sc = 2 * (x + (sx + 0.5) / kSuper) / face_px - 1;
            const double tc = 2 * (y + (sy + 0.5) / kSuper) / face_px - 1;
            // OpenGL cube-map face directions.
            std::array<double, 3> r;
            switch (f) {
              case 0:
                r = {1, -tc, -sc};
                break;
              case 1:
                r = {-1, -tc, sc};
                break;
              case 2:
                r = {sc, 1, tc};
                break;
              case 3:
                r = {sc, -1, -tc};
                break;
              case 4:
                r = {sc, -tc, 1};
                break;
              default:
                r = {-sc, -tc, -1};
                break;
            }
            const double n = std::sqrt(dot(r, r));
            for (auto& v : r) v /= n;
            std::size_t best = 0;
            for (std::size_t i = 1; i < verts.size(); ++i) {
              if (dot(r, verts[i]) > dot(r, verts[best])) best = i;
            }
            const double c = dot(r, verts[best]);
            bool inside = true;
            for (const auto& u : corner_dirs[best]) {
              // Gnomonic projection onto the tangent plane at the pentagon's centre.
              if (-dot(r, u) / c > apothem) inside = false;
            }
            black += inside ? 1 : 0;
          }
        }
        const double white = 0.93, dark = 0.06;
        const double a = double(black) / (kSuper * kSuper);
        tex.at(x, y) = std::uint8_t(std::lround(255 * (white + (dark - white) * a)));
      }
    }
  }
  return faces;
}

GrayTexture hallTexture(HallTexture kind, std::uint64_t seed, int variant, int width_px,
                        int height_px) {
  if (width_px < 8 || height_px < 8) throw Error("hall texture: size must be at least 8 px");
  std::mt19937_64 rng(seed * 7919 + std::uint64_t(kind) * 104729 +
                      std::uint64_t(variant) * 15485863);
  std::uniform_real_distribution<double> u(0, 1);
  switch (kind) {
    case HallTexture::kWall: {
      Canvas c(width_px, height_px, float(0.55 + 0.25 * u(rng)));
      addValueNoise(c, rng, 4, 4, 0.05);
      addGrain(c, rng, 0.03);
      // Panel seams and a darker skirting band at the bottom.
      const int panel = std::max(8, width_px / 8);
      for (int x = 0; x < width_px; x += panel) fillRect(c, x, 0, x + 2, height_px, 0.3f);
      fillRect(c, 0, height_px * 7 / 8, width_px, height_px, 0.25f);
      return toTexture(c);
    }
    case HallTexture::kBoard: {
      // A sponsor board: light background, rows of dark letter-like blocks, a logo block.
      const bool dark_bg = u(rng) < 0.3;
      Canvas c(width_px, height_px, dark_bg ? 0.2f : 0.85f);
      const float ink = dark_bg ? 0.9f : 0.1f;
      const int rows = 1 + int(u(rng) * 2);
      for (int r = 0; r < rows; ++r) {
        const int y0 = height_px * (2 * r + 1) / (2 * rows + 1);
        const int y1 = y0 + height_px / (2 * rows + 2);
        int x = width_px / 10;
        while (x < width_px * 9 / 10) {
          const int w = int(width_px * (0.01 + 0.03 * u(rng)));
          if (u(rng) < 0.85) fillRect(c, x, y0, x + w, y1, ink);
          x += w + int(width_px * (0.005 + 0.02 * u(rng)));
        }
      }
      addGrain(c, rng, 0.02);
      return toTexture(c);
    }
    case HallTexture::kFloor: {
      Canvas c(width_px, height_px, 0.42f);
      addValueNoise(c, rng, 3, 3, 0.06);
      addValueNoise(c, rng, 17, 17, 0.04);
      addGrain(c, rng, 0.05);
      return toTexture(c);
    }
    case HallTexture::kWood: {
      Canvas c(width_px, height_px, float(0.45 + 0.25 * u(rng)));
      addValueNoise(c, rng, 2, 12, 0.06);
      addStrokes(c, rng, width_px * height_px / 20, width_px / 8.0, width_px / 3.0, 0.01, 0.04, 0,
                 0.05);
      return toTexture(c);
    }
    case HallTexture::kCloth: {
      Canvas c(width_px, height_px, float(0.1 + 0.75 * u(rng)));
      const double pattern = u(rng);
      if (pattern < 0.35) {
        // Stripes.
        const int period = 6 + int(u(rng) * 20);
        const float stripe = float(0.1 + 0.8 * u(rng));
        for (int y = 0; y < height_px; ++y) {
          if ((y / period) % 2 == 0) fillRect(c, 0, y, width_px, y + 1, stripe);
        }
      } else if (pattern < 0.55) {
        // A printed logo on the chest.
        fillRect(c, width_px / 3, height_px / 4, width_px * 2 / 3, height_px / 2,
                 float(0.1 + 0.8 * u(rng)));
      }
      addValueNoise(c, rng, 6, 6, 0.05);
      addGrain(c, rng, 0.04);
      return toTexture(c);
    }
    case HallTexture::kCeiling: {
      Canvas c(width_px, height_px, 0.3f);
      const int beam = std::max(8, width_px / 6);
      for (int x = 0; x < width_px; x += beam) fillRect(c, x, 0, x + 3, height_px, 0.15f);
      addGrain(c, rng, 0.03);
      return toTexture(c);
    }
  }
  throw Error("hall texture: unknown kind");
}

std::vector<std::uint8_t> encodeMujocoCustom(const GrayTexture& texture) {
  std::vector<std::uint8_t> bytes(8 + texture.pixels.size() * 3);
  const std::int32_t size[2] = {texture.width, texture.height};
  std::memcpy(bytes.data(), size, sizeof(size));
  std::uint8_t* rgb = bytes.data() + 8;
  for (std::size_t i = 0; i < texture.pixels.size(); ++i) {
    rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = texture.pixels[i];
  }
  return bytes;
}

}  // namespace colorfree::sim
