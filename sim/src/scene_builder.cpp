#include "scene_builder.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>

#include "colorfree/perception/error.h"
#include "nao_model.h"
#include "textures.h"

namespace colorfree::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Look of the field and the hall. Sizes of the field itself come from FieldDimensions only.
constexpr int kCarpetTexturePx = 1024;
constexpr double kCarpetTileM = 1.3;
constexpr int kBallFacePx = 128;
constexpr double kCarpetGridM = 0.2;          // plane tessellation: per-vertex lighting resolution
constexpr double kCarpetGridPatchesM = 0.06;  // finer where sun patches need sharp edges
constexpr double kCarpetTopZ = -0.001;        // carpet just below z = 0 so lines sit on top of it
constexpr double kLineTopZ = 0.0;  // the lines' top is the ground plane the camera model sees
// Line boxes reach well below the carpet: their bottom faces then stay clear of the carpet in
// the shadow map (no shadow acne on the lines).
constexpr double kLineBottomZ = -0.02;
constexpr double kFloorZ = -0.004;
constexpr double kHallMarginXM = 4.5;  // carpet edge to end wall
constexpr double kHallMarginYM = 3.5;  // carpet edge to side wall
constexpr double kHallHeightM = 4.5;
constexpr int kCircleSegments = 64;
// Tessellation: llvmpipe's vertex work grows with the triangles of every round geom (NAOs,
// people).
constexpr int kRoundSlices = 16;
constexpr int kRoundStacks = 8;
constexpr int kBoxQuads = 2;
constexpr double kNetSpacingM = 0.1;
constexpr double kNetStringRadiusM = 0.004;
constexpr int kPeople = 12;
constexpr int kClothVariants = 8;
constexpr int kBoardVariants = 4;
// Grey levels (material rgba) chosen so that the normal preset gives luma values close to a NAO's
// view of an SPL field: carpet about 80..100, lines about 200..220, robots near white.
constexpr double kCarpetGray = 0.47;
constexpr double kLineGray = 0.62;

std::string f(double x) {
  std::ostringstream o;
  o.setf(std::ios::fixed);
  o.precision(5);
  o << x;
  return o.str();
}

std::string f3(double a, double b, double c) { return f(a) + " " + f(b) + " " + f(c); }

class SceneWriter {
 public:
  std::ostringstream assets, world;
  SceneModel model;
  int geom_count = 0;

  void texture2d(const std::string& name, const GrayTexture& tex) {
    const std::string file = name + ".tex";
    model.files[file] = encodeMujocoCustom(tex);
    assets << "<texture name=\"" << name << "\" type=\"2d\" file=\"" << file << "\"/>\n";
  }
  void material(const std::string& name, const std::string& texture, double gray, double texrepeat,
                double specular = 0.0, double shininess = 0.1, double emission = 0.0) {
    assets << "<material name=\"" << name << "\"";
    if (!texture.empty()) {
      assets << " texture=\"" << texture << "\" texuniform=\"true\" texrepeat=\"" << f(texrepeat)
             << " " << f(texrepeat) << "\"";
    }
    assets << " rgba=\"" << f3(gray, gray, gray) << " 1\" specular=\"" << f(specular)
           << "\" shininess=\"" << f(shininess) << "\" reflectance=\"0\" emission=\"" << f(emission)
           << "\"/>\n";
  }
  void geom(const std::string& prefix, const std::string& type, const std::string& attrs,
            const std::string& material) {
    world << "<geom name=\"" << prefix << geom_count++ << "\" type=\"" << type << "\" " << attrs
          << " material=\"" << material << "\"/>\n";
  }
  void box(const std::string& prefix, double x, double y, double z, double hx, double hy, double hz,
           double yaw, const std::string& material) {
    geom(prefix, "box",
         "pos=\"" + f3(x, y, z) + "\" size=\"" + f3(hx, hy, hz) + "\" euler=\"0 0 " + f(yaw) + "\"",
         material);
  }
  void capsule(const std::string& prefix, double x0, double y0, double z0, double x1, double y1,
               double z1, double r, const std::string& material) {
    geom(prefix, "capsule",
         "fromto=\"" + f3(x0, y0, z0) + " " + f3(x1, y1, z1) + "\" size=\"" + f(r) + "\"",
         material);
  }
  void cylinder(const std::string& prefix, double x0, double y0, double z0, double x1, double y1,
                double z1, double r, const std::string& material) {
    geom(prefix, "cylinder",
         "fromto=\"" + f3(x0, y0, z0) + " " + f3(x1, y1, z1) + "\" size=\"" + f(r) + "\"",
         material);
  }
  void light(const Eigen::Vector3d& pos, const Eigen::Vector3d& dir, bool directional, bool shadow,
             double diffuse, double cutoff_deg = 45) {
    const Eigen::Vector3d d = dir.normalized();
    const double specular = diffuse * 0.15;
    world << "<light pos=\"" << f3(pos.x(), pos.y(), pos.z()) << "\" dir=\""
          << f3(d.x(), d.y(), d.z()) << "\" directional=\"" << (directional ? "true" : "false")
          << "\" castshadow=\"" << (shadow ? "true" : "false") << "\" diffuse=\""
          << f3(diffuse, diffuse, diffuse) << "\" specular=\"" << f3(specular, specular, specular)
          << "\" ambient=\"0 0 0\" cutoff=\"" << f(cutoff_deg) << "\" exponent=\"0\"/>\n";
    LightBase base{};
    for (int i = 0; i < 3; ++i) {
      base.diffuse[i] = float(diffuse);
      base.specular[i] = float(specular);
    }
    model.lights.push_back(base);
  }
};

