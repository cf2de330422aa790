#include "colorfree/perception/ball_proposer.h"

#include <algorithm>
#include <cmath>
#include <memory>

#if defined(__AVX512F__)
#include <immintrin.h>
#elif defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "colorfree/perception/error.h"
#include "colorfree/perception/noise.h"
#include "colorfree/perception/param_file.h"

namespace colorfree {

BallProposerParams BallProposerParams::load(const std::string& path) {
  ParamFile f(path);
  BallProposerParams p;
  p.ball_radius_m = f.getInRange("ball_radius_m", 0.01, 0.5);
  p.min_radius_px = f.getInRange("min_radius_px", 1, 50);
  p.max_radius_px = f.getInRange("max_radius_px", 2, 500);
  p.step_fraction = f.getInRange("step_fraction", 0, 1);
  p.inner_fraction = f.getInRange("inner_fraction", 0.1, 1.5);
  p.outer_fraction = f.getInRange("outer_fraction", 0.2, 4);
  p.print_weight = f.getInRange("print_weight", 0, 10);
  p.min_response = f.getInRange("min_response", -255, 255);
  p.light_response_fraction = f.getInRange("light_response_fraction", 0, 10);
  p.light_contrast_fraction = f.getInRange("light_contrast_fraction", 0, 10);
  p.light_max_window_contrast = f.getInRange("light_max_window_contrast", 0, 255);
  p.per_window_count = static_cast<int>(f.getInRange("per_window_count", 1, 16));
  p.nms_fraction = f.getInRange("nms_fraction", 0, 10);
  p.max_count = static_cast<int>(f.getInRange("max_count", 1, 1000));
  p.line_count = static_cast<int>(f.getInRange("line_count", 0, 1000));
  p.line_min_response = f.getInRange("line_min_response", -255, 255);
  p.feet_region_diameters = f.getInRange("feet_region_diameters", 0, 20);
  p.feet_boost = f.getInRange("feet_boost", 0, 10);
  p.texture_weight = f.getInRange("texture_weight", 0, 10);
  p.texture_reference_radius_px = f.getInRange("texture_reference_radius_px", 1, 100);
  p.texture_scale_exponent = f.getInRange("texture_scale_exponent", 0, 2);
  p.texture_noise_factor = f.getInRange("texture_noise_factor", 0, 10);
  p.noise_free_gray = f.getInRange("noise_free_gray", 0, 255);
  p.response_noise_factor = f.getInRange("response_noise_factor", 0, 20);
  p.robot_body_factor = f.getInRange("robot_body_factor", 0, 1);
  p.robot_body_width_fraction = f.getInRange("robot_body_width_fraction", 0, 1);
  p.off_axis_exponent = f.getInRange("off_axis_exponent", 0, 2);
  p.centre_search_fraction = f.getInRange("centre_search_fraction", 0, 2);
  p.radius_tolerance = f.getInRange("radius_tolerance", 0, 0.5);
  p.min_gradient = f.getInRange("min_gradient", 0, 255);
  p.centre_ridge_fraction = f.getInRange("centre_ridge_fraction", 0, 1);
  p.centre_ridge_min_radius_px = f.getInRange("centre_ridge_min_radius_px", 0, 500);
  p.smear_surround_fraction = f.getInRange("smear_surround_fraction", 0, 2);
  f.finish();
  if (p.line_count > p.max_count) throw Error(path + ": line_count must not exceed max_count");
  if (p.max_radius_px <= p.min_radius_px) {
    throw Error(path + ": max_radius_px must be larger than min_radius_px");
  }
  if (p.outer_fraction <= p.inner_fraction) {
    throw Error(path + ": outer_fraction must be larger than inner_fraction");
  }
  return p;
}

BallProposerParams BallProposerParams::loadDefault() {
  return load(defaultParamDir() + "/ball_proposer.yaml");
}

BallProposer::BallProposer(BallProposerParams params) : params_(params) {}

namespace {

struct ScanRect {
  int x0, y0, x1, y1;  // [x0, x1) × [y0, y1), inside the image
  double boost;
};

struct Candidate {
  float x, y, r, response;
};

// Two integral images over a region of interest in one interleaved buffer (entry 2 k: grey level,
// 2 k + 1: edge strength |right - here| + |below - here|: the ball's print is full of edges, carpet,
// lines and robots' feet have few): sums of any box inside the region; boxes are clamped to it
// (it covers every box the scan asks for, clamped to the image). Each entry is written once, none
// is cleared first.
class Integrals {
 public:
  Integrals(const GrayView& image, int x0, int y0, int x1, int y1)
      : x0_(x0), y0_(y0), w_(x1 - x0), h_(y1 - y0), stride_(2 * (w_ + 1)),
        sums_(new std::uint32_t[static_cast<std::size_t>(stride_) * (h_ + 1)]) {
    std::fill(sums_.get(), sums_.get() + stride_, 0u);
    // One row's grey levels and edge strengths, interleaved like the sums.
    std::vector<std::uint32_t> pix(static_cast<std::size_t>(2 * w_));
    // The last column's right neighbour: the pixel beyond the region, or itself at the image border.
    const int last = x0 + w_ < image.width ? w_ : w_ - 1;
    for (int y = 0; y < h_; ++y) {
      const std::uint8_t* src = image.row(y0 + y) + x0;
      const std::uint8_t* below = image.row(std::min(y0 + y + 1, image.height - 1)) + x0;
      const std::uint32_t* above = sums_.get() + static_cast<std::size_t>(y) * stride_ + 2;
      std::uint32_t* out = sums_.get() + static_cast<std::size_t>(y + 1) * stride_;
      out[0] = out[1] = 0;
      out += 2;
      int x = 0;  // the row's pixels done
#if defined(__SSE2__)
      __m128i carry = _mm_setzero_si128();
#if defined(__AVX512F__)
      // Eight pixels (sixteen entries) at a time where AVX-512 is there, from the image's bytes:
      // their grey levels and edge strengths interleaved in one register, the running sums within
      // the eight in three shifted additions, then the row's running sum (the last pixel's pair,
      // spread over the register) added: the same integers as below.
      {
        const __m512i zero = _mm512_setzero_si512();
        const __m512i interleave = _mm512_set_epi32(15, 7, 14, 6, 13, 5, 12, 4, 11, 3, 10, 2, 9, 1, 8, 0);
        const __m512i last_pair = _mm512_set_epi32(15, 14, 15, 14, 15, 14, 15, 14, 15, 14, 15, 14, 15, 14, 15, 14);
        __m512i carry8 = _mm512_setzero_si512();
        const auto bytes = [](const std::uint8_t* p) {
          return _mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)));
        };
        for (; x + 8 <= last; x += 8) {
          const __m256i here = bytes(src + x), right = bytes(src + x + 1), down = bytes(below + x);
          const __m256i edge = _mm256_add_epi32(_mm256_abs_epi32(_mm256_sub_epi32(right, here)),
                                                _mm256_abs_epi32(_mm256_sub_epi32(down, here)));
          __m512i v = _mm512_permutexvar_epi32(
              interleave, _mm512_inserti64x4(_mm512_castsi256_si512(here), edge, 1));
          v = _mm512_add_epi32(v, _mm512_alignr_epi32(v, zero, 14));
          v = _mm512_add_epi32(v, _mm512_alignr_epi32(v, zero, 12));
          v = _mm512_add_epi32(v, _mm512_alignr_epi32(v, zero, 8));
          v = _mm512_add_epi32(v, carry8);
          _mm512_storeu_si512(out + 2 * x, _mm512_add_epi32(v, _mm512_loadu_si512(above + 2 * x)));
          carry8 = _mm512_permutexvar_epi32(last_pair, v);
        }
        carry = _mm512_castsi512_si128(carry8);
      }
#endif
#endif
      // The rest of the row's grey levels and edge strengths, interleaved like the sums.
      std::uint32_t* px = pix.data();
      for (int i = x; i < last; ++i) {
        px[2 * i] = src[i];
        px[2 * i + 1] =
            static_cast<std::uint32_t>(std::abs(src[i + 1] - src[i]) + std::abs(below[i] - src[i]));
      }
      for (int i = std::max(x, last); i < w_; ++i) {
        px[2 * i] = src[i];
        px[2 * i + 1] = static_cast<std::uint32_t>(std::abs(below[i] - src[i]));
      }
      std::uint32_t run = 0, run_edge = 0;
#if defined(__SSE2__)
      // Two pixels (four entries) at a time: the running sums of both pairs in one register. Four
      // pixels first, their sums within the four independent of the row's running sum, which
      // then waits on one addition per four pixels (not an addition and a shuffle per two).
      for (; x + 4 <= w_; x += 4) {
        __m128i lo = _mm_loadu_si128(reinterpret_cast<const __m128i*>(px + 2 * x));
        __m128i hi = _mm_loadu_si128(reinterpret_cast<const __m128i*>(px + 2 * x + 4));
        lo = _mm_add_epi32(lo, _mm_slli_si128(lo, 8));
        hi = _mm_add_epi32(hi, _mm_slli_si128(hi, 8));
        hi = _mm_add_epi32(hi, _mm_shuffle_epi32(lo, _MM_SHUFFLE(3, 2, 3, 2)));
        const __m128i up_lo = _mm_loadu_si128(reinterpret_cast<const __m128i*>(above + 2 * x));
        const __m128i up_hi = _mm_loadu_si128(reinterpret_cast<const __m128i*>(above + 2 * x + 4));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out + 2 * x),
                         _mm_add_epi32(_mm_add_epi32(lo, carry), up_lo));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out + 2 * x + 4),
                         _mm_add_epi32(_mm_add_epi32(hi, carry), up_hi));
        carry = _mm_add_epi32(carry, _mm_shuffle_epi32(hi, _MM_SHUFFLE(3, 2, 3, 2)));
      }
      for (; x + 2 <= w_; x += 2) {
        __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(px + 2 * x));
        v = _mm_add_epi32(v, _mm_slli_si128(v, 8));
        v = _mm_add_epi32(v, carry);
        carry = _mm_shuffle_epi32(v, _MM_SHUFFLE(3, 2, 3, 2));
        const __m128i up = _mm_loadu_si128(reinterpret_cast<const __m128i*>(above + 2 * x));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(out + 2 * x), _mm_add_epi32(v, up));
      }
      run = static_cast<std::uint32_t>(_mm_cvtsi128_si32(carry));
      run_edge = static_cast<std::uint32_t>(_mm_cvtsi128_si32(_mm_srli_si128(carry, 4)));
