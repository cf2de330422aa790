#include "colorfree/perception/ignore_regions.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "colorfree/perception/error.h"
#include "colorfree/perception/param_file.h"

namespace colorfree {

FieldBoundaryParams FieldBoundaryParams::load(const std::string& path) {
  ParamFile f(path);
  FieldBoundaryParams p;
  p.block_width_px = static_cast<int>(f.getInRange("block_width_px", 2, 128));
  p.block_height_px = static_cast<int>(f.getInRange("block_height_px", 2, 128));
  p.sample_step_px = static_cast<int>(f.getInRange("sample_step_px", 1, 8));
  p.carpet_luminance_tolerance = f.getInRange("carpet_luminance_tolerance", 0, 255);
  p.carpet_luminance_tolerance_ratio = f.getInRange("carpet_luminance_tolerance_ratio", 0, 1);
  p.carpet_spread_factor = f.getInRange("carpet_spread_factor", 0, 100);
  p.carpet_spread_offset = f.getInRange("carpet_spread_offset", 0, 255);
  p.min_run_blocks = static_cast<int>(f.getInRange("min_run_blocks", 1, 64));
  p.reference_fraction = f.getInRange("reference_fraction", 0.05, 1);
  p.margin_px = static_cast<int>(f.getInRange("margin_px", 0, 200));
  f.finish();
  return p;
}

FieldBoundaryParams FieldBoundaryParams::loadDefault() {
  return load(defaultParamDir() + "/field_boundary.yaml");
}

BodyModelParams BodyModelParams::load(const std::string& path) {
  ParamFile f(path);
  BodyModelParams p;
  p.foot_length_m = f.getInRange("foot_length_m", 0.01, 1);
  p.foot_width_m = f.getInRange("foot_width_m", 0.01, 1);
  p.foot_height_m = f.getInRange("foot_height_m", 0.005, 1);
  p.foot_centre_x_m = f.getInRange("foot_centre_x_m", -1, 1);
  p.feet_separation_m = f.getInRange("feet_separation_m", 0, 1);
  p.leg_width_m = f.getInRange("leg_width_m", 0.01, 1);
  p.hip_height_m = f.getInRange("hip_height_m", 0.05, 2);
  p.chest_front_x_m = f.getInRange("chest_front_x_m", -1, 1);
  p.chest_back_x_m = f.getInRange("chest_back_x_m", -1, 1);
  p.chest_width_m = f.getInRange("chest_width_m", 0.01, 2);
  p.chest_bottom_m = f.getInRange("chest_bottom_m", 0, 3);
  p.chest_top_m = f.getInRange("chest_top_m", 0, 3);
  p.margin_px = static_cast<int>(f.getInRange("margin_px", 0, 200));
  f.finish();
  if (p.chest_back_x_m >= p.chest_front_x_m) throw Error(path + ": chest back is not behind its front");
  if (p.chest_bottom_m >= p.chest_top_m) throw Error(path + ": chest bottom is not below its top");
  if (p.foot_height_m >= p.hip_height_m) throw Error(path + ": hips are not above the feet");
  return p;
}

BodyModelParams BodyModelParams::loadDefault() { return load(defaultParamDir() + "/body_model.yaml"); }

namespace {

// Whether the ray through pixel (x, y) points below the horizontal: the sign of its robot-frame
// z, which normalising (CameraModel::pixelRay) does not change.
struct DownTest {
  Eigen::Matrix3d r;
  CameraIntrinsics k;
  explicit DownTest(const CameraModel& camera)
      : r(camera.cameraToRobot().linear()), k(camera.intrinsics()) {}
  bool operator()(double x, double y) const {
    const double dx = (x - k.center_x_px) / k.focal_x_px, dy = (y - k.center_y_px) / k.focal_y_px;
    return r(2, 0) * dx + r(2, 1) * dy + r(2, 2) < 0;
  }
};

// First image row whose pixel centre lies below the horizon in column x, in [0, height].
int firstRowBelowHorizon(const CameraModel& camera, const DownTest& down_at, int x) {
  const int h = camera.height();
  const double cx = x + 0.5;
  const auto down = [&](double y) { return down_at(cx, y); };
  const auto hy = camera.horizonY(cx);
  if (!hy) return down(h / 2.0) ? 0 : h;
  int row = static_cast<int>(std::ceil(*hy - 0.5));
  row = std::clamp(row, 0, h);
  // The rows below the horizon line are on the ground only when the camera is upright.
  if (row < h && !down(row + 0.5)) return h;
  if (row == h && h > 0 && !down(h - 0.5)) return h;
  return row;
}

}  // namespace

BlockStats blockStats(const GrayView& image, int x0, int y0, int x1, int y1, int step) {
  std::uint32_t sum = 0;
  std::uint64_t sum_sq = 0;
  std::uint32_t n = 0;
#if defined(__SSE2__)
  // Whole 16-pixel chunks of each sampled row at once (every or every other pixel); the sums are
  // integers, so the order of adding does not change them.
  if ((step == 1 || step == 2) && (x1 - x0) % 16 == 0) {
    const __m128i zero = _mm_setzero_si128();
    const __m128i even = _mm_set1_epi16(0x00FF);
    __m128i sums = zero, squares = zero;
    for (int y = y0; y < y1; y += step) {
      const std::uint8_t* row = image.row(y);
      for (int x = x0; x < x1; x += 16) {
        const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x));
        if (step == 2) {
          const __m128i e = _mm_and_si128(v, even);  // the even pixels as 16-bit values
          sums = _mm_add_epi64(sums, _mm_sad_epu8(e, zero));
          squares = _mm_add_epi32(squares, _mm_madd_epi16(e, e));
        } else {
          const __m128i lo = _mm_unpacklo_epi8(v, zero), hi = _mm_unpackhi_epi8(v, zero);
          sums = _mm_add_epi64(sums, _mm_sad_epu8(v, zero));
          squares = _mm_add_epi32(squares, _mm_add_epi32(_mm_madd_epi16(lo, lo), _mm_madd_epi16(hi, hi)));
        }
      }
      n += static_cast<std::uint32_t>((x1 - x0) / step);
    }
    alignas(16) std::uint64_t s64[2];
    alignas(16) std::uint32_t q32[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(s64), sums);
    _mm_store_si128(reinterpret_cast<__m128i*>(q32), squares);
    sum = static_cast<std::uint32_t>(s64[0] + s64[1]);
    sum_sq = std::uint64_t{q32[0]} + q32[1] + q32[2] + q32[3];
  } else