// Many boxes as one mesh geom: one draw call instead of one per box (llvmpipe spends tens of
// microseconds on each). Every face has its own four vertices so that it is shaded flat.
class BoxMesh {
 public:
  // Boxes longer than this along their first axis are cut into pieces: lighting is computed per
  // vertex, so a long line needs vertices along it to show light patches.
  double max_piece_m = 1e9;

  // Box at `c` with unit axes (columns, right-handed) and half sizes along them.
  void add(const Eigen::Vector3d& c, const Eigen::Matrix3d& axes, const Eigen::Vector3d& half) {
    const int pieces = int(std::ceil(2 * half[0] / max_piece_m));
    if (pieces > 1) {
      const double piece_half = half[0] / pieces;
      for (int i = 0; i < pieces; ++i) {
        const double offset = -half[0] + (2 * i + 1) * piece_half;
        addOne(c + offset * axes.col(0), axes, Eigen::Vector3d(piece_half, half[1], half[2]));
      }
      return;
    }
    addOne(c, axes, half);
  }

 private:
  void addOne(const Eigen::Vector3d& c, const Eigen::Matrix3d& axes, const Eigen::Vector3d& half) {
    for (int i = 0; i < 3; ++i) {
      const int j = (i + 1) % 3, k = (i + 2) % 3;
      for (double sign : {1.0, -1.0}) {
        const Eigen::Vector3d centre = c + sign * half[i] * axes.col(i);
        const Eigen::Vector3d tj = half[j] * axes.col(j), tk = half[k] * axes.col(k);
        Eigen::Vector3d corners[4] = {centre - tj - tk, centre + tj - tk, centre + tj + tk,
                                      centre - tj + tk};
        if (sign < 0) std::swap(corners[1], corners[3]);
        const int base = vertex_count_;
        for (const auto& v : corners) {
          vertices_ << f3(v.x(), v.y(), v.z()) << " ";
          ++vertex_count_;
        }
        faces_ << base << " " << base + 1 << " " << base + 2 << " " << base << " " << base + 2
               << " " << base + 3 << " ";
      }
    }
  }

 public:
  // A bar of square cross-section between two points.
  void addBar(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, double half_width) {
    const Eigen::Vector3d a0 = (p1 - p0).normalized();
    const Eigen::Vector3d ref =
        std::abs(a0.z()) > 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d a1 = ref.cross(a0).normalized();
    Eigen::Matrix3d axes;
    axes << a0, a1, a0.cross(a1);
    add((p0 + p1) / 2, axes, Eigen::Vector3d((p1 - p0).norm() / 2, half_width, half_width));
  }
  void write(SceneWriter& w, const std::string& mesh_name, const std::string& geom_prefix,
             const std::string& material) const {
    w.assets << "<mesh name=\"" << mesh_name << "\" vertex=\"" << vertices_.str() << "\" face=\""
             << faces_.str() << "\"/>\n";
    w.geom(geom_prefix, "mesh", "mesh=\"" + mesh_name + "\"", material);
  }