#endif
      for (; x < w_; ++x) {
        run += px[2 * x];
        run_edge += px[2 * x + 1];
        out[2 * x] = above[2 * x] + run;
        out[2 * x + 1] = above[2 * x + 1] + run_edge;
      }
    }
  }
  // The row of integral values at image row y (clamped into the region); entry col(x) is the grey
  // level's sum left of x and above y, col(x) + 1 the edge strength's.
  const std::uint32_t* row(int y) const { return sums_.get() + static_cast<std::size_t>(clampY(y) - y0_) * stride_; }
  int col(int x) const { return 2 * (clampX(x) - x0_); }
  // Grey-level integral at image coordinates (x, y), clamped into the region.
  std::uint32_t at(int x, int y) const { return row(y)[col(x)]; }
  int clampX(int x) const { return std::clamp(x, x0_, x0_ + w_); }
  int clampY(int y) const { return std::clamp(y, y0_, y0_ + h_); }

 private:
  int x0_, y0_, w_, h_, stride_;
  std::unique_ptr<std::uint32_t[]> sums_;
};

// The response at (x, y) for expected radius r: a 3×3 grid of cells, the centre cell the inner box.
// Centre mean minus, over the four pairs of opposite surround cells, the brightest pair's darker
// cell (a line or a crossing through the centre lights both cells of a pair; a robot's foot or a
// line beside the ball only one), plus the print term: the spread of the centre's four quadrants.
// The ball's expected radius at `pixel`: the camera model's (on the optical axis) stretched by
// (1 / cos of the angle off the axis) ^ off_axis_exponent: a sphere off the axis projects to an
// ellipse 1 / cos wide across and 1 / cos^2 along the radial direction.
std::optional<double> expectedRadius(const CameraModel& camera, const BallProposerParams& p,
                                     const Eigen::Vector2d& pixel, double ball_radius_m) {
  const auto r = camera.ballRadiusPx(pixel, ball_radius_m);
  if (!r || p.off_axis_exponent == 0) return r;
  const CameraIntrinsics& in = camera.intrinsics();
  const double u = (pixel.x() - in.center_x_px) / in.focal_x_px, v = (pixel.y() - in.center_y_px) / in.focal_y_px;
  return *r * std::pow(1 + u * u + v * v, 0.5 * p.off_axis_exponent);
}

// The filter's sizes at one expected radius (the same along a scan row).
struct Scale {
  int a;               // centre box half-side, pixels
  int bx, by;          // surround box half-width and half-height, pixels
  float texture_gain;  // texture_weight × (r / reference) ^ exponent
  float edge_floor;    // the frame's noise's share of the mean edge strength (texture_noise_factor × noise)
};

