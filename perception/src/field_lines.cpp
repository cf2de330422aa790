#include "colorfree/perception/field_lines.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif
#include <numeric>

#include "colorfree/perception/error.h"
#include "colorfree/perception/noise.h"
#include "colorfree/perception/param_file.h"

namespace colorfree {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

FieldLineParams FieldLineParams::load(const std::string& path) {
  ParamFile f(path);
  FieldLineParams p;
  p.scan_spacing_px = static_cast<int>(f.getInRange("scan_spacing_px", 1, 64));
  p.edge_step_px = static_cast<int>(f.getInRange("edge_step_px", 1, 8));
  p.min_edge_contrast = f.getInRange("min_edge_contrast", 1, 255);
  p.edge_noise_factor = f.getInRange("edge_noise_factor", 0, 20);
  p.smoothing_min_noise = f.getInRange("smoothing_min_noise", 0, 255);
  p.min_spot_contrast = f.getInRange("min_spot_contrast", 1, 255);
  p.min_edge_balance = f.getInRange("min_edge_balance", 0, 1);
  p.min_width_factor = f.getInRange("min_width_factor", 0, 10);
  p.max_width_factor = f.getInRange("max_width_factor", 0.1, 20);
  p.width_slack_px = f.getInRange("width_slack_px", 0, 50);
  p.max_distance_m = f.getInRange("max_distance_m", 0.1, 20);
  p.chain_max_slope = f.getInRange("chain_max_slope", 0.1, 10);
  p.min_chain_spots = static_cast<int>(f.getInRange("min_chain_spots", 2, 100));
  p.straight_tolerance_m = f.getInRange("straight_tolerance_m", 0, 1);
  p.straight_tolerance_per_metre = f.getInRange("straight_tolerance_per_metre", 0, 1);
  p.merge_max_angle_deg = f.getInRange("merge_max_angle_deg", 0, 45);
  p.merge_max_offset_m = f.getInRange("merge_max_offset_m", 0, 1);
  p.merge_max_gap_m = f.getInRange("merge_max_gap_m", 0, 10);
  p.min_line_length_m = f.getInRange("min_line_length_m", 0, 10);
  p.min_line_spots = static_cast<int>(f.getInRange("min_line_spots", 2, 1000));
  p.extend_max_gap_m = f.getInRange("extend_max_gap_m", 0, 2);
  p.width_trend_min_range = f.getInRange("width_trend_min_range", 1, 100);
  p.min_width_trend = f.getInRange("min_width_trend", -10, 10);
  p.width_trend_minority_fraction = f.getInRange("width_trend_minority_fraction", 0, 0.5);
  p.circle_radius_tolerance_m = f.getInRange("circle_radius_tolerance_m", 0, 1);
  p.circle_inlier_distance_m = f.getInRange("circle_inlier_distance_m", 0, 1);
  p.circle_inlier_distance_per_metre = f.getInRange("circle_inlier_distance_per_metre", 0, 1);
  p.min_circle_spots = static_cast<int>(f.getInRange("min_circle_spots", 3, 1000));
  p.intersection_max_angle_deg = f.getInRange("intersection_max_angle_deg", 0, 45);
  p.intersection_end_tolerance_m = f.getInRange("intersection_end_tolerance_m", 0, 2);
  p.intersection_max_extension_m = f.getInRange("intersection_max_extension_m", 0, 2);
  p.circle_line_max_offset_m = f.getInRange("circle_line_max_offset_m", 0, 2);
  p.penalty_mark_max_extent_m = f.getInRange("penalty_mark_max_extent_m", 0.01, 2);
  p.penalty_mark_clear_radius_m = f.getInRange("penalty_mark_clear_radius_m", 0, 5);
  p.penalty_mark_max_distance_m = f.getInRange("penalty_mark_max_distance_m", 0, 20);
  p.penalty_mark_max_dark_fraction = f.getInRange("penalty_mark_max_dark_fraction", 0, 1);
  p.min_penalty_mark_spots = static_cast<int>(f.getInRange("min_penalty_mark_spots", 1, 100));
  p.penalty_mark_ball_radii = f.getInRange("penalty_mark_ball_radii", 0, 10);
  f.finish();
  if (p.min_width_factor >= p.max_width_factor) {
    throw Error(path + ": min_width_factor must be below max_width_factor");
  }
  return p;
}

FieldLineParams FieldLineParams::loadDefault() { return load(defaultParamDir() + "/field_lines.yaml"); }

const char* lineRejectReasonName(LineRejectReason reason) {
  switch (reason) {
    case LineRejectReason::kTooShort: return "too short";
    case LineRejectReason::kTooFewSpots: return "too few spots";
    case LineRejectReason::kOnCircle: return "on the centre circle";
    case LineRejectReason::kNotOnGround: return "not on the ground";
  }
  return "?";
}

FieldLineDetector::FieldLineDetector(FieldLineParams params, FieldDimensions field)
    : params_(params), field_(field) {}

namespace {

// A bright run on one scan line, before projection.
struct ScanSpot {
  double along = 0;  // pixel coordinate along the scan (centre)
  double width = 0;
};

// First index i in [i, end) where |data[i] - data[i - step]| >= thr, or end. Most of a scan line
// is carpet without such an edge: 16 pixels are checked at a time where SSE2 is there.
int nextEdge(const std::uint8_t* data, int i, int end, int step, int thr) {
#if defined(__SSE2__)
  const __m128i threshold = _mm_set1_epi8(static_cast<char>(thr));
  for (; i + 16 <= end; i += 16) {
    const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(data + i));
    const __m128i b = _mm_loadu_si128(reinterpret_cast<const __m128i*>(data + i - step));
    const __m128i diff = _mm_or_si128(_mm_subs_epu8(a, b), _mm_subs_epu8(b, a));
    const int mask = _mm_movemask_epi8(_mm_cmpeq_epi8(_mm_max_epu8(diff, threshold), diff));
    if (mask != 0) return i + __builtin_ctz(static_cast<unsigned>(mask));
  }
#endif
  for (; i < end; ++i) {
    if (std::abs(data[i] - data[i - step]) >= thr) return i;
  }
  return end;
}

// Finds bright runs between a rising and a falling edge on one scan line, `data` in order along
// it; `expected(i)` is the width expected for a line centred at sample i (0: none); `thr` is the
// edge threshold (gray levels). Noise inside a bright run can make edges of its own: a fall that
// stays above half-way from the carpet before the run to the run's level is a dip inside the run
// and does not end it.
template <typename Expected>
void scanLine(const std::uint8_t* data, int begin, int end, const Expected& expected,
              const FieldLineParams& p, int thr, std::vector<ScanSpot>& out) {
  const auto at = [data](int i) { return static_cast<int>(data[i]); };
  const int step = p.edge_step_px;
  int i = begin + step;
  double rise_pos = -1, rise_strength = 0;
  int rise_foot = 0, rise_top = 0;  // levels before and after the pending rise
  while (i < end) {
    i = nextEdge(data, i, end, step, thr);
    if (i >= end) break;
    const int d = at(i) - at(i - step);
    if (d >= thr) {
      // Strongest point of the rising edge, and the levels before and after it.
      const int foot = at(i - step);
      int best = i, best_d = d;
      while (i + 1 < end) {
        const int dd = at(i + 1) - at(i + 1 - step);
        if (dd < thr) break;
        ++i;
        if (dd > best_d) best_d = dd, best = i;
      }
      rise_pos = best - step / 2.0;
      rise_strength = best_d;
      rise_foot = foot;
      rise_top = at(i);
      ++i;
      continue;
    }
    if (d <= -thr && rise_pos >= 0) {
      int best = i, best_d = -d;
      while (i + 1 < end) {
        const int dd = at(i - step + 1) - at(i + 1);
        if (dd < thr) break;
        ++i;
        if (dd > best_d) best_d = dd, best = i;
      }
      // Still above half-way from the carpet to the run's level: a dip inside the run.
      if (2 * (at(i) - rise_foot) > rise_top - rise_foot) {
        ++i;
        continue;
      }
      const double fall_pos = best - step / 2.0;
      const double width = fall_pos - rise_pos;
      const double centre = (rise_pos + fall_pos) / 2;
      const double e = expected(static_cast<int>(centre));
      const double lo_w = p.min_width_factor * e - p.width_slack_px;
      const double hi_w = p.max_width_factor * e + p.width_slack_px;
      const double balance = std::min<double>(rise_strength, best_d) / std::max<double>(rise_strength, best_d);
      if (e > 0 && width >= lo_w && width <= hi_w && balance >= p.min_edge_balance) {
        // The run must be brighter than the carpet on both sides, on average.
        const int w = std::max(1, static_cast<int>(std::lround(width)));
        const int r0 = static_cast<int>(std::ceil(rise_pos + 0.5));
        const int r1 = static_cast<int>(std::floor(fall_pos - 0.5));
        const int flank = std::max(2, w / 2);
        const int b0 = static_cast<int>(std::floor(rise_pos)) - step / 2 - flank;
        const int a1 = static_cast<int>(std::ceil(fall_pos)) + step / 2 + flank;
        if (r1 >= r0 && b0 >= begin && a1 < end) {
          double inner = 0, before = 0, after = 0;
          for (int k = r0; k <= r1; ++k) inner += at(k);
          inner /= (r1 - r0 + 1);
          for (int k = b0; k < b0 + flank; ++k) before += at(k);
          for (int k = a1 - flank + 1; k <= a1; ++k) after += at(k);
          before /= flank;
          after /= flank;
          if (inner - std::max(before, after) >= p.min_spot_contrast) out.push_back({centre, width});
        }
      }
      rise_pos = -1;
      ++i;
      continue;
    }
    ++i;
  }
}

// [1 4 6 4 1] / 16 along a scan line (in [begin, end), the ends repeated): carpet noise drops to
// about half, a line's edges move by less than a pixel.
void smoothScan(const std::uint8_t* in, int begin, int end, std::uint8_t* out) {
  const auto at = [&](int i) { return static_cast<int>(in[std::clamp(i, begin, end - 1)]); };
  int i = begin;
  for (; i < std::min(end, begin + 2); ++i) {
    out[i] = static_cast<std::uint8_t>((at(i - 2) + 4 * at(i - 1) + 6 * at(i) + 4 * at(i + 1) + at(i + 2) + 8) >> 4);
  }
  for (; i < end - 2; ++i) {
    out[i] = static_cast<std::uint8_t>(
        (in[i - 2] + 4 * in[i - 1] + 6 * in[i] + 4 * in[i + 1] + in[i + 2] + 8) >> 4);
  }
  for (; i < end; ++i) {
    out[i] = static_cast<std::uint8_t>((at(i - 2) + 4 * at(i - 1) + 6 * at(i) + 4 * at(i + 1) + at(i + 2) + 8) >> 4);
  }
}

struct Fit {
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
  Eigen::Vector2d direction = Eigen::Vector2d::UnitX();
  double t_min = 0, t_max = 0;  // extent along the direction from the centroid
  double max_residual = 0;
  double length() const { return t_max - t_min; }
  Eigen::Vector2d start() const { return centroid + t_min * direction; }
  Eigen::Vector2d end() const { return centroid + t_max * direction; }
};

Fit fitLine(const std::vector<LineSpot>& spots, const std::vector<int>& ids) {
  Fit f;
  for (int i : ids) f.centroid += spots[i].position_in_robot;
  f.centroid /= static_cast<double>(ids.size());
  double sxx = 0, sxy = 0, syy = 0;
  for (int i : ids) {
    const Eigen::Vector2d d = spots[i].position_in_robot - f.centroid;
    sxx += d.x() * d.x();
    sxy += d.x() * d.y();
    syy += d.y() * d.y();
  }
  const double angle = 0.5 * std::atan2(2 * sxy, sxx - syy);
  f.direction = {std::cos(angle), std::sin(angle)};
  const Eigen::Vector2d normal(-f.direction.y(), f.direction.x());
  f.t_min = 1e300;
  f.t_max = -1e300;
  for (int i : ids) {
    const Eigen::Vector2d d = spots[i].position_in_robot - f.centroid;
    const double t = d.dot(f.direction);
    f.t_min = std::min(f.t_min, t);
    f.t_max = std::max(f.t_max, t);
    f.max_residual = std::max(f.max_residual, std::abs(d.dot(normal)));
  }
  return f;
}

// Pixel extent, along a vertical or horizontal scan line, of a painted strip of `width_m` whose
// centre line passes through `ground` in `direction` (robot frame); 0 when it cannot be seen.
double widthAlongScan(const CameraModel& camera, const Eigen::Vector2d& ground,
                      const Eigen::Vector2d& direction, double width_m, bool vertical_scan) {
  const Eigen::Vector2d normal(-direction.y(), direction.x());
  const Eigen::Vector2d b1 = ground + width_m / 2 * normal, b2 = ground - width_m / 2 * normal;
  const auto p1 = camera.robotToPixel({b1.x(), b1.y(), 0});
  const auto p2 = camera.robotToPixel({b2.x(), b2.y(), 0});
  const Eigen::Vector2d along = b1 + 0.05 * direction;
  const auto q1 = camera.robotToPixel({along.x(), along.y(), 0});
  if (!p1 || !p2 || !q1 || (*q1 - *p1).norm() < 1e-9) return 0;
  const Eigen::Vector2d d = (*q1 - *p1).normalized();
  const Eigen::Vector2d image_normal(-d.y(), d.x());
  const double across = std::abs((*p2 - *p1).dot(image_normal));
  const double cosine = std::max(0.2, std::abs(vertical_scan ? image_normal.y() : image_normal.x()));
  return across / cosine;
}

// A white cross on the carpet has nothing darker than the carpet inside; a ball (its black
// patches) has. Compares the pixels of a square of the mark's size (a little more, seen from
// the side it is foreshortened the same way) with the carpet around it.
bool hasDarkInside(const GrayView& image, const CameraModel& camera, const Eigen::Vector2d& centre,
                   const Eigen::Vector2d& centre_px, double mark_size_m, const FieldLineParams& p) {
  // The mark's extent in the image: across (sideways on the ground) and along the view (ahead).
  const Eigen::Vector2d ahead = centre.normalized();
  const Eigen::Vector2d side(-ahead.y(), ahead.x());
  const Eigen::Vector2d a = centre + side * (mark_size_m * 0.6), b = centre + ahead * (mark_size_m * 0.6);
  const auto a_px = camera.robotToPixel({a.x(), a.y(), 0});
  const auto b_px = camera.robotToPixel({b.x(), b.y(), 0});
  if (!a_px || !b_px) return false;
  const int half_x = std::max(2, static_cast<int>(std::lround(std::abs(a_px->x() - centre_px.x()) + std::abs(b_px->x() - centre_px.x()))));
  const int half_y = std::max(2, static_cast<int>(std::lround(std::abs(a_px->y() - centre_px.y()) + std::abs(b_px->y() - centre_px.y()))));
  const int cx = static_cast<int>(centre_px.x()), cy = static_cast<int>(centre_px.y());
  std::vector<int> ring, inner;
  int inside = 0;
  for (int y = cy - 2 * half_y; y <= cy + 2 * half_y; ++y) {
    for (int x = cx - 2 * half_x; x <= cx + 2 * half_x; x += 2) {
      if (!image.contains(x, y)) continue;
      const bool in = std::abs(x - cx) <= half_x && std::abs(y - cy) <= half_y;
      (in ? inner : ring).push_back(image.at(x, y));
    }
  }
  if (ring.size() < 8 || inner.empty()) return false;
  std::nth_element(ring.begin(), ring.begin() + ring.size() / 2, ring.end());
  const double carpet = ring[ring.size() / 2];
  for (int v : inner) inside += v < carpet - p.min_spot_contrast;
  return inside > p.penalty_mark_max_dark_fraction * static_cast<double>(inner.size());
}

struct Piece {
  std::vector<int> ids;
  Fit fit;
  bool alive = true;
};

// Kåsa's algebraic circle fit; false when degenerate.
bool fitCircle(const std::vector<Eigen::Vector2d>& pts, Eigen::Vector2d& centre, double& radius) {
  if (pts.size() < 3) return false;
  Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const auto& p : pts) {
    const Eigen::Vector3d row(p.x(), p.y(), 1);
    const double z = p.squaredNorm();
    a += row * row.transpose();
    b += row * z;
  }
  const Eigen::Vector3d s = a.ldlt().solve(b);
  if (!s.allFinite()) return false;
  centre = {s(0) / 2, s(1) / 2};
  const double r2 = s(2) + centre.squaredNorm();
  if (r2 <= 0) return false;
  radius = std::sqrt(r2);
  return true;
}

}  // namespace