 private:
  std::ostringstream vertices_, faces_;
  int vertex_count_ = 0;
};

// A field line between two centre points, `width` wide, extended by `extend` at both ends.
void lineBox(BoxMesh& mesh, const FieldDimensions& fd, double x0, double y0, double x1, double y1,
             double extend) {
  const double len = std::hypot(x1 - x0, y1 - y0);
  const double half_h = (kLineTopZ - kLineBottomZ) / 2;
  const double yaw = std::atan2(y1 - y0, x1 - x0);
  Eigen::Matrix3d axes;
  axes << std::cos(yaw), -std::sin(yaw), 0, std::sin(yaw), std::cos(yaw), 0, 0, 0, 1;
  mesh.add(Eigen::Vector3d((x0 + x1) / 2, (y0 + y1) / 2, kLineBottomZ + half_h), axes,
           Eigen::Vector3d(len / 2 + extend, fd.line_width_m / 2, half_h));
}

void writeField(SceneWriter& w, const FieldDimensions& fd, double grid_m) {
  BoxMesh lines;
  lines.max_piece_m = 2 * grid_m;
  const double L = fd.halfLength(), W = fd.halfWidth(), hw = fd.line_width_m / 2;
  w.geom(kCarpetPrefix, "plane",
         "pos=\"0 0 " + f(kCarpetTopZ) + "\" size=\"" +
             f3(fd.carpetHalfLength(), fd.carpetHalfWidth(), grid_m) + "\"",
         "carpet");
  lineBox(lines, fd, -L, W, L, W, hw);
  lineBox(lines, fd, -L, -W, L, -W, hw);
  lineBox(lines, fd, 0, -W, 0, W, 0);
  for (double s : {-1.0, 1.0}) {
    lineBox(lines, fd, s * L, -W, s * L, W, hw);
    const double pa = s * (L - fd.penalty_area_length_m), pw = fd.penalty_area_width_m / 2;
    lineBox(lines, fd, pa, -pw, pa, pw, hw);
    lineBox(lines, fd, pa, pw, s * L, pw, hw);
    lineBox(lines, fd, pa, -pw, s * L, -pw, hw);
    const double ga = s * (L - fd.goal_area_length_m), gw = fd.goal_area_width_m / 2;
    lineBox(lines, fd, ga, -gw, ga, gw, hw);
    lineBox(lines, fd, ga, gw, s * L, gw, hw);
    lineBox(lines, fd, ga, -gw, s * L, -gw, hw);
    const double pm = s * (L - fd.penalty_mark_distance_m), arm = fd.penalty_mark_size_m / 2;
    lineBox(lines, fd, pm - arm, 0, pm + arm, 0, 0);
    lineBox(lines, fd, pm, -arm, pm, arm, 0);
  }
  // Centre circle as chords; each chord is lengthened so neighbours meet at the outer edge.
  const double r = fd.centre_circle_diameter_m / 2;
  const double da = 2 * kPi / kCircleSegments;
  for (int i = 0; i < kCircleSegments; ++i) {
    const double a0 = i * da, a1 = (i + 1) * da;
    lineBox(lines, fd, r * std::cos(a0), r * std::sin(a0), r * std::cos(a1), r * std::sin(a1),
            hw * std::tan(da / 2));
  }
  lines.write(w, "lines_mesh", kLinePrefix, "line");
}