// std::lround(t) for 0 <= t < 2^31, inline (the library call costs more than the rest of a scan
// row's set-up): t - trunc(t) is exact.
inline int roundHalfUp(double t) {
  const int i = static_cast<int>(t);
  return i + (t - i >= 0.5);
}

// `widen_px`: the surround's growth in x and y (the camera's exposure smear draws the ball out
// over the left and right or the upper and lower cells of a square one).
Scale scaleAt(double r, const BallProposerParams& p, float edge_floor,
              const Eigen::Vector2i& widen_px) {
  Scale s;
  s.edge_floor = edge_floor;
  s.a = std::max(1, roundHalfUp(p.inner_fraction * r));
  const int b = std::max(s.a + 1, roundHalfUp(p.outer_fraction * r));
  s.bx = b + widen_px.x();
  s.by = b + widen_px.y();
  // In float, as it is used (powf is some three times faster than pow, and this runs per scan row).
  s.texture_gain = static_cast<float>(p.texture_weight) *
                   std::pow(static_cast<float>(r / p.texture_reference_radius_px),
                            static_cast<float>(p.texture_scale_exponent));
  return s;
}

float response(const Integrals& ii, int x, int y, const Scale& sc, const BallProposerParams& p,
               float* on_line = nullptr) {
  const int a = sc.a, bx = sc.bx, by = sc.by;
  const int xs[4] = {ii.clampX(x - bx), ii.clampX(x - a), ii.clampX(x + a), ii.clampX(x + bx)};
  const int ys[4] = {ii.clampY(y - by), ii.clampY(y - a), ii.clampY(y + a), ii.clampY(y + by)};
  const int cols[4] = {ii.col(xs[0]), ii.col(xs[1]), ii.col(xs[2]), ii.col(xs[3])};
  const std::uint32_t* rows[4] = {ii.row(ys[0]), ii.row(ys[1]), ii.row(ys[2]), ii.row(ys[3])};
  std::uint32_t v[4][4];
  for (int j = 0; j < 4; ++j) {
    for (int i = 0; i < 4; ++i) v[j][i] = rows[j][cols[i]];
  }
  float mean[3][3];
  bool valid[3][3];
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) {
      const int area = (xs[i + 1] - xs[i]) * (ys[j + 1] - ys[j]);
      valid[j][i] = area > 0;
      const std::uint32_t s = v[j + 1][i + 1] - v[j][i + 1] - v[j + 1][i] + v[j][i];
      mean[j][i] = area > 0 ? static_cast<float>(s) / static_cast<float>(area) : 0.f;
    }
  }
  if (!valid[1][1]) return -1e9f;
  // Opposite pairs: left-right, top-bottom, and the two diagonals. A cell outside the image does
  // not light its pair.
  const int pairs[4][4] = {{1, 0, 1, 2}, {0, 1, 2, 1}, {0, 0, 2, 2}, {0, 2, 2, 0}};
  float surround = -1e9f, second = -1e9f;
  for (const auto& q : pairs) {
    if (valid[q[0]][q[1]] && valid[q[2]][q[3]]) {
      const float m = std::min(mean[q[0]][q[1]], mean[q[2]][q[3]]);
      if (m > surround) {
        second = surround;
        surround = m;
      } else if (m > second) {
        second = m;
      }
    }
  }
  // On a line: the ball on a line lights one pair like the line itself; against the second
  // brightest pair it still stands out (a crossing lights two pairs).
  if (on_line) *on_line = second > -1e8f ? mean[1][1] - second : -1e9f;
  // The ring's mean (the 8 cells, by area): off the ball's centre part of the ball falls into the
  // ring and raises it, which keeps the peak on the centre.
  const int ring_area = (xs[3] - xs[0]) * (ys[3] - ys[0]) - (xs[2] - xs[1]) * (ys[2] - ys[1]);
  if (ring_area <= 0) return -1e9f;
  const std::uint32_t outer_sum = v[3][3] - v[0][3] - v[3][0] + v[0][0];
  const std::uint32_t inner_sum = v[2][2] - v[1][2] - v[2][1] + v[1][1];
  const float ring = static_cast<float>(outer_sum - inner_sum) / static_cast<float>(ring_area);
  surround = std::max(surround, ring);
  float dog = mean[1][1] - surround;
  if (sc.texture_gain > 0) {
    const std::uint32_t edge_sum = rows[2][cols[2] + 1] - rows[1][cols[2] + 1] - rows[2][cols[1] + 1] + rows[1][cols[1] + 1];
    const int inner_area = (xs[2] - xs[1]) * (ys[2] - ys[1]);
    const float edges = std::max(0.f, static_cast<float>(edge_sum) / static_cast<float>(inner_area) - sc.edge_floor);
    const float texture = sc.texture_gain * edges;
    dog += texture;
    if (on_line) *on_line += texture;
  }
  if (p.print_weight > 0) {
    const int cx = std::clamp(x, xs[1], xs[2]);
    const int cy = std::clamp(y, ys[1], ys[2]);
    const int qx[3] = {xs[1], cx, xs[2]};
    const int qy[3] = {ys[1], cy, ys[2]};
    float lo = 1e9f, hi = -1e9f;
    for (int j = 0; j < 2; ++j) {
      for (int i = 0; i < 2; ++i) {
        const int area = (qx[i + 1] - qx[i]) * (qy[j + 1] - qy[j]);
        if (area <= 0) continue;
        const std::uint32_t s = ii.at(qx[i + 1], qy[j + 1]) - ii.at(qx[i], qy[j + 1]) -
                                ii.at(qx[i + 1], qy[j]) + ii.at(qx[i], qy[j]);
        const float m = static_cast<float>(s) / static_cast<float>(area);
        lo = std::min(lo, m);
        hi = std::max(hi, m);
      }
    }
    if (hi >= lo) dog += static_cast<float>(p.print_weight) * (hi - lo);
  }
  return dog;
}

// response() where no box needs clamping (every box of the row inside the region): the same
// arithmetic, with the row's four integral rows and the cells' areas prepared once per scan row.
struct RowBoxes {
  const std::uint32_t* rows[4];  // integral rows at y - by, y - a, y + a, y + by
  int da, db;                    // 2 a, 2 bx: the boxes' offsets in interleaved entries
  float area[9];                 // the 3x3 cells, row-major
  float ring_area, inner_area;
};