FieldLineResult FieldLineDetector::run(const GrayView& image, const CameraModel& camera,
                                       const IgnoreMask& ignore, bool keep_rejected) const {
  const int w = image.width;
  const int h = image.height;
  if (w != camera.width() || h != camera.height()) {
    throw Error("field lines: image is " + std::to_string(w) + "x" + std::to_string(h) +
                " but the camera model is " + std::to_string(camera.width()) + "x" +
                std::to_string(camera.height()));
  }
  if (ignore.width != w || ignore.height != h) {
    throw Error("field lines: ignore mask does not match the image size");
  }
  const FieldLineParams& p = params_;
  const double lw = field_.line_width_m;
  FieldLineResult out;

  // Expected pixel widths of a line per row, measured at the image's middle column on every
  // kWidthRowStep-th row and interpolated between.
  std::vector<double> expected_v(h, 0), expected_h(h, 0);
  const Eigen::Vector3d cam = camera.position();
  const double cx = w / 2.0;
  constexpr int kWidthRowStep = 4;
  const auto widthsAt = [&](int y, double& v, double& hz) {
    v = hz = 0;
    const auto g = camera.pixelToGround({cx, y + 0.5});
    if (!g || (*g - cam.head<2>()).norm() > p.max_distance_m) return;
    const Eigen::Vector2d away = (*g - cam.head<2>()).normalized();
    const Eigen::Vector2d side(-away.y(), away.x());
    const auto a = camera.robotToPixel({g->x() + lw * away.x(), g->y() + lw * away.y(), 0});
    const auto b = camera.robotToPixel({g->x() + lw * side.x(), g->y() + lw * side.y(), 0});
    if (a) v = std::abs(a->y() - (y + 0.5));
    if (b) hz = std::abs(b->x() - cx);
  };
  // Each measured row once (a block's last row is the next one's first).
  double v1 = 0, h1 = 0;
  int measured = -1;
  for (int y0 = 0; y0 < h; y0 += kWidthRowStep) {
    const int y1 = std::min(y0 + kWidthRowStep, h - 1);
    double v0, h0;
    if (measured == y0) {
      v0 = v1, h0 = h1;
    } else {
      widthsAt(y0, v0, h0);
    }
    widthsAt(y1, v1, h1);
    measured = y1;
    for (int y = y0; y < std::min(y0 + kWidthRowStep, h); ++y) {
      // Rows next to the horizon or the distance limit keep 0 (no line expected).
      if (v0 <= 0 || v1 <= 0) {
        if (y == y0) expected_v[y] = v0, expected_h[y] = h0;
        continue;
      }
      const double t = y1 > y0 ? static_cast<double>(y - y0) / (y1 - y0) : 0;
      expected_v[y] = v0 + t * (v1 - v0);
      expected_h[y] = h0 + t * (h1 - h0);
    }
  }

  // Vertical scan lines: spots per scan line, kept in order of scan lines.
  const int spacing = p.scan_spacing_px;
  std::vector<ScanSpot> found;
  std::vector<std::vector<int>> vertical_lines, horizontal_lines;
  const auto addSpot = [&](const Eigen::Vector2d& px, double width, double expected, bool vertical) {
    const auto g = camera.pixelToGround(px);
    if (!g || (*g - cam.head<2>()).norm() > p.max_distance_m) return -1;
    LineSpot s;
    s.position_px = px;
    s.position_in_robot = *g;
    s.width_px = width;
    s.expected_width_px = expected;
    s.vertical_scan = vertical;
    out.spots.push_back(s);
    return static_cast<int>(out.spots.size()) - 1;
  };
  // The vertical scan lines copied into contiguous columns, reading the image row by row.
  const int scan_columns = (w - spacing / 2 + spacing - 1) / spacing;
  std::vector<std::uint8_t> columns(static_cast<std::size_t>(scan_columns) * h);
  {
    const int first_row = *std::min_element(ignore.top_y.begin(), ignore.top_y.end());
    const int last_row = *std::max_element(ignore.bottom_y.begin(), ignore.bottom_y.end());
    // Blocks of 16 rows: each column gets 16 bytes in one store, the rows stay in the cache.
    constexpr int kBlock = 16;
    const int y_end = std::min(h, last_row);
    int y = std::max(0, first_row);
    for (; y + kBlock <= y_end; y += kBlock) {
      const std::uint8_t* rows[kBlock];
      for (int r = 0; r < kBlock; ++r) rows[r] = image.row(y + r);
      for (int c = 0, x = spacing / 2; c < scan_columns; ++c, x += spacing) {
        std::uint8_t block[kBlock];
        for (int r = 0; r < kBlock; ++r) block[r] = rows[r][x];
        std::memcpy(columns.data() + static_cast<std::size_t>(c) * h + y, block, kBlock);
      }
    }
    for (; y < y_end; ++y) {
      const std::uint8_t* row = image.row(y);
      for (int c = 0, x = spacing / 2; c < scan_columns; ++c, x += spacing) {
        columns[static_cast<std::size_t>(c) * h + y] = row[x];
      }
    }
  }
  // The horizontal scan lines (copied only when they are smoothed).
  const int scan_rows = (h - spacing / 2 + spacing - 1) / spacing;
  std::vector<std::uint8_t> rows;
  const auto rowData = [&](int y) -> const std::uint8_t* {
    return rows.empty() ? image.row(y) : rows.data() + static_cast<std::size_t>(y / spacing) * w;
  };
  const auto columnData = [&](int x) { return columns.data() + static_cast<std::size_t>(x / spacing) * h; };
  // Carpet noise along both kinds of scan lines, from every fourth scan line and sample: the
  // differences of neighbouring pixels (as noisy as those over edge_step_px for pixel noise, but
  // less affected by the carpet's smooth texture and shading).
  const auto noiseOf = [&](bool vertical) {
    DifferenceNoise noise;
    if (vertical) {
      for (int x = spacing / 2; x < w; x += 4 * spacing) {
        const std::uint8_t* d = columnData(x);
        for (int i = ignore.top_y[x] + 1; i < ignore.bottom_y[x]; i += 4) noise.add(d[i] - d[i - 1]);
      }
    } else {
      for (int y = spacing / 2; y < h; y += 4 * spacing) {
        if (expected_h[y] <= 0) continue;
        const std::uint8_t* d = rowData(y);
        for (int x = 1; x < w; x += 4) {
          if (ignore.looked(x, y) && ignore.looked(x - 1, y)) noise.add(d[x] - d[x - 1]);
        }
      }
    }
    return noise.sigma();
  };
  double noise_v = noiseOf(true), noise_h = noiseOf(false);
  // Noisy frames: the scan lines are smoothed first (the noise of one pixel is the edge noise
  // over sqrt(2)).
  if (std::max(noise_v, noise_h) / std::sqrt(2.0) >= p.smoothing_min_noise) {
    std::vector<std::uint8_t> raw(static_cast<std::size_t>(std::max(w, h)));
    for (int x = spacing / 2; x < w; x += spacing) {
      const int top = ignore.top_y[x], bottom = ignore.bottom_y[x];
      if (bottom - top < 3) continue;
      std::uint8_t* d = columns.data() + static_cast<std::size_t>(x / spacing) * h;
      std::memcpy(raw.data() + top, d + top, static_cast<std::size_t>(bottom - top));
      smoothScan(raw.data(), top, bottom, d);
    }
    rows.assign(static_cast<std::size_t>(scan_rows) * w, 0);
    for (int y = spacing / 2; y < h; y += spacing) {
      std::uint8_t* d = rows.data() + static_cast<std::size_t>(y / spacing) * w;
      std::memcpy(d, image.row(y), static_cast<std::size_t>(w));
      // Each looked-at run on its own (the ignored pixels do not bleed in).
      int x = 0;
      while (x < w) {
        while (x < w && !ignore.looked(x, y)) ++x;
        const int begin = x;
        while (x < w && ignore.looked(x, y)) ++x;
        if (x - begin >= 3) smoothScan(image.row(y), begin, x, d);
      }
    }
    noise_v = noiseOf(true);
    noise_h = noiseOf(false);
  }
  const auto threshold = [&](double noise) {
    return std::clamp(static_cast<int>(std::ceil(std::max(p.min_edge_contrast, p.edge_noise_factor * noise))), 1, 255);
  };
  const int thr_v = threshold(noise_v), thr_h = threshold(noise_h);

  for (int x = spacing / 2; x < w; x += spacing) {
    vertical_lines.emplace_back();
    const int top = ignore.top_y[x];
    const int bottom = ignore.bottom_y[x];
    if (bottom - top < 3 * p.edge_step_px) continue;
    found.clear();
    scanLine(
        columnData(x), top, bottom, [&](int y) { return expected_v[std::clamp(y, 0, h - 1)]; }, p, thr_v,
        found);
    for (const ScanSpot& s : found) {
      const int id = addSpot({x + 0.5, s.along + 0.5}, s.width,
                             expected_v[std::clamp(static_cast<int>(s.along), 0, h - 1)], true);
      if (id >= 0) vertical_lines.back().push_back(id);
    }
  }
  const int max_top = *std::max_element(ignore.top_y.begin(), ignore.top_y.end());
  const int min_bottom = *std::min_element(ignore.bottom_y.begin(), ignore.bottom_y.end());
  for (int y = spacing / 2; y < h; y += spacing) {
    horizontal_lines.emplace_back();
    if (expected_h[y] <= 0) continue;
    const std::uint8_t* row = rowData(y);
    const bool whole_row = y >= max_top && y < min_bottom;
    int x = 0;
    while (x < w) {
      int begin = 0;
      if (whole_row) {
        x = w;
      } else {
        while (x < w && !ignore.looked(x, y)) ++x;
        begin = x;
        while (x < w && ignore.looked(x, y)) ++x;
      }
      if (x - begin < 3 * p.edge_step_px) continue;
      found.clear();
      scanLine(row, begin, x, [&](int) { return expected_h[y]; }, p, thr_h, found);
      for (const ScanSpot& s : found) {
        const int id = addSpot({s.along + 0.5, y + 0.5}, s.width, expected_h[y], false);
        if (id >= 0) horizontal_lines.back().push_back(id);
      }
    }
  }

  // Chains of spots on neighbouring scan lines (one gap allowed), in the image.
  std::vector<std::vector<int>> chains;
  const auto chainScans = [&](const std::vector<std::vector<int>>& scans, bool vertical) {
    struct Open {
      int chain;
      int last_scan;
      double slope;  // pixels across per scan line, once two spots are in
      bool has_slope;
    };
    std::vector<Open> open;
    const auto across = [&](int id) {
      return vertical ? out.spots[id].position_px.y() : out.spots[id].position_px.x();
    };
    for (int scan = 0; scan < static_cast<int>(scans.size()); ++scan) {
      std::vector<char> taken(open.size(), 0);
      std::vector<std::pair<int, int>> joins;  // (open index or -1, spot)
      for (int id : scans[scan]) {
        int best = -1;
        double best_err = 1e300;
        for (std::size_t k = 0; k < open.size(); ++k) {
          if (taken[k]) continue;
          const int last = chains[open[k].chain].back();
          const int steps = scan - open[k].last_scan;
          const double jump = across(id) - across(last);
          if (std::abs(jump) > p.chain_max_slope * steps * spacing + out.spots[id].width_px / 2) continue;
          const double err = std::abs(jump - (open[k].has_slope ? open[k].slope * steps : 0.0));
          if (err < best_err) best_err = err, best = static_cast<int>(k);
        }
        if (best >= 0) taken[best] = 1;
        joins.emplace_back(best, id);
      }
      for (const auto& [k, id] : joins) {
        if (k >= 0) {
          auto& chain = chains[open[k].chain];
          open[k].slope = (across(id) - across(chain.back())) / (scan - open[k].last_scan);
          open[k].has_slope = true;
          chain.push_back(id);
          open[k].last_scan = scan;
        } else {
          chains.push_back({id});
          open.push_back({static_cast<int>(chains.size()) - 1, scan, 0.0, false});
        }
      }
      open.erase(std::remove_if(open.begin(), open.end(),
                                [&](const Open& o) { return scan - o.last_scan >= 2; }),
                 open.end());
    }
  };
  chainScans(vertical_lines, true);
  chainScans(horizontal_lines, false);

  // Straight pieces on the ground; a chain that bends (a corner, an arc) is split where it is
  // farthest from its fitted line, until every piece is straight.
  std::vector<Piece> pieces;
  std::vector<char> in_chain(out.spots.size(), 0);
  const auto tolerance = [&](const Fit& f) {
    const double dist = (f.centroid - cam.head<2>()).norm();
    return p.straight_tolerance_m + p.straight_tolerance_per_metre * dist;
  };
  std::vector<std::vector<int>> long_chains;
  std::vector<std::vector<int>> todo;
  for (const auto& chain : chains) {
    if (static_cast<int>(chain.size()) < p.min_chain_spots) continue;
    for (int id : chain) in_chain[id] = 1;
    long_chains.push_back(chain);
    todo.push_back(chain);
  }
  while (!todo.empty()) {
    std::vector<int> ids = std::move(todo.back());
    todo.pop_back();
    Piece piece;
    piece.fit = fitLine(out.spots, ids);
    const double tol = tolerance(piece.fit);
    if (piece.fit.max_residual <= tol) {
      piece.ids = std::move(ids);
      pieces.push_back(std::move(piece));
      continue;
    }
    const Eigen::Vector2d normal(-piece.fit.direction.y(), piece.fit.direction.x());
    std::size_t worst = 0;
    double worst_residual = -1;
    for (std::size_t i = 0; i < ids.size(); ++i) {
      const double r = std::abs((out.spots[ids[i]].position_in_robot - piece.fit.centroid).dot(normal));
      if (r > worst_residual) worst_residual = r, worst = i;
    }
    worst = std::clamp<std::size_t>(worst, 1, ids.size() - 1);
    std::vector<int> first(ids.begin(), ids.begin() + static_cast<long>(worst));
    std::vector<int> second(ids.begin() + static_cast<long>(worst), ids.end());
    if (static_cast<int>(first.size()) >= p.min_chain_spots) todo.push_back(std::move(first));
    if (static_cast<int>(second.size()) >= p.min_chain_spots) todo.push_back(std::move(second));
  }

  // Centre circle: every chained spot votes for the two centres a radius away along its normal.
  const double radius = field_.centre_circle_diameter_m / 2;
  std::vector<char> on_circle(out.spots.size(), 0);
  {
    constexpr double kCell = 0.1;
    // Votes counted on a dense grid around the robot (spots are at most max_distance away).
    const double reach = p.max_distance_m + radius + kCell;
    const int cells = 2 * static_cast<int>(std::ceil(reach / kCell)) + 1;
    const int offset = cells / 2;
    std::vector<std::uint16_t> grid(static_cast<std::size_t>(cells) * cells, 0);
    std::vector<int> voted;
    const Eigen::Vector2d origin = cam.head<2>();
    for (const auto& c : long_chains) {
      for (std::size_t i = 0; i < c.size(); ++i) {
        const std::size_t a = i > 0 ? i - 1 : i;
        const std::size_t b = i + 1 < c.size() ? i + 1 : i;
        const Eigen::Vector2d t = out.spots[c[b]].position_in_robot - out.spots[c[a]].position_in_robot;
        if (t.norm() < 1e-6) continue;
        const Eigen::Vector2d n = Eigen::Vector2d(-t.y(), t.x()).normalized();
        for (double sgn : {-1.0, 1.0}) {
          const Eigen::Vector2d centre = out.spots[c[i]].position_in_robot + sgn * radius * n - origin;
          const int gx = static_cast<int>(std::floor(centre.x() / kCell)) + offset;
          const int gy = static_cast<int>(std::floor(centre.y() / kCell)) + offset;
          if (gx < 1 || gy < 1 || gx >= cells - 1 || gy >= cells - 1) continue;
          const int index = gy * cells + gx;
          if (grid[index]++ == 0) voted.push_back(index);
        }
      }
    }
    int best_votes = 0;
    int best_index = 0;
    for (int index : voted) {
      int sum = 0;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) sum += grid[index + dy * cells + dx];
      }
      if (sum > best_votes || (sum == best_votes && index < best_index)) best_votes = sum, best_index = index;
    }
    const std::pair<int, int> best_cell{best_index % cells - offset, best_index / cells - offset};
    if (best_votes >= p.min_circle_spots) {
      Eigen::Vector2d centre =
          origin + Eigen::Vector2d((best_cell.first + 0.5) * kCell, (best_cell.second + 0.5) * kCell);
      bool ok = false;
      // Spots farther away are placed less precisely on the ground.
      const auto inlierDistance = [&](int id) {
        return p.circle_inlier_distance_m +
               p.circle_inlier_distance_per_metre * (out.spots[id].position_in_robot - cam.head<2>()).norm();
      };
      std::vector<int> inliers;
      // Refit a few times on the chains that lie (mostly) on the current circle: a straight line
      // touches a circle only along a short stretch, so its chain is mostly off it.
      for (int iteration = 0; iteration < 3; ++iteration) {
        inliers.clear();
        std::vector<Eigen::Vector2d> pts;
        const double scale = iteration == 0 ? 1.5 : 1.0;
        for (const auto& chain : long_chains) {
          std::size_t first = inliers.size();
          for (int id : chain) {
            const double d = (out.spots[id].position_in_robot - centre).norm();
            if (std::abs(d - radius) <= scale * inlierDistance(id)) inliers.push_back(id);
          }
          if ((inliers.size() - first) * 10 < chain.size() * 7) {
            inliers.resize(first);
            continue;
          }
          for (std::size_t i = first; i < inliers.size(); ++i) pts.push_back(out.spots[inliers[i]].position_in_robot);
        }
        Eigen::Vector2d c;
        double r;
        ok = static_cast<int>(pts.size()) >= p.min_circle_spots && fitCircle(pts, c, r) &&
             std::abs(r - radius) <= p.circle_radius_tolerance_m;
        if (!ok) break;
        centre = c;
      }
      if (ok) {
        // The points must go round the centre: a straight line touches it only in a narrow arc.
        std::vector<double> angles;
        for (int id : inliers) {
          const Eigen::Vector2d d = out.spots[id].position_in_robot - centre;
          angles.push_back(std::atan2(d.y(), d.x()));
        }
        std::sort(angles.begin(), angles.end());
        double largest_gap = angles.front() + 2 * kPi - angles.back();
        for (std::size_t i = 1; i < angles.size(); ++i) largest_gap = std::max(largest_gap, angles[i] - angles[i - 1]);
        const double span = 2 * kPi - largest_gap;
        if (span >= kPi / 2.5) {
          CircleMarkPercept circle;
          circle.centre_in_robot = centre;
          if (const auto px = camera.robotToPixel({centre.x(), centre.y(), 0})) circle.centre_px = *px;
          out.features.centre_circle = circle;
          for (int id : inliers) out.circle_points_in_robot.push_back(out.spots[id].position_in_robot);
          for (int id = 0; id < static_cast<int>(out.spots.size()); ++id) {
            const double d = (out.spots[id].position_in_robot - centre).norm();
            if (in_chain[id] && std::abs(d - radius) <= inlierDistance(id)) on_circle[id] = 1;
          }
        }
      }
    }
  }

  // Pieces mostly on the circle are its arcs, not lines.
  std::vector<RejectedLine> rejected;
  const auto toPercept = [&](const Fit& f) {
    LinePercept l;
    l.start_in_robot = f.start();
    l.end_in_robot = f.end();
    if (const auto a = camera.robotToPixel({l.start_in_robot.x(), l.start_in_robot.y(), 0})) l.start_px = *a;
    if (const auto b = camera.robotToPixel({l.end_in_robot.x(), l.end_in_robot.y(), 0})) l.end_px = *b;
    return l;
  };
  if (out.features.centre_circle) {
    for (auto& pc : pieces) {
      int n = 0;
      for (int id : pc.ids) n += on_circle[id];
      if (n * 10 >= static_cast<int>(pc.ids.size()) * 7) {
        pc.alive = false;
        if (keep_rejected) rejected.push_back({toPercept(pc.fit), LineRejectReason::kOnCircle});
      }
    }
  }

  // Merge collinear pieces, longest first.
  std::sort(pieces.begin(), pieces.end(),
            [](const Piece& a, const Piece& b) { return a.fit.length() > b.fit.length(); });
  const double max_cos = std::cos(p.merge_max_angle_deg * kPi / 180);
  bool merged_any = true;
  while (merged_any) {
    merged_any = false;
    for (std::size_t i = 0; i < pieces.size(); ++i) {
      if (!pieces[i].alive) continue;
      for (std::size_t j = i + 1; j < pieces.size(); ++j) {
        if (!pieces[j].alive) continue;
        const Fit& a = pieces[i].fit;
        const Fit& b = pieces[j].fit;
        if (std::abs(a.direction.dot(b.direction)) < max_cos) continue;
        const Eigen::Vector2d normal(-a.direction.y(), a.direction.x());
        if (std::abs((b.start() - a.centroid).dot(normal)) > p.merge_max_offset_m ||
            std::abs((b.end() - a.centroid).dot(normal)) > p.merge_max_offset_m) {
          continue;
        }
        const double s0 = (b.start() - a.centroid).dot(a.direction);
        const double s1 = (b.end() - a.centroid).dot(a.direction);
        const double gap = std::max(std::min(s0, s1) - a.t_max, a.t_min - std::max(s0, s1));
        if (gap > p.merge_max_gap_m) continue;
        std::vector<int> ids = pieces[i].ids;
        ids.insert(ids.end(), pieces[j].ids.begin(), pieces[j].ids.end());
        const Fit f = fitLine(out.spots, ids);
        if (f.max_residual > tolerance(f) + p.merge_max_offset_m / 2) continue;
        pieces[i].ids = std::move(ids);
        pieces[i].fit = f;
        pieces[j].alive = false;
        merged_any = true;
      }
    }
  }

  // Spots lost when a chain was split at a corner, or on short pieces, join the line they lie on
  // (a spot at a corner may serve both lines).
  for (auto& pc : pieces) {
    if (!pc.alive) continue;
    const Fit& f = pc.fit;
    const Eigen::Vector2d normal(-f.direction.y(), f.direction.x());
    const double tol = tolerance(f);
    std::vector<char> own(out.spots.size(), 0);
    for (int id : pc.ids) own[id] = 1;
    std::vector<int> ids = pc.ids;
    for (int id = 0; id < static_cast<int>(out.spots.size()); ++id) {
      if (own[id] || on_circle[id]) continue;
      const Eigen::Vector2d d = out.spots[id].position_in_robot - f.centroid;
      const double t = d.dot(f.direction);
      if (std::abs(d.dot(normal)) <= tol && t >= f.t_min - p.extend_max_gap_m && t <= f.t_max + p.extend_max_gap_m) {
        ids.push_back(id);
      }
    }
    if (ids.size() == pc.ids.size()) continue;
    const Fit grown = fitLine(out.spots, ids);
    if (grown.max_residual <= tolerance(grown)) {
      pc.ids = std::move(ids);
      pc.fit = grown;
    }
  }

  std::vector<char> on_line(out.spots.size(), 0);
  for (const auto& pc : pieces) {
    if (!pc.alive) continue;
    std::optional<LineRejectReason> reason;
    if (pc.fit.length() < p.min_line_length_m) {
      reason = LineRejectReason::kTooShort;
    } else if (static_cast<int>(pc.ids.size()) < p.min_line_spots) {
      reason = LineRejectReason::kTooFewSpots;
    } else {
      // Widths of a painted line grow with the width it would have at each spot (given the line's
      // direction on the ground); those of an upright part (a robot's leg) do not.
      std::vector<double> expected;
      expected.reserve(pc.ids.size());
      // Spots scanned the other way than most of the piece's, when they are few (a robot's feet
      // standing on the line join it as a few such spots, their widths nothing like a painted
      // line's there), are left out of the trend.
      int vertical = 0;
      for (int id : pc.ids) vertical += out.spots[id].vertical_scan ? 1 : 0;
      const int others = std::min<int>(vertical, static_cast<int>(pc.ids.size()) - vertical);
      const bool majority_vertical = 2 * vertical >= static_cast<int>(pc.ids.size());
      const bool drop_others = others <= p.width_trend_minority_fraction * static_cast<double>(pc.ids.size());
      std::vector<char> counted(pc.ids.size(), 0);
      double e_min = 1e300, e_max = 0;
      for (std::size_t i = 0; i < pc.ids.size(); ++i) {
        const auto& spot = out.spots[pc.ids[i]];
        const double e = widthAlongScan(camera, spot.position_in_robot, pc.fit.direction, lw, spot.vertical_scan);
        expected.push_back(e);
        counted[i] = e > 0 && !(drop_others && spot.vertical_scan != majority_vertical);
        if (counted[i]) e_min = std::min(e_min, e), e_max = std::max(e_max, e);
      }
      if (e_max > 0 && e_max / e_min >= p.width_trend_min_range) {
        double mx = 0, my = 0, n = 0;
        for (std::size_t i = 0; i < pc.ids.size(); ++i) {
          if (!counted[i]) continue;
          mx += std::log(expected[i]);
          my += std::log(std::max(1.0, out.spots[pc.ids[i]].width_px));
          ++n;
        }
        mx /= n;
        my /= n;
        double sxy = 0, sxx = 0;
        for (std::size_t i = 0; i < pc.ids.size(); ++i) {
          if (!counted[i]) continue;
          const double dx = std::log(expected[i]) - mx;
          sxy += dx * (std::log(std::max(1.0, out.spots[pc.ids[i]].width_px)) - my);
          sxx += dx * dx;
        }
        if (sxx > 0 && sxy / sxx < p.min_width_trend) reason = LineRejectReason::kNotOnGround;
      }
    }
    if (reason) {
      if (keep_rejected) rejected.push_back({toPercept(pc.fit), *reason});
      continue;
    }
    for (int id : pc.ids) on_line[id] = 1;
    out.features.lines.push_back(toPercept(pc.fit));
  }
  if (keep_rejected) out.rejected = std::move(rejected);

  // Intersections of lines that meet at about a right angle.
  const double max_dot = std::sin(p.intersection_max_angle_deg * kPi / 180);
  const auto& lines = out.features.lines;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    for (std::size_t j = i + 1; j < lines.size(); ++j) {
      const Eigen::Vector2d a0 = lines[i].start_in_robot, b0 = lines[j].start_in_robot;
      const Eigen::Vector2d da = lines[i].end_in_robot - a0, db = lines[j].end_in_robot - b0;
      const double la = da.norm(), lb = db.norm();
      const Eigen::Vector2d ua = da / la, ub = db / lb;
      if (std::abs(ua.dot(ub)) > max_dot) continue;
      const double det = ua.x() * (-ub.y()) - ua.y() * (-ub.x());
      if (std::abs(det) < 1e-9) continue;
      const Eigen::Vector2d r = b0 - a0;
      const double ta = (r.x() * (-ub.y()) - r.y() * (-ub.x())) / det;
      const double tb = (ua.x() * r.y() - ua.y() * r.x()) / det;
      const double ext = p.intersection_max_extension_m;
      if (ta < -ext || ta > la + ext || tb < -ext || tb > lb + ext) continue;
      const double tol = p.intersection_end_tolerance_m;
      const bool a_end = ta < tol || ta > la - tol;
      const bool b_end = tb < tol || tb > lb - tol;
      IntersectionPercept x;
      x.position_in_robot = a0 + ta * ua;
      if (const auto px = camera.robotToPixel({x.position_in_robot.x(), x.position_in_robot.y(), 0})) {
        x.position_px = *px;
      }
      const Eigen::Vector2d away_a = ta < la / 2 ? ua : Eigen::Vector2d(-ua);
      const Eigen::Vector2d away_b = tb < lb / 2 ? ub : Eigen::Vector2d(-ub);
      if (a_end && b_end) {
        x.type = IntersectionType::kL;
        x.direction1_in_robot = away_a;
        x.direction2_in_robot = away_b;
      } else if (a_end) {
        x.type = IntersectionType::kT;
        x.direction1_in_robot = away_a;
        x.direction2_in_robot = ub;
      } else if (b_end) {
        x.type = IntersectionType::kT;
        x.direction1_in_robot = away_b;
        x.direction2_in_robot = ua;
      } else {
        x.type = IntersectionType::kX;
        x.direction1_in_robot = ua;
        x.direction2_in_robot = ub;
      }
      out.features.intersections.push_back(x);
    }
  }

  // The halfway line crosses the centre circle in two X intersections.
  if (out.features.centre_circle) {
    const Eigen::Vector2d centre = out.features.centre_circle->centre_in_robot;
    for (std::size_t i = 0; i < lines.size(); ++i) {
      const Eigen::Vector2d a0 = lines[i].start_in_robot;
      const Eigen::Vector2d d = lines[i].end_in_robot - a0;
      const double len = d.norm();
      const Eigen::Vector2d u = d / len;
      const Eigen::Vector2d normal(-u.y(), u.x());
      if (std::abs((centre - a0).dot(normal)) > p.circle_line_max_offset_m) continue;
      const double tc = (centre - a0).dot(u);
      for (double t : {tc - radius, tc + radius}) {
        if (t < -p.intersection_max_extension_m || t > len + p.intersection_max_extension_m) continue;
        IntersectionPercept x;
        x.type = IntersectionType::kX;
        x.position_in_robot = a0 + t * u;
        if (const auto px = camera.robotToPixel({x.position_in_robot.x(), x.position_in_robot.y(), 0})) {
          x.position_px = *px;
        }
        x.direction1_in_robot = u;
        x.direction2_in_robot = normal;
        out.features.intersections.push_back(x);
      }
    }
  }

  // Penalty marks: a small cluster of spots not on a line or the circle, alone on the carpet.
  std::vector<int> loose;
  for (int id = 0; id < static_cast<int>(out.spots.size()); ++id) {
    if (!on_line[id] && !on_circle[id]) loose.push_back(id);
  }
  std::vector<char> used(out.spots.size(), 0);
  for (int seed : loose) {
    if (used[seed]) continue;
    std::vector<int> cluster;
    for (int id : loose) {
      if (!used[id] && (out.spots[id].position_in_robot - out.spots[seed].position_in_robot).norm() <=
                           p.penalty_mark_max_extent_m) {
        cluster.push_back(id);
      }
    }
    if (static_cast<int>(cluster.size()) < p.min_penalty_mark_spots) continue;
    // A cross is crossed by both vertical and horizontal scan lines.
    bool vertical = false, horizontal = false;
    for (int id : cluster) (out.spots[id].vertical_scan ? vertical : horizontal) = true;
    if (!vertical || !horizontal) {
      for (int id : cluster) used[id] = 1;
      continue;
    }
    Eigen::Vector2d centre = Eigen::Vector2d::Zero();
    for (int id : cluster) centre += out.spots[id].position_in_robot;
    centre /= static_cast<double>(cluster.size());
    double extent = 0;
    for (int a : cluster) {
      for (int b : cluster) {
        extent = std::max(extent, (out.spots[a].position_in_robot - out.spots[b].position_in_robot).norm());
      }
    }
    bool clear = extent <= p.penalty_mark_max_extent_m &&
                 (centre - cam.head<2>()).norm() <= p.penalty_mark_max_distance_m;
    for (int id = 0; clear && id < static_cast<int>(out.spots.size()); ++id) {
      if (std::find(cluster.begin(), cluster.end(), id) != cluster.end()) continue;
      if ((out.spots[id].position_in_robot - centre).norm() < p.penalty_mark_clear_radius_m) clear = false;
    }
    for (int id : cluster) used[id] = 1;
    if (!clear) continue;
    const auto centre_px = camera.robotToPixel({centre.x(), centre.y(), 0});
    if (!centre_px || hasDarkInside(image, camera, centre, *centre_px, field_.penalty_mark_size_m, p)) continue;
    CircleMarkPercept mark;
    mark.centre_in_robot = centre;
    mark.centre_px = *centre_px;
    out.features.penalty_marks.push_back(mark);
  }
  return out;
}

}  // namespace colorfree