void writeGoals(SceneWriter& w, const FieldDimensions& fd) {
  const double pr = fd.goal_post_diameter_m / 2;
  const double post_y = fd.goal_inner_width_m / 2 + pr;
  const double top = fd.goal_height_m + pr;
  for (double s : {-1.0, 1.0}) {
    const double x = s * (fd.halfLength() + fd.line_width_m / 2);
    const double back = s * (fd.halfLength() + fd.line_width_m / 2 + fd.goal_depth_m);
    for (double py : {-post_y, post_y}) {
      w.cylinder(kGoalPrefix, x, py, kCarpetTopZ, x, py, top + pr, pr, "goal");
      // Frame of the net: back post, top and bottom side bars.
      w.cylinder(kGoalPrefix, back, py, kCarpetTopZ, back, py, top, pr * 0.4, "goal");
      w.cylinder(kGoalPrefix, x, py, top, back, py, top, pr * 0.4, "goal");
      w.cylinder(kGoalPrefix, x, py, pr * 0.4, back, py, pr * 0.4, pr * 0.4, "goal");
    }
    w.cylinder(kGoalPrefix, x, -post_y - pr, top, x, post_y + pr, top, pr, "goal");
    w.cylinder(kGoalPrefix, back, -post_y, top, back, post_y, top, pr * 0.4, "goal");
    w.cylinder(kGoalPrefix, back, -post_y, pr * 0.4, back, post_y, pr * 0.4, pr * 0.4, "goal");
    // The net: strings on the back, the sides and the roof.
    const double sr = kNetStringRadiusM;
    BoxMesh net;
    const auto net_string = [&net, sr](double x0, double y0, double z0, double x1, double y1,
                                       double z1) {
      net.addBar(Eigen::Vector3d(x0, y0, z0), Eigen::Vector3d(x1, y1, z1), sr);
    };
    for (double y = -post_y + kNetSpacingM; y < post_y - 1e-6; y += kNetSpacingM) {
      net_string(back, y, 0, back, y, top);
      net_string(x, y, top, back, y, top);
    }
    for (double z = kNetSpacingM; z < top - 1e-6; z += kNetSpacingM) {
      net_string(back, -post_y, z, back, post_y, z);
      for (double py : {-post_y, post_y}) net_string(x, py, z, back, py, z);
    }
    for (double d = kNetSpacingM; d < fd.goal_depth_m - 1e-6; d += kNetSpacingM) {
      const double xd = x + s * d;
      net_string(xd, -post_y, top, xd, post_y, top);
      for (double py : {-post_y, post_y}) net_string(xd, py, 0, xd, py, top);
    }
    net.write(w, s > 0 ? "net_mesh_pos" : "net_mesh_neg", kGoalPrefix, "net");
  }
}

void writePerson(SceneWriter& w, std::mt19937_64& rng, double x, double y, double yaw) {
  std::uniform_real_distribution<double> u(0, 1);
  const double k = 0.9 + 0.18 * u(rng);
  const std::string shirt = "cloth" + std::to_string(int(u(rng) * kClothVariants));
  const std::string trousers = "cloth" + std::to_string(int(u(rng) * kClothVariants));
  const double skin = 0.35 + 0.45 * u(rng);
  w.world << "<body pos=\"" << f3(x, y, 0) << "\" euler=\"0 0 " << f(yaw) << "\">\n";
  for (double s : {-1.0, 1.0}) {
    w.capsule("hall_", 0, s * 0.1 * k, 0.1 * k, 0, s * 0.1 * k, 0.85 * k, 0.075 * k, trousers);
    w.box("hall_", 0.04 * k, s * 0.1 * k, 0.04 * k, 0.13 * k, 0.05 * k, 0.04 * k, 0, "shoe");
    w.capsule("hall_", 0.02 * k, s * 0.25 * k, 1.4 * k, 0.08 * k, s * 0.27 * k, 0.85 * k, 0.05 * k,
              shirt);
  }
  w.box("hall_", 0, 0, 1.15 * k, 0.12 * k, 0.21 * k, 0.3 * k, 0, shirt);
  w.capsule("hall_", 0, 0, 1.45 * k, 0, 0, 1.52 * k, 0.05 * k,
            "skin" + std::to_string(int(skin * 3)));
  w.geom("hall_", "ellipsoid",
         "pos=\"" + f3(0, 0, 1.64 * k) + "\" size=\"" + f3(0.1 * k, 0.085 * k, 0.115 * k) + "\"",
         "skin" + std::to_string(int(skin * 3)));
  w.world << "</body>\n";
}