RowBoxes rowBoxes(const Integrals& ii, int y, const Scale& sc) {
  RowBoxes g;
  const int a = sc.a, bx = sc.bx, by = sc.by;
  const int ys[4] = {y - by, y - a, y + a, y + by};
  for (int j = 0; j < 4; ++j) g.rows[j] = ii.row(ys[j]);
  g.da = 2 * a;
  g.db = 2 * bx;
  const int width[3] = {bx - a, 2 * a, bx - a}, height[3] = {by - a, 2 * a, by - a};
  for (int j = 0; j < 3; ++j) {
    for (int i = 0; i < 3; ++i) g.area[3 * j + i] = static_cast<float>(width[i] * height[j]);
  }
  g.ring_area = static_cast<float>((2 * bx) * (2 * by) - (2 * a) * (2 * a));
  g.inner_area = static_cast<float>((2 * a) * (2 * a));
  return g;
}

// response() × boost where no box needs clamping, for n positions of one scan row (their integral
// entries col0, col0 + 2 step, ...; at most kBatch at a time): every position's corner values read
// and its arithmetic done in one loop the compiler vectorises (kStep 1 or 2, the most common steps:
// the reads strided by a stride known at compile time; 0: any step, gathered), without the branches
// of a sequential top-two search (mispredicted on every other position). The same operations on
// the same values as response() (where GCC contracts a multiplication and an addition into one
// fused operation in one of them and not in the other, a response differs in its last bit).
constexpr int kBatch = 32;

template <int kStep>
void responsesInside(const RowBoxes& g, int col0, int step, int n, const Scale& sc, float boost,
                     float* __restrict resp, float* __restrict line) {
  const float texture_gain = sc.texture_gain, edge_floor = sc.edge_floor;
  const int st = kStep > 0 ? 2 * kStep : 2 * step;
  const std::uint32_t* __restrict r0 = g.rows[0];
  const std::uint32_t* __restrict r1 = g.rows[1];
  const std::uint32_t* __restrict r2 = g.rows[2];
  const std::uint32_t* __restrict r3 = g.rows[3];
  const int da = g.da, db = g.db;
  float area[9];
  for (int m = 0; m < 9; ++m) area[m] = g.area[m];
  const float ring_area = g.ring_area, inner_area = g.inner_area;
  for (int k = 0; k < n; ++k) {
    const int c = col0 + st * k;
    const int c0 = c - db, c1 = c - da, c2 = c + da, c3 = c + db;
    const std::uint32_t v[16] = {r0[c0], r0[c1], r0[c2], r0[c3], r1[c0], r1[c1], r1[c2], r1[c3],
                                 r2[c0], r2[c1], r2[c2], r2[c3], r3[c0], r3[c1], r3[c2], r3[c3]};
    float mean[9];
    std::uint32_t sums[9];
    for (int j = 0; j < 3; ++j) {
      for (int i = 0; i < 3; ++i) {
        sums[3 * j + i] = v[4 * (j + 1) + i + 1] - v[4 * j + i + 1] - v[4 * (j + 1) + i] + v[4 * j + i];
      }
    }
    for (int m = 0; m < 9; ++m) mean[m] = static_cast<float>(sums[m]) / area[m];
    // The four opposite pairs' darker cells; the largest and the second largest of them.
    const float m0 = std::min(mean[3], mean[5]), m1 = std::min(mean[1], mean[7]);
    const float m2 = std::min(mean[0], mean[8]), m3 = std::min(mean[2], mean[6]);
    const float hi01 = std::max(m0, m1), lo01 = std::min(m0, m1);
    const float hi23 = std::max(m2, m3), lo23 = std::min(m2, m3);
    const float first = std::max(hi01, hi23);
    const float second = std::max(std::min(hi01, hi23), std::max(lo01, lo23));
    float on_line = mean[4] - second;
    const std::uint32_t outer_sum = v[15] - v[3] - v[12] + v[0];
    const float ring = static_cast<float>(outer_sum - sums[4]) / ring_area;
    const float surround = std::max(first, ring);
    float dog = mean[4] - surround;
    // (with texture_gain 0 the term is +0, which changes no response: no branch in the loop; with
    // edge_floor 0, max(0, x - 0) is x)
    const std::uint32_t edge_sum = r2[c2 + 1] - r1[c2 + 1] - r2[c1 + 1] + r1[c1 + 1];
    const float edges = std::max(0.f, static_cast<float>(edge_sum) / inner_area - edge_floor);
    const float texture = texture_gain * edges;
    dog += texture;
    on_line += texture;
    resp[k] = dog * boost;
    line[k] = on_line;
  }
}

// Circle-centre voting around (x, y): every pixel within the outline's reach whose gradient is
// strong votes for the points r along its gradient, both ways (the ball is brighter than the
// carpet, or darker when the carpet is overexposed), over radii (1 ± radius_tolerance) r; the votes
// are accumulated on a grid of cells about r / 8 wide within centre_search_fraction r of (x, y) and
// smoothed over 3x3 cells. The centre is the best smoothed cell, or, with centre_ridge_fraction in
// (0, 1), the centroid of the cells around it on its ridge (see the parameter). Returns (x, y) when
// no cell gets votes.
struct CentringScratch {
  std::vector<float> votes, smoothed, all_smoothed;
  std::vector<int> stack;
  // The sampled pixels' positions and integer gradients (the strong ones first, in scan order),
  // and the strong ones' strengths and vote cells.
  std::vector<int> sx, sy, sdx, sdy, cells;
  std::vector<float> strength;
  std::vector<float> ux, uy;  // the strong ones' gradient directions
};

// static_cast<int>(std::floor(t)) for |t| < 2^31, in operations the compiler vectorises (it does
// not vectorise std::floor here).
inline int floorToInt(float t) {
  const int i = static_cast<int>(t);  // towards zero
  return i - (t < static_cast<float>(i));
}

// The grid cell (with its border) of each strong pixel's vote at signed distance sign_rr along its
// gradient, or `trash` when the vote falls outside the grid. In floats (twice the lanes of
// doubles): a vote within some 1e-4 px of a cell's border can fall into its neighbour (on the
// 1,990 proposals of the seven scenes checked with BP_EXACT it never did).
void voteCells(const int* __restrict sx, const int* __restrict sy, const float* __restrict ux,
               const float* __restrict uy, int m, double sign_rr, double x, double y, int cell,
               int half, int n, int w, int trash, int* __restrict cv) {
  const float rr = static_cast<float>(sign_rr), inv_cell = 1.f / static_cast<float>(cell);
  const float ox = static_cast<float>(0.5 - x), oy = static_cast<float>(0.5 - y);
  for (int k = 0; k < m; ++k) {
    // (a multiplication by 1 changes nothing)
    const float cx = (static_cast<float>(sx[k]) + ox + rr * ux[k]) * inv_cell;
    const float cy = (static_cast<float>(sy[k]) + oy + rr * uy[k]) * inv_cell;
    const int i = floorToInt(cx + 0.5f) + half;
    const int j = floorToInt(cy + 0.5f) + half;
    const bool in = static_cast<unsigned>(i) < static_cast<unsigned>(n) &&
                    static_cast<unsigned>(j) < static_cast<unsigned>(n);
    cv[k] = in ? (j + 1) * w + i + 1 : trash;
  }
}