#endif
  {
    for (int y = y0; y < y1; y += step) {
      const std::uint8_t* row = image.row(y);
      for (int x = x0; x < x1; x += step) {
        const std::uint32_t v = row[x];
        sum += v;
        sum_sq += v * v;
        ++n;
      }
    }
  }
  if (n == 0) return {};
  const double mean = static_cast<double>(sum) / n;
  const double var = std::max(0.0, static_cast<double>(sum_sq) / n - mean * mean);
  return {static_cast<float>(mean), static_cast<float>(std::sqrt(var))};
}

namespace {

double cross(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a.x() - o.x()) * (b.y() - o.y()) - (a.y() - o.y()) * (b.x() - o.x());
}

// The largest convex function below the points (y grows downwards: the hull on the image's top).
std::vector<Eigen::Vector2d> upperImageHull(std::vector<Eigen::Vector2d> points) {
  std::sort(points.begin(), points.end(),
            [](const auto& a, const auto& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  std::vector<Eigen::Vector2d> hull;
  for (const auto& p : points) {
    if (!hull.empty() && hull.back().x() == p.x()) continue;
    while (hull.size() >= 2 && cross(hull[hull.size() - 2], hull.back(), p) <= 0) hull.pop_back();
    hull.push_back(p);
  }
  return hull;
}

double hullAt(const std::vector<Eigen::Vector2d>& hull, double x) {
  if (x <= hull.front().x()) return hull.front().y();
  if (x >= hull.back().x()) return hull.back().y();
  for (std::size_t i = 1; i < hull.size(); ++i) {
    if (x <= hull[i].x()) {
      const double t = (x - hull[i - 1].x()) / (hull[i].x() - hull[i - 1].x());
      return hull[i - 1].y() + t * (hull[i].y() - hull[i - 1].y());
    }
  }
  return hull.back().y();
}

}  // namespace

FieldBoundaryDetector::FieldBoundaryDetector(FieldBoundaryParams params) : params_(params) {}

FieldBoundary FieldBoundaryDetector::run(const GrayView& image, const CameraModel& camera) const {
  const int w = image.width;
  const int h = image.height;
  FieldBoundary out;
  out.horizon_y.resize(w);
  const DownTest down(camera);
  for (int x = 0; x < w; ++x) out.horizon_y[x] = firstRowBelowHorizon(camera, down, x);

  const int bw = params_.block_width_px;
  const int bh = params_.block_height_px;
  const int columns = w / bw;
  const int block_rows = h / bh;
  // Block statistics below the horizon, block row 0 at the bottom of the image.
  std::vector<BlockStats> stats(static_cast<std::size_t>(columns) * block_rows);
  std::vector<int> rows_below(columns, 0);
  std::vector<float> ref_means, ref_spreads;
  for (int c = 0; c < columns; ++c) {
    const int x0 = c * bw;
    int horizon = 0;
    for (int x = x0; x < x0 + bw; ++x) horizon = std::max(horizon, out.horizon_y[x]);
    const int usable = (h - horizon) / bh;
    rows_below[c] = usable;
    const int reference_rows = std::max(1, static_cast<int>(usable * params_.reference_fraction));
    for (int k = 0; k < usable; ++k) {
      const int y1 = h - k * bh;
      const BlockStats s = blockStats(image, x0, y1 - bh, x0 + bw, y1, params_.sample_step_px);
      stats[static_cast<std::size_t>(c) * block_rows + k] = s;
      if (k < reference_rows) {
        ref_means.push_back(s.mean);
        ref_spreads.push_back(s.spread);
      }
    }
  }
  out.boundary_y = out.horizon_y;
  if (ref_means.empty()) return out;
  const auto median = [](std::vector<float>& v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return static_cast<double>(v[v.size() / 2]);
  };
  const double carpet_mean = median(ref_means);
  const double carpet_spread = median(ref_spreads);
  const double max_spread = params_.carpet_spread_factor * carpet_spread + params_.carpet_spread_offset;
  const double tolerance = std::max(params_.carpet_luminance_tolerance,
                                    params_.carpet_luminance_tolerance_ratio * carpet_mean);

  std::vector<float> own;
  for (int c = 0; c < columns; ++c) {
    // The column's own carpet (light changes across the image), unless it has too few blocks.
    double reference = carpet_mean;
    const int reference_rows = static_cast<int>(rows_below[c] * params_.reference_fraction);
    if (reference_rows >= 3) {
      own.clear();
      for (int k = 0; k < reference_rows; ++k) own.push_back(stats[static_cast<std::size_t>(c) * block_rows + k].mean);
      const double m = median(own);
      if (std::abs(m - carpet_mean) <= tolerance) reference = m;
    }
    int run = 0;
    int top_row = -1;
    for (int k = 0; k < rows_below[c]; ++k) {
      const BlockStats& s = stats[static_cast<std::size_t>(c) * block_rows + k];
      const bool carpet = std::abs(s.mean - reference) <= tolerance && s.spread <= max_spread;
      if (carpet) {
        // Follows a slow change of light along the column.
        reference = 0.8 * reference + 0.2 * s.mean;
        if (++run >= params_.min_run_blocks) top_row = h - (k + 1) * bh;
      } else {
        run = 0;
      }
    }
    if (top_row < 0) continue;
    // Carpet up to the highest block below the horizon: the field reaches the horizon here.
    if (top_row - bh < out.horizon_y[c * bw]) top_row = out.horizon_y[c * bw];
    out.texture_points_px.emplace_back(c * bw + bw / 2.0, top_row);
  }
  if (out.texture_points_px.empty()) return out;
  const std::vector<Eigen::Vector2d> hull = upperImageHull(out.texture_points_px);
  for (int x = 0; x < w; ++x) {
    const int y = static_cast<int>(std::floor(hullAt(hull, x + 0.5))) - params_.margin_px;
    out.boundary_y[x] = std::clamp(std::max(y, out.horizon_y[x]), 0, h);
  }
  return out;
}

BodyContourProvider::BodyContourProvider(BodyModelParams params) : params_(params) {}

namespace {

struct Box {
  Eigen::Vector3d min, max;
};

std::vector<Eigen::Vector2d> convexHull(std::vector<Eigen::Vector2d> points) {
  if (points.size() < 3) return points;
  std::sort(points.begin(), points.end(),
            [](const auto& a, const auto& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  std::vector<Eigen::Vector2d> hull(2 * points.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], points[i]) <= 0) --k;
    hull[k++] = points[i];
  }
  for (std::size_t i = points.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], points[i - 1]) <= 0) --k;
    hull[k++] = points[i - 1];
  }
  hull.resize(k - 1);
  return hull;
}

}  // namespace