void writeHall(SceneWriter& w, const FieldDimensions& fd, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const double cl = fd.carpetHalfLength(), cw = fd.carpetHalfWidth();
  const double hx = cl + kHallMarginXM, hy = cw + kHallMarginYM, hz = kHallHeightM;
  w.geom("hall_", "plane", "pos=\"0 0 " + f(kFloorZ) + "\" size=\"" + f3(hx, hy, 0.5) + "\"",
         "floor");
  // Walls, ceiling.
  w.box("hall_", 0, hy + 0.05, hz / 2, hx, 0.05, hz / 2, 0, "wall0");
  w.box("hall_", 0, -hy - 0.05, hz / 2, hx, 0.05, hz / 2, 0, "wall1");
  w.box("hall_", hx + 0.05, 0, hz / 2, 0.05, hy, hz / 2, 0, "wall1");
  w.box("hall_", -hx - 0.05, 0, hz / 2, 0.05, hy, hz / 2, 0, "wall0");
  w.box("hall_", 0, 0, hz + 0.05, hx, hy, 0.05, 0, "ceiling");
  // Rows of ceiling lamps and windows high on one side wall.
  for (double lx = -hx + 2.5; lx < hx - 1; lx += 4) {
    for (double ly : {-cw * 0.8, 0.0, cw * 0.8})
      w.box("hall_", lx, ly, hz - 0.05, 0.6, 0.15, 0.03, 0, "lamp");
  }
  for (double wx = -hx + 3; wx < hx - 2; wx += 4.5)
    w.box("hall_", wx, hy - 0.01, hz * 0.72, 1.3, 0.02, 0.7, 0, "window");
  // Sponsor boards behind the goals and along one side.
  for (double s : {-1.0, 1.0}) {
    for (double by : {-1.6, 1.6}) {
      const std::string mat = "board" + std::to_string(int(u(rng) * kBoardVariants));
      w.box("hall_", s * (cl + 0.9), by, 0.3, 0.02, 1.55, 0.3, 0, mat);
    }
  }
  for (double bx = -cl + 1.5; bx < cl - 1; bx += 3.3) {
    const std::string mat = "board" + std::to_string(int(u(rng) * kBoardVariants));
    w.box("hall_", bx, cw + 1.6, 0.4, 1.5, 0.02, 0.4, 0, mat);
  }
  // Team tables with laptops on the other side.
  for (double tx : {-cl * 0.55, 0.0, cl * 0.55}) {
    const double x = tx + (u(rng) - 0.5);
    const double y = -(cw + 1.4);
    w.box("hall_", x, y, 0.73, 0.8, 0.4, 0.02, 0, "wood");
    for (double lx : {-0.75, 0.75}) {
      for (double ly : {-0.35, 0.35})
        w.box("hall_", x + lx, y + ly, 0.36, 0.02, 0.02, 0.36, 0, "metal");
    }
    for (int k = 0; k < 2; ++k) {
      const double px = x - 0.4 + 0.8 * k + 0.2 * (u(rng) - 0.5);
      w.box("hall_", px, y + 0.05, 0.76, 0.17, 0.12, 0.01, 0, "laptop");
      w.geom("hall_", "box",
             "pos=\"" + f3(px, y - 0.08, 0.87) + "\" size=\"0.17 0.01 0.11\" euler=\"-0.25 0 0\"",
             "laptop");
    }
  }
  // People standing around the field, facing it.
  for (int i = 0; i < kPeople; ++i) {
    double x, y;
    const double side = u(rng);
    if (side < 0.6) {
      x = (u(rng) * 2 - 1) * (cl + 1.0);
      y = (u(rng) < 0.5 ? -1 : 1) * (cw + 0.35 + 1.3 * u(rng));
    } else {
      x = (u(rng) < 0.5 ? -1 : 1) * (cl + 0.35 + 1.4 * u(rng));
      y = (u(rng) * 2 - 1) * (cw + 0.5);
    }
    const double yaw = std::atan2(-y, -x) + (u(rng) - 0.5) * 1.2;
    writePerson(w, rng, x, y, yaw);
  }
}