Eigen::Vector2d centreFromEdges(const GrayView& image, double x, double y, double r, const BallProposerParams& p,
                                CentringScratch& scratch) {
  const double search = p.centre_search_fraction * r;
  if (search < 1) return {x, y};
  const int cell = std::max(1, static_cast<int>(r / 8));
  const int half = static_cast<int>(std::ceil(search / cell));
  const int n = 2 * half + 1;
  // The votes on the grid with a border of one empty cell (so that the 3x3 smoothing needs no
  // bounds: adding a +0 changes no sum), and after it six cells that take the votes falling
  // outside the grid (one per vote of a pixel, so that successive ones do not wait on each other).
  const int w = n + 2;
  const int trash = w * w;
  std::vector<float>& acc = scratch.votes;
  acc.assign(static_cast<std::size_t>(trash) + 6, 0.f);
  const double reach = search + (1 + p.radius_tolerance) * r + 1;
  const int x0 = std::max(1, static_cast<int>(x - reach)), x1 = std::min(image.width - 2, static_cast<int>(x + reach));
  const int y0 = std::max(1, static_cast<int>(y - reach)), y1 = std::min(image.height - 2, static_cast<int>(y + reach));
  const double radii[3] = {(1 - p.radius_tolerance) * r, r, (1 + p.radius_tolerance) * r};
  const float min_grad = static_cast<float>(p.min_gradient);
  // A pixel's gradient (gx, gy) = (dx, dy) / 2 for the integer differences dx, dy, and
  // gx^2 + gy^2 = (dx^2 + dy^2) / 4 exactly (all terms are small multiples of 1/4): the strength
  // test on the integers, without a branch (the strong pixels are some 40 %, unpredictable).
  const float min_d2 = 4 * (min_grad * min_grad);
  const std::size_t most = x1 >= x0 && y1 >= y0
                               ? static_cast<std::size_t>((x1 - x0) / cell + 1) * ((y1 - y0) / cell + 1)
                               : 0;
  if (scratch.sx.size() < most) {
    for (std::vector<int>* v : {&scratch.sx, &scratch.sy, &scratch.sdx, &scratch.sdy}) v->resize(most);
    scratch.strength.resize(most);
    scratch.ux.resize(most);
    scratch.uy.resize(most);
    scratch.cells.resize(6 * most);
  }
  int* sx = scratch.sx.data();
  int* sy = scratch.sy.data();
  int* sdx = scratch.sdx.data();
  int* sdy = scratch.sdy.data();
  int m = 0;  // strong pixels so far
  for (int py = y0; py <= y1; py += cell) {
    const std::uint8_t* up = image.row(py - 1);
    const std::uint8_t* row = image.row(py);
    const std::uint8_t* down = image.row(py + 1);
    for (int px = x0; px <= x1; px += cell) {
      const int dx = row[px + 1] - row[px - 1], dy = down[px] - up[px];
      sx[m] = px;
      sy[m] = py;
      sdx[m] = dx;
      sdy[m] = dy;
      m += !(static_cast<float>(dx * dx + dy * dy) < min_d2);
    }
  }
  // Each strong pixel votes for the points r along its gradient, both ways, at the three radii:
  // the cells first (no branch), then the votes added in the order of the pixels, radii and signs
  // (so every cell's sum is the same float whatever the vectorisation).
  // (Loops over the pixels with one kind of work each: the compiler vectorises them.)
  float* strength = scratch.strength.data();
  float* ux = scratch.ux.data();
  float* uy = scratch.uy.data();
  int* cells = scratch.cells.data();  // vote v of pixel k: cells[v * m + k]
  for (int k = 0; k < m; ++k) {
    const float gx = 0.5f * static_cast<float>(sdx[k]);
    const float gy = 0.5f * static_cast<float>(sdy[k]);
    const float g = std::sqrt(gx * gx + gy * gy);
    strength[k] = g;
    ux[k] = gx / g;
    uy[k] = gy / g;
  }
  for (int v = 0; v < 6; ++v) {
    const double sign_rr = (v % 2 == 0 ? 1.0 : -1.0) * radii[v / 2];
    int* cv = cells + static_cast<std::size_t>(v) * m;
    voteCells(sx, sy, ux, uy, m, sign_rr, x, y, cell, half, n, w, trash + v, cv);
  }
  for (int k = 0; k < m; ++k) {
    const float g = strength[k];
    for (int v = 0; v < 6; ++v) {
      acc[static_cast<std::size_t>(cells[static_cast<std::size_t>(v) * m + k])] += g;
    }
  }
  // (not for a ball the image border cuts: its visible arc alone votes, and the centroid of the
  // cells drifts into the image)
  const bool ridge = p.centre_ridge_fraction > 0 && p.centre_ridge_fraction < 1 && r >= p.centre_ridge_min_radius_px &&
                     x - r >= 0 && y - r >= 0 && x + r <= image.width && y + r <= image.height;
  // The 3x3 sums of every cell, in the order the cells are visited (rows, then columns).
  std::vector<float>& all = scratch.all_smoothed;
  all.resize(static_cast<std::size_t>(n) * n);
  for (int j = 0; j < n; ++j) {
    const float* a0 = acc.data() + static_cast<std::size_t>(j) * w;
    const float* a1 = a0 + w;
    const float* a2 = a1 + w;
    float* out = all.data() + static_cast<std::size_t>(j) * n;
    for (int i = 0; i < n; ++i) {
      float v = 0;
      v += a0[i];
      v += a0[i + 1];
      v += a0[i + 2];
      v += a1[i];
      v += a1[i + 1];
      v += a1[i + 2];
      v += a2[i];
      v += a2[i + 1];
      v += a2[i + 2];
      out[i] = v;
    }
  }
  std::vector<float>& sm = scratch.smoothed;
  if (ridge) sm.assign(static_cast<std::size_t>(n) * n, 0.f);
  float best = 0;
  int bi = half, bj = half;
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < n; ++i) {
      const double di = (i - half) * cell, dj = (j - half) * cell;
      if (di * di + dj * dj > search * search) continue;
      const float v = all[static_cast<std::size_t>(j) * n + i];
      if (ridge) sm[static_cast<std::size_t>(j) * n + i] = v;
      if (v > best) best = v, bi = i, bj = j;
    }
  }
  const Eigen::Vector2d best_cell(x + (bi - half) * cell, y + (bj - half) * cell);
  if (!ridge || best <= 0) return best_cell;
  // The ridge: the cells 8-connected to the best one with at least the threshold (cells outside
  // the search disc are 0, so it stays inside); each is marked by setting it below 0 once taken.
  const float threshold = static_cast<float>(p.centre_ridge_fraction) * best;
  std::vector<int>& stack = scratch.stack;
  stack.clear();
  stack.push_back(bj * n + bi);
  double sw = 0, si = 0, sj = 0;
  float& first = sm[static_cast<std::size_t>(bj) * n + bi];
  first = -first - 1;  // taken (a taken cell's value v is stored as -v - 1 < 0)
  while (!stack.empty()) {
    const int k = stack.back();
    stack.pop_back();
    const int i = k % n, j = k / n;
    const double w = -sm[static_cast<std::size_t>(k)] - 1 - threshold;
    sw += w;
    si += w * i;
    sj += w * j;
    for (int b = std::max(0, j - 1); b <= std::min(n - 1, j + 1); ++b) {
      for (int a = std::max(0, i - 1); a <= std::min(n - 1, i + 1); ++a) {
        float& v = sm[static_cast<std::size_t>(b) * n + a];
        if (v < threshold) continue;  // below the threshold, or taken already
        v = -v - 1;
        stack.push_back(b * n + a);
      }
    }
  }
  if (sw <= 0) return best_cell;
  return {x + (si / sw - half) * cell, y + (sj / sw - half) * cell};
}