BodyContour BodyContourProvider::run(const CameraModel& camera) const {
  const int w = camera.width();
  const int h = camera.height();
  BodyContour out;
  out.top_y.assign(w, h);
  const auto& p = params_;
  std::vector<Box> boxes;
  for (double side : {-1.0, 1.0}) {
    const double y = side * p.feet_separation_m / 2;
    boxes.push_back({{p.foot_centre_x_m - p.foot_length_m / 2, y - p.foot_width_m / 2, 0},
                     {p.foot_centre_x_m + p.foot_length_m / 2, y + p.foot_width_m / 2, p.foot_height_m}});
    boxes.push_back({{-p.leg_width_m / 2, y - p.leg_width_m / 2, p.foot_height_m},
                     {p.leg_width_m / 2, y + p.leg_width_m / 2, p.hip_height_m}});
  }
  boxes.push_back({{p.chest_back_x_m, -p.chest_width_m / 2, p.chest_bottom_m},
                   {p.chest_front_x_m, p.chest_width_m / 2, p.chest_top_m}});

  const Eigen::Isometry3d robot_to_camera = camera.cameraToRobot().inverse();
  const auto& k = camera.intrinsics();
  constexpr double kNear = 0.01;
  for (const Box& box : boxes) {
    std::array<Eigen::Vector3d, 8> corners;
    for (int i = 0; i < 8; ++i) {
      const Eigen::Vector3d v((i & 1) ? box.max.x() : box.min.x(), (i & 2) ? box.max.y() : box.min.y(),
                              (i & 4) ? box.max.z() : box.min.z());
      corners[i] = robot_to_camera * v;
    }
    // The box clipped at the near plane: corners in front and edge crossings of the plane.
    std::vector<Eigen::Vector3d> clipped;
    for (int i = 0; i < 8; ++i) {
      if (corners[i].z() >= kNear) clipped.push_back(corners[i]);
      for (int bit : {1, 2, 4}) {
        const int j = i | bit;
        if (j == i) continue;
        const Eigen::Vector3d& a = corners[i];
        const Eigen::Vector3d& b = corners[j];
        if ((a.z() < kNear) != (b.z() < kNear)) {
          const double t = (kNear - a.z()) / (b.z() - a.z());
          clipped.push_back(a + t * (b - a));
        }
      }
    }
    if (clipped.size() < 3) continue;
    std::vector<Eigen::Vector2d> projected;
    for (const auto& c : clipped) {
      projected.emplace_back(k.center_x_px + k.focal_x_px * c.x() / c.z(),
                             k.center_y_px + k.focal_y_px * c.y() / c.z());
    }
    const std::vector<Eigen::Vector2d> poly = convexHull(projected);
    if (poly.size() < 3) continue;
    double min_x = poly[0].x(), max_x = poly[0].x(), min_y = poly[0].y();
    for (const auto& v : poly) {
      min_x = std::min(min_x, v.x());
      max_x = std::max(max_x, v.x());
      min_y = std::min(min_y, v.y());
    }
    if (max_x < 0 || min_x > w || min_y > h) continue;
    out.polygons_px.push_back(poly);
    const int x_begin = std::max(0, static_cast<int>(std::floor(min_x)));
    const int x_end = std::min(w, static_cast<int>(std::ceil(max_x)));
    for (int x = x_begin; x < x_end; ++x) {
      // Top of the polygon at the column's centre (or its nearest point inside the polygon).
      const double cx = std::clamp(x + 0.5, min_x, max_x);
      double top = 1e300;
      for (std::size_t i = 0; i < poly.size(); ++i) {
        const Eigen::Vector2d& a = poly[i];
        const Eigen::Vector2d& b = poly[(i + 1) % poly.size()];
        if ((cx < std::min(a.x(), b.x())) || (cx > std::max(a.x(), b.x()))) continue;
        const double y = (b.x() == a.x()) ? std::min(a.y(), b.y())
                                          : a.y() + (cx - a.x()) / (b.x() - a.x()) * (b.y() - a.y());
        top = std::min(top, y);
      }
      if (top > h) continue;
      const int row = std::clamp(static_cast<int>(std::floor(top)) - p.margin_px, 0, h);
      out.top_y[x] = std::min(out.top_y[x], row);
    }
  }
  return out;
}

IgnoreMask IgnoreMask::all(int width, int height) {
  IgnoreMask m;
  m.width = width;
  m.height = height;
  m.top_y.assign(width, 0);
  m.bottom_y.assign(width, height);
  return m;
}

IgnoreMask IgnoreMask::combine(const FieldBoundary& boundary, const BodyContour& body, int width,
                               int height) {
  if (static_cast<int>(boundary.boundary_y.size()) != width ||
      static_cast<int>(body.top_y.size()) != width) {
    throw Error("ignore mask: field boundary or body contour does not match the image width");
  }
  IgnoreMask m;
  m.width = width;
  m.height = height;
  m.top_y = boundary.boundary_y;
  m.bottom_y = body.top_y;
  return m;
}

}  // namespace colorfree