void writeLights(SceneWriter& w, const SceneSpec& spec, std::mt19937_64& rng) {
  using V = Eigen::Vector3d;
  std::uniform_real_distribution<double> u(0, 1);
  const FieldDimensions& fd = spec.field;
  // Lamps hang just below the ceiling; a light above it would be shadowed by it.
  const double lamp_z = kHallHeightM - 0.2;
  double ambient = 0.65;
  switch (spec.lighting) {
    case LightingPreset::kNormal:
    case LightingPreset::kFlicker:
    case LightingPreset::kDim:
    case LightingPreset::kOverexposed: {
      const double k = spec.lighting == LightingPreset::kDim           ? 0.6
                       : spec.lighting == LightingPreset::kOverexposed ? 2.0
                                                                       : 1.0;
      ambient *= k;
      // Many hall lamps: soft, faint shadows; one lamp casts them, the others fill.
      w.light(V(0.4, -0.3, lamp_z), V(0, 0, -1), false, true, 0.3 * k, 65);
      w.light(V(0, 0, lamp_z), V(0.35, 0.25, -1), true, false, 0.2 * k);
      w.light(V(0, 0, lamp_z), V(-0.35, -0.25, -1), true, false, 0.2 * k);
      break;
    }
    case LightingPreset::kDirectional:
      ambient = 0.5;
      w.light(V(fd.halfLength() * 0.5, -fd.halfWidth() * 0.5, 4), V(-0.5, 0.4, -0.6), true, true,
              1.1);
      break;
    case LightingPreset::kUneven: {
      ambient = 0.5;
      w.light(V(0.4, -0.3, lamp_z), V(0, 0, -1), false, true, 0.35, 65);
      w.light(V(0, 0, lamp_z), V(0.35, 0.25, -1), true, false, 0.1);
      // Sunlight through the windows: bright patches with hard edges at random places.
      const V sun = V(0.25, -0.45, -1).normalized();
      for (int i = 0; i < 4; ++i) {
        const V target((u(rng) * 2 - 1) * fd.halfLength(), (u(rng) * 2 - 1) * fd.halfWidth(), 0);
        w.light(target - sun * 3.5, sun, false, false, 1.3, 10 + 8 * u(rng));
      }
      break;
    }
  }
  w.model.headlight_ambient = float(ambient);
}

}  // namespace

std::string robotPrefix(int index) {
  // Built by appending: GCC 12 warns falsely (-Wrestrict) on "r" + std::to_string(i).
  std::string prefix = "r";
  prefix += std::to_string(index);
  prefix += '_';
  return prefix;
}

void validateSceneSpec(const SceneSpec& spec) {
  const FieldDimensions& fd = spec.field;
  const std::pair<const char*, double> sizes[] = {
      {"field_length_m", fd.field_length_m},
      {"field_width_m", fd.field_width_m},
      {"line_width_m", fd.line_width_m},
      {"border_strip_m", fd.border_strip_m},
      {"centre_circle_diameter_m", fd.centre_circle_diameter_m},
      {"penalty_area_length_m", fd.penalty_area_length_m},
      {"penalty_area_width_m", fd.penalty_area_width_m},
      {"goal_area_length_m", fd.goal_area_length_m},
      {"goal_area_width_m", fd.goal_area_width_m},
      {"penalty_mark_distance_m", fd.penalty_mark_distance_m},
      {"penalty_mark_size_m", fd.penalty_mark_size_m},
      {"goal_inner_width_m", fd.goal_inner_width_m},
      {"goal_depth_m", fd.goal_depth_m},
      {"goal_height_m", fd.goal_height_m},
      {"goal_post_diameter_m", fd.goal_post_diameter_m},
      {"ball_diameter_m", fd.ball_diameter_m}};
  for (const auto& [name, v] : sizes) {
    if (!std::isfinite(v) || v <= 0 || v > 100) {
      throw Error("scene: field dimension " + std::string(name) + " = " + std::to_string(v) +
                  " is impossible");
    }
  }
  if (fd.penalty_area_length_m >= fd.halfLength() ||
      fd.goal_area_length_m >= fd.penalty_area_length_m ||
      fd.penalty_area_width_m >= fd.field_width_m ||
      fd.goal_area_width_m >= fd.penalty_area_width_m ||
      fd.centre_circle_diameter_m >= fd.field_width_m ||
      fd.line_width_m * 4 >= fd.goal_area_length_m ||
      fd.penalty_mark_distance_m >= fd.halfLength() || fd.goal_inner_width_m >= fd.field_width_m) {
    throw Error(
        "scene: field dimensions do not fit together (areas, circle or marks larger than "
        "the field)");
  }
  if (spec.robot_count < 0 || spec.robot_count > 9) {
    throw Error("scene: robot_count " + std::to_string(spec.robot_count) +
                " is impossible (0..9 besides the observer, 10 robots in all)");
  }
  if (spec.jersey_gray.size() > std::size_t(spec.robot_count)) {
    throw Error("scene: " + std::to_string(spec.jersey_gray.size()) + " jersey grey levels for " +
                std::to_string(spec.robot_count) + " robots");
  }
  for (double g : spec.jersey_gray) {
    if (!std::isfinite(g) || g < 0 || g > 1) {
      throw Error("scene: jersey grey " + std::to_string(g) + " is not in 0..1");
    }
  }
  if (!std::isfinite(spec.observer_jersey_gray) || spec.observer_jersey_gray < 0 ||
      spec.observer_jersey_gray > 1) {
    throw Error("scene: observer jersey grey is not in 0..1");
  }
  if (spec.multisamples < 0 || spec.multisamples > 16) {
    throw Error("scene: multisamples " + std::to_string(spec.multisamples) + " is not in 0..16");
  }
  if (spec.max_width_px < 16 || spec.max_height_px < 16 || spec.max_width_px > 4096 ||
      spec.max_height_px > 4096) {
    throw Error("scene: off-screen buffer " + std::to_string(spec.max_width_px) + "x" +
                std::to_string(spec.max_height_px) + " is impossible (16..4096)");
  }
  if (spec.shadow_map_px < 256 || spec.shadow_map_px > 8192) {
    throw Error("scene: shadow map " + std::to_string(spec.shadow_map_px) +
                " px is not in 256..8192");
  }
  if (!std::isfinite(spec.camera_horizontal_fov_deg) || spec.camera_horizontal_fov_deg < 10 ||
      spec.camera_horizontal_fov_deg > 150) {
    throw Error("scene: camera field of view " + std::to_string(spec.camera_horizontal_fov_deg) +
                " deg is not in 10..150");
  }
}