// Windows (of the high-contrast grid) whose grey-level standard deviation over every 2nd row is at
// least `min_std`, looked at (centre pixel), grown by one window: row-major, 1 where marked.
std::vector<std::uint8_t> dimWindows(const GrayView& image, const IgnoreMask& ignore,
                                     const ContrastRegions& regions, double min_std) {
  const int s = regions.window_px, cols = regions.columns, rows = regions.rows;
  std::vector<std::uint8_t> seeds(static_cast<std::size_t>(cols) * rows, 0);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      if (!ignore.looked(c * s + s / 2, r * s + s / 2)) continue;
      std::uint32_t sum = 0, sum2 = 0, n = 0;
#if defined(__SSE2__)
      // Sixteen pixels at a time (the compiler's vector loop takes 32): sums of bytes and of their
      // squares in integer lanes, the same integers.
      __m128i vsum = _mm_setzero_si128(), vsum2 = _mm_setzero_si128();
      const __m128i zero = _mm_setzero_si128();
      const int s16 = s / 16 * 16;
#else
      const int s16 = 0;
#endif
      for (int y = r * s; y < (r + 1) * s; y += 2) {
        const std::uint8_t* row = image.row(y) + c * s;
#if defined(__SSE2__)
        for (int x = 0; x < s16; x += 16) {
          const __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x));
          vsum = _mm_add_epi64(vsum, _mm_sad_epu8(v, zero));
          const __m128i lo = _mm_unpacklo_epi8(v, zero), hi = _mm_unpackhi_epi8(v, zero);
          vsum2 =
              _mm_add_epi32(vsum2, _mm_add_epi32(_mm_madd_epi16(lo, lo), _mm_madd_epi16(hi, hi)));
        }
#endif
        for (int x = s16; x < s; ++x) {
          sum += row[x];
          sum2 += static_cast<std::uint32_t>(row[x]) * row[x];
        }
        n += static_cast<std::uint32_t>(s);
      }
#if defined(__SSE2__)
      sum += static_cast<std::uint32_t>(_mm_cvtsi128_si32(vsum)) +
             static_cast<std::uint32_t>(_mm_cvtsi128_si32(_mm_srli_si128(vsum, 8)));
      vsum2 = _mm_add_epi32(vsum2, _mm_srli_si128(vsum2, 8));
      vsum2 = _mm_add_epi32(vsum2, _mm_srli_si128(vsum2, 4));
      sum2 += static_cast<std::uint32_t>(_mm_cvtsi128_si32(vsum2));
#endif
      const double mean = double(sum) / n;
      const double var = double(sum2) / n - mean * mean;
      if (var >= min_std * min_std) seeds[static_cast<std::size_t>(r) * cols + c] = 1;
    }
  }
  std::vector<std::uint8_t> out(seeds.size(), 0);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      if (!seeds[static_cast<std::size_t>(r) * cols + c]) continue;
      for (int j = std::max(0, r - 1); j <= std::min(rows - 1, r + 1); ++j) {
        for (int i = std::max(0, c - 1); i <= std::min(cols - 1, c + 1); ++i) out[static_cast<std::size_t>(j) * cols + i] = 1;
      }
    }
  }
  return out;
}

}  // namespace