SceneModel buildScene(const SceneSpec& spec) {
  validateSceneSpec(spec);
  const FieldDimensions& fd = spec.field;
  std::mt19937_64 rng(spec.seed);
  SceneWriter w;

  // Textures and materials.
  const GrayTexture carpet = carpetTexture(spec.seed, kCarpetTexturePx);
  w.texture2d("carpet_tex", carpet);
  // The print does not depend on the seed: made once per process.
  static const std::vector<GrayTexture> faces = ballCubeFaces(kBallFacePx);
  const char* face_names[] = {"right", "left", "up", "down", "front", "back"};
  w.assets << "<texture name=\"ball_tex\" type=\"cube\"";
  for (int i = 0; i < 6; ++i) {
    const std::string file = std::string("ball_") + face_names[i] + ".tex";
    w.model.files[file] = encodeMujocoCustom(faces[i]);
    w.assets << " file" << face_names[i] << "=\"" << file << "\"";
  }
  w.assets << "/>\n";
  const std::uint64_t s = spec.seed;
  w.texture2d("wall0_tex", hallTexture(HallTexture::kWall, s, 0, 256, 128));
  w.texture2d("wall1_tex", hallTexture(HallTexture::kWall, s, 1, 256, 128));
  w.texture2d("floor_tex", hallTexture(HallTexture::kFloor, s, 0, 256, 256));
  w.texture2d("wood_tex", hallTexture(HallTexture::kWood, s, 0, 256, 256));
  w.texture2d("ceiling_tex", hallTexture(HallTexture::kCeiling, s, 0, 128, 128));
  for (int i = 0; i < kBoardVariants; ++i) {
    w.texture2d("board" + std::to_string(i) + "_tex",
                hallTexture(HallTexture::kBoard, s, i, 256, 64));
  }
  for (int i = 0; i < kClothVariants; ++i) {
    w.texture2d("cloth" + std::to_string(i) + "_tex",
                hallTexture(HallTexture::kCloth, s, i, 64, 64));
  }
  w.material("carpet", "carpet_tex", kCarpetGray, 1 / kCarpetTileM);
  // Lines are flat white: where two line boxes overlap (corners, crossings, circle chords) their
  // coplanar tops then look the same whichever wins the depth test.
  w.material("line", "", kLineGray, 0);
  w.material("goal", "", 0.93, 0, 0.2, 0.3);
  w.material("net", "", 0.8, 0);
  w.material("ball", "ball_tex", 1.0, 1, 0.15, 0.2);
  w.material("nao_white", "", 0.92, 0, 0.25, 0.3);
  w.material("nao_grey", "", 0.5, 0, 0.2, 0.3);
  w.material("nao_dark", "", 0.18, 0, 0.1, 0.2);
  w.material("floor", "floor_tex", 0.8, 0.5);
  w.material("wall0", "wall0_tex", 0.9, 0.25);
  w.material("wall1", "wall1_tex", 0.9, 0.25);
  w.material("ceiling", "ceiling_tex", 0.7, 0.3);
  w.material("lamp", "", 1.0, 0, 0, 0, 1.0);
  w.material("window", "", 0.95, 0, 0, 0, 0.9);
  w.material("wood", "wood_tex", 0.9, 1);
  w.material("metal", "", 0.4, 0, 0.4, 0.5);
  w.material("laptop", "", 0.15, 0, 0.3, 0.5);
  w.material("shoe", "", 0.12, 0);
  for (int i = 0; i < 3; ++i) w.material("skin" + std::to_string(i), "", 0.45 + 0.15 * i, 0);
  for (int i = 0; i < kBoardVariants; ++i) {
    w.material("board" + std::to_string(i), "board" + std::to_string(i) + "_tex", 0.95, 0.33);
  }
  for (int i = 0; i < kClothVariants; ++i) {
    w.material("cloth" + std::to_string(i), "cloth" + std::to_string(i) + "_tex", 0.9, 3);
  }
  w.material("obs_jersey", "", spec.observer_jersey_gray, 0);
  for (int i = 0; i < spec.robot_count; ++i) {
    const double g = std::size_t(i) < spec.jersey_gray.size() ? spec.jersey_gray[i] : 0.5;
    w.material(robotPrefix(i) + "jersey", "", g, 0);
  }

  writeLights(w, spec, rng);
  writeField(w, fd, spec.lighting == LightingPreset::kUneven ? kCarpetGridPatchesM : kCarpetGridM);
  writeGoals(w, fd);
  writeHall(w, fd, rng);
  if (spec.ball) {
    w.world << "<body name=\"ball\" mocap=\"true\" pos=\"0 0 " << f(fd.ballRadius()) << "\">"
            << "<geom name=\"ball\" type=\"sphere\" size=\"" << f(fd.ballRadius())
            << "\" material=\"ball\"/></body>\n";
  }
  w.world << naoMjcf({kObserverPrefix, "obs_jersey", true});
  for (int i = 0; i < spec.robot_count; ++i) {
    w.world << naoMjcf({robotPrefix(i), robotPrefix(i) + "jersey", false});
  }

  std::ostringstream x;
  x << "<mujoco model=\"colorfree_spl\">\n"
    << "<compiler angle=\"radian\"/>\n"
    << "<option gravity=\"0 0 0\"/>\n"
    << "<visual>\n"
    << "<global offwidth=\"" << spec.max_width_px << "\" offheight=\"" << spec.max_height_px
    << "\"/>\n"
    << "<quality shadowsize=\"" << spec.shadow_map_px << "\" offsamples=\"" << spec.multisamples
    << "\" numslices=\"" << kRoundSlices << "\" numstacks=\"" << kRoundStacks << "\" numquads=\""
    << kBoxQuads << "\"/>\n"
    << "<headlight active=\"1\" ambient=\""
    << f3(w.model.headlight_ambient, w.model.headlight_ambient, w.model.headlight_ambient)
    << "\" diffuse=\"0 0 0\" specular=\"0 0 0\"/>\n"
    // Near clip 3 cm so that the bottom camera sees the own chest and feet, while the depth
    // buffer still separates lines and carpet (1 mm) 10 m away; shadows of the directional light
    // cover the carpet.
    << "<map znear=\"0.03\" zfar=\"60\" haze=\"0\" shadowclip=\"" << f(fd.carpetHalfLength() + 1)
    << "\" shadowscale=\"0.8\"/>\n"
    << "</visual>\n"
    << "<statistic extent=\"1\" center=\"0 0 0\"/>\n"
    << "<default><geom contype=\"0\" conaffinity=\"0\"/></default>\n"
    << "<asset>\n"
    << w.assets.str() << "</asset>\n"
    << "<worldbody>\n"
    << w.world.str() << "</worldbody>\n"
    << "</mujoco>\n";
  w.model.mjcf = x.str();
  return std::move(w.model);
}

}  // namespace colorfree::sim