std::vector<BallProposal> BallProposer::run(const GrayView& image, const CameraModel& camera,
                                            const IgnoreMask& ignore,
                                            const ContrastRegions& regions,
                                            const std::vector<RobotPercept>* robots,
                                            std::optional<double> pixel_noise_gray,
                                            std::optional<double> light_gray) const {
  const BallProposerParams& p = params_;
  if (image.empty()) throw Error("ball proposals: empty image");
  if (ignore.width != image.width || ignore.height != image.height) {
    throw Error("ball proposals: ignore mask does not match the image size");
  }
  if (regions.columns * regions.window_px > image.width ||
      regions.rows * regions.window_px > image.height ||
      regions.mask.size() != static_cast<std::size_t>(regions.columns) * regions.rows) {
    throw Error("ball proposals: high-contrast windows do not match the image size");
  }
  // Thresholds that follow the frame's light (the absolute ones hold in a bright frame).
  double min_response = p.min_response;
  std::vector<std::uint8_t> dim;
  if (p.light_response_fraction > 0 || p.light_contrast_fraction > 0) {
    const double light = light_gray ? *light_gray : frameLightGray(image, ignore);
    if (p.light_response_fraction > 0) min_response = std::min(min_response, p.light_response_fraction * light);
    const double min_std = p.light_contrast_fraction * light;
    if (p.light_contrast_fraction > 0 && min_std < p.light_max_window_contrast) {
      dim = dimWindows(image, ignore, regions, min_std);
    }
  }
  // The frame's pixel noise beyond the level the responses were tuned at (in quadrature: independent
  // noises' variances add): its share of the texture term's edges, and the responses' margin below.
  double noise = 0;
  if (p.texture_noise_factor > 0 || p.response_noise_factor > 0) {
    const double sigma = pixel_noise_gray ? *pixel_noise_gray : pixelNoiseGray(image, ignore);
    noise = std::sqrt(std::max(0.0, sigma * sigma - p.noise_free_gray * p.noise_free_gray));
  }
  const float edge_floor = static_cast<float>(p.texture_noise_factor * noise);
  std::vector<ScanRect> rects;
  rects.reserve(regions.mask.size() + (robots != nullptr ? robots->size() : 0));
  const int s = regions.window_px;
  for (int r = 0; r < regions.rows; ++r) {
    for (int c = 0; c < regions.columns; ++c) {
      const bool extra = !dim.empty() && dim[static_cast<std::size_t>(r) * regions.columns + c];
      if (regions.marked(c, r) || extra) rects.push_back({c * s, r * s, (c + 1) * s, (r + 1) * s, 1.0});
    }
  }
  if (robots != nullptr) {
    for (const RobotPercept& robot : *robots) {
      const auto rad = expectedRadius(camera, p, robot.feet_px, p.ball_radius_m);
      if (!rad) continue;
      const double half = p.feet_region_diameters * 2 * *rad / 2;
      const int x0 = std::max(0, static_cast<int>(std::floor(robot.feet_px.x() - half)));
      const int x1 = std::min(image.width, static_cast<int>(std::ceil(robot.feet_px.x() + half)));
      const int y0 = std::max(0, static_cast<int>(std::floor(robot.feet_px.y() - half)));
      const int y1 = std::min(image.height, static_cast<int>(std::ceil(robot.feet_px.y() + half)));
      if (x1 > x0 && y1 > y0) rects.push_back({x0, y0, x1, y1, p.feet_boost});
    }
  }
  if (rects.empty()) return {};

  // The camera's own turn over the exposure draws a ball out by its smear: the part beyond the
  // ball's disc, up to half the smear each way, falls into the surround's cells along it and lights
  // them like a line through the ball. The surround widens by smear_surround_fraction of half the
  // smear, in x and y apart; the centre box stays (the smear's middle keeps the ball's full grey).
  const Eigen::Vector2d widen_px =
      p.smear_surround_fraction * camera.exposureSmearPx().cwiseAbs() / 2;
  const Eigen::Vector2i widen = widen_px.array().round().cast<int>();
  // Expected radius at the top and bottom of every rectangle (interpolated in between).
  struct RectRadius {
    std::optional<double> top, bottom;
  };
  std::vector<RectRadius> radii(rects.size());
  int rx0 = image.width, ry0 = image.height, rx1 = 0, ry1 = 0;
  for (std::size_t k = 0; k < rects.size(); ++k) {
    const ScanRect& rc = rects[k];
    const double cx = (rc.x0 + rc.x1) / 2.0;
    radii[k].top = expectedRadius(camera, p, {cx, rc.y0 + 0.5}, p.ball_radius_m);
    radii[k].bottom = expectedRadius(camera, p, {cx, rc.y1 - 0.5}, p.ball_radius_m);
    const double rmax = std::min(p.max_radius_px, std::max({p.min_radius_px, radii[k].top.value_or(0),
                                                            radii[k].bottom.value_or(0)}));
    const int margin = static_cast<int>(std::ceil(p.outer_fraction * rmax)) + widen.maxCoeff() + 2;
    rx0 = std::min(rx0, rc.x0 - margin);
    ry0 = std::min(ry0, rc.y0 - margin);
    rx1 = std::max(rx1, rc.x1 + margin);
    ry1 = std::max(ry1, rc.y1 + margin);
  }
  rx0 = std::max(rx0, 0);
  ry0 = std::max(ry0, 0);
  rx1 = std::min(rx1, image.width);
  ry1 = std::min(ry1, image.height);
  const Integrals ii(image, rx0, ry0, rx1, ry1);

  std::vector<Candidate> candidates;
  std::vector<Candidate> line_candidates;
  std::vector<Candidate> best;
  candidates.reserve(rects.size() * static_cast<std::size_t>(p.per_window_count));
  line_candidates.reserve(rects.size());
  const int keep = p.per_window_count;
  for (std::size_t k = 0; k < rects.size(); ++k) {
    const ScanRect& rc = rects[k];
    best.clear();
    Candidate best_line{0, 0, 0, -1e9f};
    const double cx = (rc.x0 + rc.x1) / 2.0;
    int y = rc.y0;
    while (y < rc.y1) {
      std::optional<double> rad;
      if (radii[k].top && radii[k].bottom) {
        const double t = rc.y1 - 1 > rc.y0 ? (y - rc.y0) / double(rc.y1 - 1 - rc.y0) : 0.0;
        rad = *radii[k].top + t * (*radii[k].bottom - *radii[k].top);
      } else {
        rad = expectedRadius(camera, p, {cx, y + 0.5}, p.ball_radius_m);
      }
      if (!rad || *rad > p.max_radius_px || *rad < p.min_radius_px) {
        ++y;
        continue;
      }
      const double r = *rad;
      const int step = std::max(1, static_cast<int>(p.step_fraction * r));
      const Scale scale = scaleAt(r, p, edge_floor, widen);
      // The first position half a step in; a step wider than the rectangle (a 16-px window and
      // an expected radius of 66 px or more) would leave it out: one evaluation at its middle
      // instead, so the grid of the largest radii is the windows' grid.
      const bool coarse = rc.x0 + (step - 1) / 2 >= rc.x1;
      const int x_start = coarse ? (rc.x0 + rc.x1) / 2 : rc.x0 + (step - 1) / 2;
      const int yy = coarse && y == rc.y0 ? (rc.y0 + rc.y1) / 2
                                          : std::min(y + (step - 1) / 2, rc.y1 - 1);
      const float boost = static_cast<float>(rc.boost);
      // The centre box's mean carries the frame's noise over its (2 a)^2 pixels: responses count
      // net of response_noise_factor such deviations (0 without noise: x - 0 is x).
      const float margin = static_cast<float>(p.response_noise_factor * noise / (2 * scale.a));
      const auto consider_line = [&](int x, float line_resp) {
        line_resp -= margin;
        if (p.line_count > 0 && line_resp > best_line.response) {
          best_line = {x + 0.5f, yy + 0.5f, static_cast<float>(r), line_resp};
        }
      };
      const auto consider_ball = [&](int x, float resp) {
        resp -= margin;
        if (resp < min_response) return;
        const Candidate cand{x + 0.5f, yy + 0.5f, static_cast<float>(r), resp};
        if (static_cast<int>(best.size()) < keep) {
          best.push_back(cand);
        } else {
          auto weakest = std::min_element(best.begin(), best.end(), [](const Candidate& l, const Candidate& m) {
            return l.response < m.response;
          });
          if (cand.response > weakest->response) *weakest = cand;
        }
      };
      const auto consider = [&](int x, float resp, float line_resp) {
        consider_line(x, line_resp);
        consider_ball(x, resp);
      };
      // The positions k of the row (x = x_start + k step) whose boxes need no clamping, [fast0,
      // fast1), take the fast path (the print term needs the general one); the others, at the
      // region's border, response().
      const int count = (rc.x1 - x_start + step - 1) / step;
      int fast0 = count, fast1 = count;
      if (p.print_weight <= 0 && yy - scale.by >= ry0 && yy + scale.by <= ry1) {
        const int lo = rx0 + scale.bx - x_start, hi = rx1 - scale.bx - x_start;  // x - x_start
        fast0 = lo <= 0 ? 0 : std::min(count, (lo + step - 1) / step);
        fast1 = hi < 0 ? fast0 : std::clamp(hi / step + 1, fast0, count);
      }
      const auto general = [&](int k0, int k1) {
        for (int k = k0; k < k1; ++k) {
          const int x = x_start + k * step;
          if (!ignore.looked(x, yy)) continue;
          float line_resp = 0;
          const float resp = response(ii, x, yy, scale, p, &line_resp) * boost;
          consider(x, resp, line_resp);
        }
      };
      general(0, fast0);
      if (fast1 > fast0) {
        const RowBoxes boxes = rowBoxes(ii, yy, scale);
        float resps[kBatch], lines[kBatch];
        for (int k0 = fast0; k0 < fast1; k0 += kBatch) {
          const int n = std::min(kBatch, fast1 - k0);
          const int x0 = x_start + k0 * step;
          const int col0 = ii.col(x0);
          if (step == 1) {
            responsesInside<1>(boxes, col0, step, n, scale, boost, resps, lines);
          } else if (step == 2) {
            responsesInside<2>(boxes, col0, step, n, scale, boost, resps, lines);
          } else {
            responsesInside<0>(boxes, col0, step, n, scale, boost, resps, lines);
          }
          if (keep == 1) {
            // One candidate a window: of each run of positions only the first of its strongest
            // responses and the first of its strongest line responses can become it (an equal one
            // later does not replace it), so they alone are considered, in the order of the runs.
            int ball_k = -1, line_k = -1;
            float ball_max = 0, line_max = 0;
            for (int k = 0; k < n; ++k) {
              if (!ignore.looked(x0 + k * step, yy)) continue;
              const float b = resps[k] - margin, l = lines[k] - margin;
              if (ball_k < 0 || b > ball_max) ball_max = b, ball_k = k;
              if (line_k < 0 || l > line_max) line_max = l, line_k = k;
            }
            if (line_k >= 0) consider_line(x0 + line_k * step, lines[line_k]);
            if (ball_k >= 0) consider_ball(x0 + ball_k * step, resps[ball_k]);
          } else {
            for (int k = 0; k < n; ++k) {
              const int x = x0 + k * step;
              if (ignore.looked(x, yy)) consider(x, resps[k], lines[k]);
            }
          }
        }
      }
      general(fast1, count);
      y += step;
    }
    candidates.insert(candidates.end(), best.begin(), best.end());
    if (best_line.response >= p.line_min_response) line_candidates.push_back(best_line);
  }
  // Robots' bodies above their feet regions (white, textured parts) cannot hold a visible ball
  // lying on the ground in front of them: their candidates count robot_body_factor of their response.
  // The body is the middle of the box across: in the box's margins beside it a ball behind the
  // robot shows in full.
  if (robots != nullptr && p.robot_body_factor < 1) {
    for (const RobotPercept& robot : *robots) {
      const auto rad = expectedRadius(camera, p, robot.feet_px, p.ball_radius_m);
      if (!rad) continue;
      const double top_of_feet = robot.feet_px.y() - p.feet_region_diameters * *rad;
      const double centre_x = (robot.box.x0 + robot.box.x1) / 2;
      const double half_body = p.robot_body_width_fraction * robot.box.width() / 2;
      for (std::vector<Candidate>* list : {&candidates, &line_candidates}) {
        for (Candidate& c : *list) {
          if (std::abs(c.x - centre_x) <= half_body && c.y >= robot.box.y0 && c.y < top_of_feet) {
            c.response *= static_cast<float>(p.robot_body_factor);
          }
        }
      }
    }
  }
  const auto by_response = [](const Candidate& l, const Candidate& m) {
    if (l.response != m.response) return l.response > m.response;
    if (l.y != m.y) return l.y < m.y;
    return l.x < m.x;
  };
  std::stable_sort(candidates.begin(), candidates.end(), by_response);
  std::stable_sort(line_candidates.begin(), line_candidates.end(), by_response);
  std::vector<BallProposal> out;
  std::vector<Eigen::Vector2d> raw_centres;  // the scan's positions of the proposals in `out`
  CentringScratch scratch;                   // centreFromEdges' scratch
  const auto near = [&](double x, double y, double r) {
    for (std::size_t k = 0; k < out.size(); ++k) {
      const double d = p.nms_fraction * std::max<double>(r, out[k].radius_px);
      for (const Eigen::Vector2d& o : {out[k].centre_px, raw_centres[k]}) {
        const double dx = x - o.x(), dy = y - o.y();
        if (dx * dx + dy * dy < d * d) return true;
      }
    }
    return false;
  };
  const auto take = [&](const std::vector<Candidate>& list, int limit) {
    for (const Candidate& c : list) {
      if (static_cast<int>(out.size()) >= limit) break;
      if (near(c.x, c.y, c.r)) continue;
      // The centre: where the outline's gradients point to at the expected radius (robust to the
      // shading of the ball's lower half and to its shadow, which pull the DoG's peak upwards).
      const Eigen::Vector2d centre = centreFromEdges(image, c.x, c.y, c.r, p, scratch);
      if (near(centre.x(), centre.y(), c.r)) continue;  // the same ball as an earlier one
      BallProposal prop;
      prop.centre_px = centre;
      prop.radius_px = c.r;
      prop.response = c.response;
      raw_centres.emplace_back(c.x, c.y);
      out.push_back(prop);
    }
  };
  take(candidates, p.max_count - p.line_count);
  take(line_candidates, static_cast<int>(out.size()) + p.line_count);
  take(candidates, p.max_count);  // unused line slots go back to the others
  // Strongest first (refinement can reorder; on-line responses share the scale).
  std::stable_sort(out.begin(), out.end(),
                   [](const BallProposal& l, const BallProposal& m) { return l.response > m.response; });
  return out;
}

}  // namespace colorfree
