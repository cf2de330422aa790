#include "colorfree/perception/robot_orientation.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numbers>

#include "colorfree/perception/cnn/patch.h"
#include "colorfree/perception/cnn/shipped_nets.h"
#include "colorfree/perception/error.h"
#include "colorfree/perception/param_file.h"

namespace colorfree {

RobotOrientationParams RobotOrientationParams::load(const std::string& path) {
  ParamFile f(path);
  RobotOrientationParams p;
  p.feet_region_above_fraction = f.getInRange("feet_region_above_fraction", 0, 1);
  p.feet_region_below_fraction = f.getInRange("feet_region_below_fraction", 0, 1);
  p.scan_step_px = static_cast<int>(f.getInRange("scan_step_px", 1, 16));
  p.median_width_px = static_cast<int>(f.getInRange("median_width_px", 1, 9));
  p.variance_radius_px = static_cast<int>(f.getInRange("variance_radius_px", 1, kMaxEdgeMaskRadiusPx));
  p.cns_sigma_gray = f.getInRange("cns_sigma_gray", 0.01, 255);
  p.cns_threshold = f.getInRange("cns_threshold", 0, 2);
  p.silhouette_min_rows = static_cast<int>(f.getInRange("silhouette_min_rows", 1, 8));
  p.silhouette_neighbour_rows_px = static_cast<int>(f.getInRange("silhouette_neighbour_rows_px", 0, 64));
  p.silhouette_min_chain_px = static_cast<int>(f.getInRange("silhouette_min_chain_px", 1, 640));
  p.silhouette_min_chain_fraction = f.getInRange("silhouette_min_chain_fraction", 0, 1);
  p.silhouette_min_above_carpet_ratio = f.getInRange("silhouette_min_above_carpet_ratio", 0, 4);
  p.silhouette_above_rows_px = static_cast<int>(f.getInRange("silhouette_above_rows_px", 1, 16));
  p.dark_panel_max_gray_ratio = f.getInRange("dark_panel_max_gray_ratio", 0, 1);
  p.dark_panel_min_height_fraction = f.getInRange("dark_panel_min_height_fraction", 0, 1);
  p.dark_panel_max_height_fraction = f.getInRange("dark_panel_max_height_fraction", 0, 1);
  p.dark_panel_min_chain_share = f.getInRange("dark_panel_min_chain_share", 0, 1);
  p.dark_panel_below_feet_fraction = f.getInRange("dark_panel_below_feet_fraction", 0, 1);
  p.dark_panel_edge_min_rows = static_cast<int>(f.getInRange("dark_panel_edge_min_rows", 1, 8));
  if (p.dark_panel_edge_min_rows > p.silhouette_min_rows) {
    throw Error(path + ": dark_panel_edge_min_rows must not exceed silhouette_min_rows");
  }
  p.vote_distance_m = f.getInRange("vote_distance_m", 0.0001, 1);
  p.vote_margin_m = f.getInRange("vote_margin_m", 0, 2);
  p.second_line_min_length_m = f.getInRange("second_line_min_length_m", 0, 2);
  p.second_line_max_length_m = f.getInRange("second_line_max_length_m", 0, 2);
  p.second_line_max_cos = f.getInRange("second_line_max_cos", 0, 1);
  p.second_line_max_refined_cos = f.getInRange("second_line_max_refined_cos", 0, 1);
  p.min_line_votes = f.getInRange("min_line_votes", 0, 1000);
  p.line_max_voter_gap_m = f.getInRange("line_max_voter_gap_m", 0, 2);
  p.line_max_feet_distance_m = f.getInRange("line_max_feet_distance_m", 0, 10);
  p.field_line_margin_px = f.getInRange("field_line_margin_px", 0, 50);
  p.field_line_min_length_m = f.getInRange("field_line_min_length_m", 0, 20);
  p.field_line_min_angle_deg = f.getInRange("field_line_min_angle_deg", 0, 90);
  p.field_line_sole_max_gray_ratio = f.getInRange("field_line_sole_max_gray_ratio", 0, 1);
  p.field_line_sole_min_box_height_px = f.getInRange("field_line_sole_min_box_height_px", 0, 4000);
  p.field_line_sole_max_height_fraction = f.getInRange("field_line_sole_max_height_fraction", 0, 1);
  p.region_margin_fraction = f.getInRange("region_margin_fraction", 0, 2);
  p.region_above_fraction = f.getInRange("region_above_fraction", 0, 2);
  p.region_below_fraction = f.getInRange("region_below_fraction", 0, 2);
  p.min_usable_confidence = f.getInRange("min_usable_confidence", 0, 1);
  p.min_side_confidence = f.getInRange("min_side_confidence", 0, 1);
  p.min_side_facing_share = f.getInRange("min_side_facing_share", 0.5, 1);
  p.ori_net_mirrored_look = f.getInRange("ori_net_mirrored_look", 0, 1) > 0;
  p.keep_most_confident_of_a_class = f.getInRange("keep_most_confident_of_a_class", 0, 1) > 0;
  p.track_max_distance_m = f.getInRange("track_max_distance_m", 0, 10);
  p.track_expiry_s = f.getInRange("track_expiry_s", 0, 60);
  p.filter_buffer_size = static_cast<int>(f.getInRange("filter_buffer_size", 1, 101));
  f.finish();
  return p;
}

RobotOrientationParams RobotOrientationParams::loadDefault() {
  return load(defaultParamDir() + "/robot_orientation.yaml");
}

namespace {
CnsRegion clampRegion(const GrayView& image, int x0, int y0, int width, int height) {
  CnsRegion r;
  r.x0 = std::clamp(x0, 0, image.width);
  r.y0 = std::clamp(y0, 0, image.height);
  r.width = std::clamp(width, 0, image.width - r.x0);
  r.height = std::clamp(height, 0, image.height - r.y0);
  return r;
}

// The region grown by `border` px on every side, copied with reads clamped to the image (pw ×
// ph values, row by row), so the loops over it need no checks.
template <typename T>
std::vector<T> paddedRegion(const GrayView& image, const CnsRegion& r, int border) {
  const int pw = r.width + 2 * border, ph = r.height + 2 * border;
  std::vector<T> pix(static_cast<std::size_t>(pw) * ph);
  std::vector<int> col(pw);
  for (int i = 0; i < pw; ++i) col[i] = std::clamp(r.x0 - border + i, 0, image.width - 1);
  // Columns i_lo .. i_hi-1 need no clamping: a plain copy.
  const int i_lo = std::min(pw, std::max(0, border - r.x0));
  const int i_hi = std::max(i_lo, std::min(pw, image.width - r.x0 + border));
  for (int j = 0; j < ph; ++j) {
    const std::uint8_t* src = image.row(std::clamp(r.y0 - border + j, 0, image.height - 1));
    T* dst = &pix[static_cast<std::size_t>(j) * pw];
    for (int i = 0; i < i_lo; ++i) dst[i] = src[col[i]];
    const std::uint8_t* run = src + (r.x0 - border);
    for (int i = i_lo; i < i_hi; ++i) dst[i] = run[i];
    for (int i = i_hi; i < pw; ++i) dst[i] = src[col[i]];
  }
  return pix;
}

// The CNS's rows of a (non-empty) region: calls row(y, up, mid, down, vs, vs2) for each row y
// (relative to the region), with up / mid / down the image rows y-1, y, y+1 from the region's
// column 0 (reads clamped to the image, valid from column -1 to width) and vs, vs2 the sums of the
// values and their squares over the variance window's 2·radius+1 rows per column (valid from
// column -radius to width-1+radius).
template <typename RowFn>
void forEachCnsRow(const GrayView& image, const CnsRegion& r, int radius, RowFn&& row_fn) {
  // The region grown by a border (the variance window's radius, at least the Sobel's 1 px).
  const int border = std::max(radius, 1);
  const int pw = r.width + 2 * border;
  const std::vector<std::int32_t> pix = paddedRegion<std::int32_t>(image, r, border);
  // The vertical sums per padded column, slid down row by row.
  std::vector<std::int32_t> vs(pw, 0), vs2(pw, 0);
  for (int j = border - radius; j <= border + radius; ++j) {
    const std::int32_t* row = &pix[static_cast<std::size_t>(j) * pw];
    for (int i = 0; i < pw; ++i) {
      vs[i] += row[i];
      vs2[i] += row[i] * row[i];
    }
  }
  for (int y = 0; y < r.height; ++y) {
    if (y > 0) {
      const std::int32_t* gone = &pix[static_cast<std::size_t>(y - 1 + border - radius) * pw];
      const std::int32_t* come = &pix[static_cast<std::size_t>(y + border + radius) * pw];
      for (int i = 0; i < pw; ++i) {
        vs[i] += come[i] - gone[i];
        vs2[i] += come[i] * come[i] - gone[i] * gone[i];
      }
    }
    const std::int32_t* up = &pix[static_cast<std::size_t>(y + border - 1) * pw + border];
    row_fn(y, up, up + pw, up + 2 * pw, vs.data() + border, vs2.data() + border);
  }
}

// 1 / sqrt(64 · variance + σ²) from a window's sums (n pixels).
struct CnsNormalizer {
  std::int64_t n;
  float inv_n2, sigma2;
  CnsNormalizer(int radius, double sigma)
      : n(static_cast<std::int64_t>(2 * radius + 1) * (2 * radius + 1)),
        inv_n2(1.0f / static_cast<float>(n * n)),
        sigma2(static_cast<float>(sigma * sigma)) {}
  // 64 · variance + σ², the normalizer's square.
  float squared(std::int64_t s, std::int64_t s2) const {
    // n² · variance, exact in integers.
    const std::int64_t var_n2 = std::max<std::int64_t>(0, n * s2 - s * s);
    return 64.0f * static_cast<float>(var_n2) * inv_n2 + sigma2;
  }
  float operator()(std::int64_t s, std::int64_t s2) const { return 1.0f / std::sqrt(squared(s, s2)); }
};

int sobelX(const std::int32_t* up, const std::int32_t* mid, const std::int32_t* down) {
  return (up[1] + 2 * mid[1] + down[1]) - (up[-1] + 2 * mid[-1] + down[-1]);
}
int sobelY(const std::int32_t* up, const std::int32_t* down) {
  return (down[-1] + 2 * down[0] + down[1]) - (up[-1] + 2 * up[0] + up[1]);
}
}  // namespace

CnsImage contrastNormalizedSobel(const GrayView& image, int x0, int y0, int width, int height,
                                 int radius, double sigma) {
  const CnsRegion r = clampRegion(image, x0, y0, width, height);
  CnsImage out;
  static_cast<CnsRegion&>(out) = r;
  out.gx.assign(static_cast<std::size_t>(r.width) * r.height, 0.0f);
  out.gy.assign(out.gx.size(), 0.0f);
  if (r.width == 0 || r.height == 0) return out;
  radius = std::max(radius, 0);
  const CnsNormalizer norm(radius, sigma);
  forEachCnsRow(image, r, radius,
                [&](int y, const std::int32_t* up, const std::int32_t* mid, const std::int32_t* down,
                    const std::int32_t* vs, const std::int32_t* vs2) {
                  float* gx = &out.gx[static_cast<std::size_t>(y) * r.width];
                  float* gy = &out.gy[static_cast<std::size_t>(y) * r.width];
                  // The horizontal sums slide along the row.
                  std::int64_t s = 0, s2 = 0;
                  for (int i = -radius; i < radius; ++i) {
                    s += vs[i];
                    s2 += vs2[i];
                  }
                  for (int x = 0; x < r.width; ++x) {
                    s += vs[x + radius];
                    s2 += vs2[x + radius];
                    const float inv_norm = norm(s, s2);
                    gx[x] = static_cast<float>(sobelX(up + x, mid + x, down + x)) * inv_norm;
                    gy[x] = static_cast<float>(sobelY(up + x, down + x)) * inv_norm;
                    s -= vs[x - radius];
                    s2 -= vs2[x - radius];
                  }
                });
  return out;
}

CnsEdgeMask brightAboveEdgeMask(const GrayView& image, int x0, int y0, int width, int height,
                                int radius, double sigma, double threshold) {
  const CnsRegion r = clampRegion(image, x0, y0, width, height);
  CnsEdgeMask out;
  static_cast<CnsRegion&>(out) = r;
  out.on.assign(static_cast<std::size_t>(r.width) * r.height, 0);
  if (r.width == 0 || r.height == 0) return out;
  radius = std::max(radius, 0);
  if (radius > kMaxEdgeMaskRadiusPx) {
    throw Error("brightAboveEdgeMask: variance radius " + std::to_string(radius) + " px is above " +
                std::to_string(kMaxEdgeMaskRadiusPx) + " (the window's sums must fit 32 bits)");
  }
  const CnsNormalizer norm(radius, sigma);
  const float t = static_cast<float>(threshold);
  // The region grown by a border (the variance window's radius, at least the Sobel's 1 px).
  const int border = std::max(radius, 1);
  const int w = r.width, pw = r.width + 2 * border;
  const std::vector<std::uint8_t> pix = paddedRegion<std::uint8_t>(image, r, border);
  // Each pixel's square once (at most 255², a 16-bit value), for the sums of squares.
  std::vector<std::uint16_t> pix2(pix.size());
  for (std::size_t i = 0; i < pix.size(); ++i)
    pix2[i] = static_cast<std::uint16_t>(pix[i] * pix[i]);
  // The window's sums: per padded row its horizontal sums (values and squares) over the
  // 2·radius+1 columns around each region column, kept for the 2·radius+2 rows last needed;
  // per region column the vertical sums of those, slid down row by row. Exact integers: the same
  // sums in any order.
  const int ring = 2 * radius + 2;
  std::vector<std::int32_t> hs(static_cast<std::size_t>(ring) * w), hs2(hs.size());
  std::vector<std::int32_t> zero(w, 0), s(w, 0), s2(w, 0);
  auto horizontalSums = [&](int j) {  // padded row j into its ring slot
    const std::uint8_t* row = &pix[static_cast<std::size_t>(j) * pw + border - radius];
    const std::uint16_t* row2 = &pix2[static_cast<std::size_t>(j) * pw + border - radius];
    std::int32_t* __restrict h = &hs[static_cast<std::size_t>(j % ring) * w];
    std::int32_t* __restrict h2 = &hs2[static_cast<std::size_t>(j % ring) * w];
    if (radius == 2) {  // the shipped radius, unrolled
      for (int x = 0; x < w; ++x) {
        h[x] = std::int32_t{row[x]} + row[x + 1] + row[x + 2] + row[x + 3] + row[x + 4];
        h2[x] = std::int32_t{row2[x]} + row2[x + 1] + row2[x + 2] + row2[x + 3] + row2[x + 4];
      }
    } else {
      for (int x = 0; x < w; ++x) {
        std::int32_t sum = 0, sum2 = 0;
        for (int i = 0; i <= 2 * radius; ++i) {
          sum += row[x + i];
          sum2 += row2[x + i];
        }
        h[x] = sum;
        h2[x] = sum2;
      }
    }
  };
  for (int j = border - radius; j <= border + radius; ++j) {
    horizontalSums(j);
    const std::int32_t* h = &hs[static_cast<std::size_t>(j % ring) * w];
    const std::int32_t* h2 = &hs2[static_cast<std::size_t>(j % ring) * w];
    for (int x = 0; x < w; ++x) {
      s[x] += h[x];
      s2[x] += h2[x];
    }
  }
  const std::int32_t nn = static_cast<std::int32_t>(norm.n);
  const float inv_n2 = norm.inv_n2, sigma2 = norm.sigma2, t2 = t * t;
  for (int y = 0; y < r.height; ++y) {
    // The rows entering and leaving the window (none on the first row: the sums start there).
    const std::int32_t *come = zero.data(), *come2 = zero.data(), *gone = zero.data(),
                       *gone2 = zero.data();
    if (y > 0) {
      const int j_come = y + border + radius, j_gone = y - 1 + border - radius;
      horizontalSums(j_come);
      come = &hs[static_cast<std::size_t>(j_come % ring) * w];
      come2 = &hs2[static_cast<std::size_t>(j_come % ring) * w];
      gone = &hs[static_cast<std::size_t>(j_gone % ring) * w];
      gone2 = &hs2[static_cast<std::size_t>(j_gone % ring) * w];
    }
    const std::uint8_t* __restrict up =
        &pix[static_cast<std::size_t>(y + border - 1) * pw + border];
    const std::uint8_t* __restrict down = up + 2 * pw;
    std::int32_t* __restrict ps = s.data();
    std::int32_t* __restrict ps2 = s2.data();
    std::uint8_t* __restrict on = &out.on[static_cast<std::size_t>(y) * w];
    std::int32_t any = 0;
    // One loop the compiler vectorises: the sums slid, the Sobel, the decision, the byte.
    for (int x = 0; x < w; ++x) {
      const std::int32_t sum = ps[x] + come[x] - gone[x], sum2 = ps2[x] + come2[x] - gone2[x];
      ps[x] = sum;
      ps2[x] = sum2;
      const std::int32_t g_int =
          (static_cast<std::int32_t>(up[x - 1]) + 2 * up[x] + up[x + 1]) -
          (static_cast<std::int32_t>(down[x - 1]) + 2 * down[x] + down[x + 1]);
      // (-gy) / sqrt(q) > t on the squares (the float q as CnsNormalizer::squared gives it; the
      // squared Sobel is exact in a float) ...
      const std::int32_t var_n2 = std::max(0, nn * sum2 - sum * sum);
      const float q = 64.0f * static_cast<float>(var_n2) * inv_n2 + sigma2;
      const float g = static_cast<float>(std::max(g_int, 0));
      const float g2 = g * g, t2q = t2 * q;
      const auto above = static_cast<std::int32_t>(g2 > t2q * (1 + 1e-5f));
      const auto near = static_cast<std::int32_t>(g2 >= t2q * (1 - 1e-5f));
      const std::int32_t decided =
          static_cast<std::int32_t>(g_int > 0) * (above + 2 * (near - above));  // 1 on, 2 a tie
      any |= decided;
      on[x] = static_cast<std::uint8_t>(decided);
    }
    if ((any & 2) == 0) continue;
    // ... and near a tie (the 2s) as contrastNormalizedSobel computes gy (negated: exact in
    // floating point).
    for (int x = 0; x < w; ++x) {
      if (x % 8 == 0 && x + 8 <= w) {  // eight bytes at a time past the stretches without a tie
        std::uint64_t eight;
        std::memcpy(&eight, on + x, 8);
        eight &= 0x0202020202020202ULL;
        if (eight == 0) {
          x += 7;
          continue;
        }
      }
      if (on[x] != 2) continue;
      const std::int32_t gy = (static_cast<std::int32_t>(down[x - 1]) + 2 * down[x] + down[x + 1]) -
                              (static_cast<std::int32_t>(up[x - 1]) + 2 * up[x] + up[x + 1]);
      on[x] = -(static_cast<float>(gy) * norm(ps[x], ps2[x])) > t;
    }
  }
  return out;
}

RobotOrientationEstimator::RobotOrientationEstimator(RobotOrientationParams params,
                                                     FieldDimensions field,
                                                     cnn::Classifier ori_boost_net,
                                                     cnn::Classifier ori_net)
    : params_(params),
      robot_height_m_(field.robot_height_m),
      line_half_width_m_(field.line_width_m / 2),
      centre_circle_radius_m_(field.centre_circle_diameter_m / 2),
      boost_(std::move(ori_boost_net)),
      ori_(std::move(ori_net)) {
  if (boost_.classes() != 2 || ori_.classes() != 4) {
    throw Error("robot orientation: OriBoostNet must give 2 classes and OriNet 4 (front, back, side facing left, side facing right)");
  }
}

RobotOrientationEstimator RobotOrientationEstimator::loadDefault() {
  const cnn::ShippedNet& b = cnn::kShippedNets[3];
  const cnn::ShippedNet& o = cnn::kShippedNets[4];
  return RobotOrientationEstimator(RobotOrientationParams::loadDefault(),
                                   FieldDimensions::loadDefault(),
                                   cnn::Classifier::load(b.cfgPath(), b.weightsPath()),
                                   cnn::Classifier::load(o.cfgPath(), o.weightsPath()));
}

namespace {
// Least-squares refit of a hull line to the silhouette points that voted for it (the hull's
// vertices are the extreme, noisiest points); the ends are the extreme inliers.
// With max_gap > 0 only the longest contiguous run of those voters (`lineVoters`).
LineHypothesis refineLine(const LineHypothesis& line, const std::vector<Eigen::Vector2d>& points,
                          double vote_distance, double vote_margin, double max_gap) {
  const Eigen::Vector2d u = line.direction();
  const Eigen::Vector2d n(-u.y(), u.x());
  const double len = line.length();
  std::vector<Eigen::Vector2d> in;
  if (max_gap > 0) {
    in = lineVoters(line.a, line.b, points, vote_distance, vote_margin, max_gap);
  } else {
    for (const auto& q : points) {
      const double t = (q - line.a).dot(u);
      if (std::abs((q - line.a).dot(n)) <= vote_distance && t >= -vote_margin &&
          t <= len + vote_margin) {
        in.push_back(q);
      }
    }
  }
  if (in.size() < 3) return line;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& q : in) mean += q;
  mean /= static_cast<double>(in.size());
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  for (const auto& q : in) cov += (q - mean) * (q - mean).transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(cov);
  Eigen::Vector2d d = es.eigenvectors().col(1);
  if (d.dot(u) < 0) d = -d;
  double t0 = 0, t1 = 0;
  for (const auto& q : in) {
    const double t = (q - mean).dot(d);
    t0 = std::min(t0, t);
    t1 = std::max(t1, t);
  }
  LineHypothesis out = line;
  out.a = mean + t0 * d;
  out.b = mean + t1 * d;
  out.votes = static_cast<int>(in.size());
  return out;
}

struct DarkPanel {
  double max_gray;         ///< a panel's pixels are darker than this (the 3-px mean of a row)
  int min_rows, max_rows;  ///< its height
  int max_end_row;         ///< its lower end at most this row (the feet stand on it)
};

// The row below the dark panel whose upper edge is at `row` (the edge's lowest row: the panel
// starts within two rows below it), or `row` when no such panel is there.
int belowDarkPanel(const GrayView& image, int x, int row, const DarkPanel& panel) {
  if (x < 1 || x + 1 >= image.width) return row;
  const auto dark = [&](int y) {
    const std::uint8_t* px = image.row(y) + x;
    return px[-1] + px[0] + px[1] < 3 * panel.max_gray;
  };
  int top = row;
  while (top < image.height && top - row <= 2 && !dark(top)) ++top;
  if (top >= image.height || top - row > 2) return row;
  int end = top;
  while (end < image.height && end - top <= panel.max_rows && dark(end)) ++end;
  const int rows = end - top;
  if (end >= image.height || end > panel.max_end_row || rows < panel.min_rows ||
      rows > panel.max_rows) {
    return row;
  }
  return end;
}

// The detected field lines and centre circle whose lower edge (a bright line above the carpet) may
// pass for the feet's: long lines across the line of sight through the feet region in the image,
// the circle where it passes within the lines generator's reach of the feet, across the line of
// sight there.
class FieldMarkingsAtFeet {
 public:
  FieldMarkingsAtFeet(const RobotOrientationParams& p, const FieldFeatures& field, const CameraModel& camera,
                      const std::optional<Eigen::Vector2d>& feet_ground, int x_left, int x_right, int y_top,
                      int y_bottom, double half_width_m, double circle_radius_m)
      : margin_px_(p.field_line_margin_px), half_width_m_(half_width_m), circle_radius_m_(circle_radius_m) {
    if (margin_px_ <= 0 || !feet_ground) return;
    const Eigen::Vector2d sight = (*feet_ground - camera.position().head<2>()).normalized();
    const double max_cos = std::cos(p.field_line_min_angle_deg * std::numbers::pi / 180);
    for (const LinePercept& l : field.lines) {
      const Eigen::Vector2d d = l.end_in_robot - l.start_in_robot;
      const double length = d.norm();
      if (length < p.field_line_min_length_m) continue;
      const Eigen::Vector2d u = d / length;
      if (std::abs(u.dot(sight)) > max_cos) continue;
      // Through the feet region in the image: its rows over the region's columns.
      const Eigen::Vector2d& pa = l.start_px.x() <= l.end_px.x() ? l.start_px : l.end_px;
      const Eigen::Vector2d& pb = l.start_px.x() <= l.end_px.x() ? l.end_px : l.start_px;
      const double x0 = std::max<double>(pa.x(), x_left), x1 = std::min<double>(pb.x(), x_right);
      if (x0 > x1) continue;
      const auto rowAt = [&](double x) {
        return pb.x() > pa.x() ? pa.y() + (x - pa.x()) * (pb.y() - pa.y()) / (pb.x() - pa.x()) : pa.y();
      };
      if (std::max(rowAt(x0), rowAt(x1)) < y_top || std::min(rowAt(x0), rowAt(x1)) > y_bottom) continue;
      lines_.push_back({l.start_in_robot, u, length});
    }
    if (field.centre_circle) {
      const Eigen::Vector2d radial = *feet_ground - field.centre_circle->centre_in_robot;
      const double r = radial.norm();
      const double reach = p.line_max_feet_distance_m + half_width_m_;
      if (std::abs(r - circle_radius_m_) <= reach && r > 0 &&
          std::abs(Eigen::Vector2d(-radial.y(), radial.x()).dot(sight)) / r <= max_cos) {
        circle_centre_ = field.centre_circle->centre_in_robot;
      }
    }
  }

  // Whether pixel `px`'s ground point lies on one of them: within the line's half width, grown by
  // the margin's pixels on the ground there (a pixel's depth), of its middle (a straight line's
  // extended as far beyond its ends).
  bool covers(const CameraModel& camera, const Eigen::Vector2d& px) const {
    if (lines_.empty() && !circle_centre_) return false;
    const auto g = camera.pixelToGround(px);
    const auto g_above = camera.pixelToGround(px - Eigen::Vector2d(0, 1));
    if (!g || !g_above) return false;
    const double band = half_width_m_ + margin_px_ * (*g - *g_above).norm();
    for (const GroundLine& l : lines_) {
      if (nearSegment(l.a, l.u, l.length, *g, band, band)) return true;
    }
    return circle_centre_ && std::abs((*g - *circle_centre_).norm() - circle_radius_m_) <= band;
  }

 private:
  struct GroundLine {
    Eigen::Vector2d a, u;  ///< a point and the unit direction on the ground
    double length;
  };
  double margin_px_, half_width_m_, circle_radius_m_;
  std::vector<GroundLine> lines_;
  std::optional<Eigen::Vector2d> circle_centre_;
};

}  // namespace

RobotLines RobotOrientationEstimator::findLines(const GrayView& image, const CameraModel& camera,
                                                const RobotPercept& robot,
                                                const FieldFeatures& field) const {
  const RobotOrientationParams& p = params_;
  RobotLines out;
  const double h = robot.box.height();
  const int y_top = static_cast<int>(std::floor(robot.feet_px.y() - p.feet_region_above_fraction * h));
  const int y_bottom = static_cast<int>(std::ceil(robot.feet_px.y() + p.feet_region_below_fraction * h));
  const int x_left = static_cast<int>(std::floor(robot.box.x0));
  const int x_right = static_cast<int>(std::ceil(robot.box.x1));
  const CnsEdgeMask edges = brightAboveEdgeMask(image, x_left, y_top, x_right - x_left,
                                                y_bottom - y_top, p.variance_radius_px,
                                                p.cns_sigma_gray, p.cns_threshold);
  if (edges.width < 3 || edges.height < 3) return out;
  const int half = p.median_width_px / 2;
  // Per scan line, the edges from the bottom up (the lowest row of each run of rows above the
  // threshold; a real edge answers on several rows, noise on one), at most kMaxHits.
  constexpr int kMaxHits = 4;
  struct Hit {
    int column, row;
  };
  std::vector<Hit> hits;
  std::vector<int> first_hit;  // per scan line, its first entry in `hits`
  // The carpet's gray: the median over the columns just beside the feet region on both sides
  // (outside the robot's box, however tight the box; inside its outer columns where the image
  // ends there). An edge with no more than the carpet above it is a cast shadow's upper edge or
  // the carpet's texture, not the feet (white, or lit gray, above the carpet or the dark panels).
  double min_above_gray = 0, carpet_gray = 0;
  if (p.silhouette_min_above_carpet_ratio > 0 || p.dark_panel_max_gray_ratio > 0 ||
      p.field_line_sole_max_gray_ratio > 0) {
    // The median by a histogram of the gray levels: the same value as sorting them. Counted in
    // four histograms, by a column's place in the list, so that neighbouring columns of the same
    // gray do not wait on each other's increments; summed after.
    std::array<std::array<int, 256>, 4> quarter{};
    int outer_count = 0;
    const int strip = std::max(2, edges.width / 16);
    std::vector<int> columns_beside;
    for (int i = 1; i <= strip; ++i) {
      const int left = edges.x0 - i >= 0 ? edges.x0 - i : edges.x0 + i - 1;
      const int right = edges.x0 + edges.width - 1 + i < image.width ? edges.x0 + edges.width - 1 + i
                                                                       : edges.x0 + edges.width - i;
      columns_beside.push_back(left);
      columns_beside.push_back(right);
    }
    for (int y = edges.y0; y < edges.y0 + edges.height; ++y) {
      const std::uint8_t* row = image.row(y);
      for (std::size_t i = 0; i < columns_beside.size(); ++i)
        ++quarter[i % 4][row[columns_beside[i]]];
      outer_count += static_cast<int>(columns_beside.size());
    }
    std::array<int, 256> histogram;
    for (int g = 0; g < 256; ++g)
      histogram[g] = quarter[0][g] + quarter[1][g] + quarter[2][g] + quarter[3][g];
    // The gray at rank outer_count / 2 in ascending order.
    int median = 0;
    for (int rank = outer_count / 2; rank >= histogram[median]; ++median) rank -= histogram[median];
    carpet_gray = median;
    min_above_gray = p.silhouette_min_above_carpet_ratio * median;
  }
  // An edge passes when the mean gray of the rows just above it (its upper row y_edge) is at least
  // min_above_gray: sum / n >= min_above_gray with n those rows inside the image. Decided on the
  // integer sum against the least passing sum per n (the same test as the double quotient's).
  const int above_rows = p.silhouette_above_rows_px;
  std::array<int, 17> min_above_sum{};  // silhouette_above_rows_px is at most 16
  if (min_above_gray > 0) {
    min_above_sum[0] = std::numeric_limits<int>::max();  // no row above: the mean is 0
    for (int n = 1; n <= above_rows; ++n) {
      int sum = static_cast<int>(std::ceil(min_above_gray * n));
      while (sum > 0 && static_cast<double>(sum - 1) / n >= min_above_gray) --sum;
      while (static_cast<double>(sum) / n < min_above_gray) ++sum;
      min_above_sum[n] = sum;
    }
  }
  std::vector<int> scan_x;
  for (int x = edges.x0 + half; x < edges.x0 + edges.width - half; x += p.scan_step_px) scan_x.push_back(x);
  const int columns = static_cast<int>(scan_x.size());
  // The median of the 2·half+1 responses around a pixel exceeds the threshold when more than
  // half of them do: `majority`, one bit per pixel (bit x % 64 of word x / 64 of its row), on the
  // scanned rows (all but the region's first and last) and zero elsewhere.
  const int w = edges.width, m = p.silhouette_min_rows;
  const int words = (w + 63) / 64;
  std::vector<std::uint64_t> majority(static_cast<std::size_t>(edges.height) * words, 0);
  // Bit x of the result is byte x of bytes[0, count) (each 0 or 1).
  auto packBits = [](const std::uint8_t* bytes, int count, std::uint64_t* out) {
    // Byte i of eight (each 0 or 1) lands on bit 56 + i of the product, no two partial products
    // overlap: the eight bits in its top byte.
    auto eightBits = [](std::uint64_t eight) { return (eight * 0x0102040810204080ULL) >> 56; };
    const int whole = count / 8;  // bytes 8·i .. 8·i+7 all inside
    for (int k = 0; 64 * k < count; ++k) {
      std::uint64_t word = 0;
      const int end = std::min(whole, 8 * k + 8);
      for (int i = 8 * k; i < end; ++i) {
        std::uint64_t eight;
        std::memcpy(&eight, bytes + 8 * i, 8);
        word |= eightBits(eight) << (8 * (i % 8));
      }
      out[k] = word;
    }
    if (count % 8 != 0) {
      std::uint64_t eight = 0;
      for (int j = 0; j < count % 8; ++j)
        eight |= static_cast<std::uint64_t>(bytes[8 * whole + j]) << (8 * j);
      out[whole / 8] |= eightBits(eight) << (8 * (whole % 8));
    }
  };
  if (half == 1) {
    // The median of three: two of the pixel and its two neighbours, on columns 1 .. w-2.
    std::vector<std::uint64_t> on(words);
    const std::uint64_t last_bit = std::uint64_t{1} << ((w - 1) % 64);
    for (int r = 1; r + 1 < edges.height; ++r) {
      packBits(&edges.on[static_cast<std::size_t>(r) * w], w, on.data());
      std::uint64_t* out_row = &majority[static_cast<std::size_t>(r) * words];
      for (int k = 0; k < words; ++k) {
        const std::uint64_t b = on[k];
        const std::uint64_t left = (b << 1) | (k > 0 ? on[k - 1] >> 63 : 0);           // bit x: x-1
        const std::uint64_t right = (b >> 1) | (k + 1 < words ? on[k + 1] << 63 : 0);  // bit x: x+1
        out_row[k] = (left & b) | (left & right) | (b & right);
      }
      out_row[0] &= ~std::uint64_t{1};
      out_row[words - 1] &= ~last_bit;
    }
  } else {
    std::vector<std::uint8_t> out_row(w);
    for (int r = 1; r + 1 < edges.height; ++r) {
      const std::uint8_t* row = &edges.on[static_cast<std::size_t>(r) * w];
      std::fill(out_row.begin(), out_row.end(), 0);
      int on = 0;
      for (int x = 0; x < 2 * half; ++x) on += row[x];
      for (int x = half; x + half < w; ++x) {
        on += row[x + half];
        out_row[x] = on > half;
        on -= row[x - half];
      }
      packBits(out_row.data(), w, &majority[static_cast<std::size_t>(r) * words]);
    }
  }
  // A heel's dark panel below an edge (its upper edge): points move below it, and its thin rim
  // answers on fewer rows.
  const DarkPanel panel{p.dark_panel_max_gray_ratio * carpet_gray,
                        static_cast<int>(std::ceil(p.dark_panel_min_height_fraction * h)),
                        static_cast<int>(p.dark_panel_max_height_fraction * h),
                        static_cast<int>(robot.feet_px.y() + p.dark_panel_below_feet_fraction * h)};
  const int panel_m = p.dark_panel_max_gray_ratio > 0 ? p.dark_panel_edge_min_rows : m;
  // Scanning a line bottom-up, an edge is the lowest row r of a run of majority rows (row r + 1
  // off or not scanned) at least m rows long (rows r-m+1 .. r on), or panel_m rows long with a
  // dark panel right below it. All scan lines together, row by row, 64 columns a word.
  std::vector<int> found(columns, 0);
  std::vector<Hit> column_hits(static_cast<std::size_t>(columns) * kMaxHits);
  // The scan line of each mask column, -1 where none is.
  std::vector<int> column_of(w, -1);
  for (int c = 0; c < columns; ++c) column_of[half + c * p.scan_step_px] = c;
  // The columns still scanned (a scan line and fewer than kMaxHits edges on it), 64 a word.
  std::vector<std::uint64_t> open_bits(words, 0);
  for (int x = 0; x < w; ++x) {
    if (column_of[x] >= 0) open_bits[x / 64] |= std::uint64_t{1} << (x % 64);
  }
  int open = columns;
  const auto mask_row = [&](int r) { return &majority[static_cast<std::size_t>(r) * words]; };
  // A run's top row, the rows above it whose mean the edge test takes and the least passing sum.
  struct AboveTest {
    int top_y = 0, n = 0, min_sum = 0;
  };
  const auto aboveTest = [&](int top_y) {
    AboveTest t;
    t.top_y = top_y;
    t.n = min_above_gray > 0 ? std::min(above_rows, top_y) : 0;
    t.min_sum = min_above_gray > 0 ? min_above_sum[t.n] : 0;
    return t;
  };
  for (int r = edges.height - 2; r >= panel_m && open > 0; --r) {
    const std::uint64_t* below = mask_row(r + 1);
    const int y = edges.y0 + r;  // the edge's row (the run's lowest)
    const bool long_possible = r >= m;
    // A panel starts below the edge and ends at most at its last row, at least min_rows on.
    const bool short_possible = panel_m < m && y + panel.min_rows <= panel.max_end_row;
    const AboveTest long_test = aboveTest(y - m + 1), short_test = aboveTest(y - panel_m + 1);
    for (int k = 0; k < words; ++k) {
      std::uint64_t lowest = ~below[k] & open_bits[k];
      std::uint64_t short_run = lowest;
      for (int j = 0; j < panel_m; ++j) short_run &= mask_row(r - j)[k];
      if (short_run == 0) continue;
      std::uint64_t long_run = long_possible ? short_run : 0;
      for (int j = panel_m; j < m && long_run != 0; ++j) long_run &= mask_row(r - j)[k];
      short_run = short_possible ? short_run & ~long_run : 0;
      for (std::uint64_t start = short_run | long_run; start != 0; start &= start - 1) {
        const int bit = __builtin_ctzll(start);
        const int c = column_of[64 * k + bit];
        const bool is_long = (long_run >> bit) & 1;
        if (!is_long && belowDarkPanel(image, scan_x[c], y, panel) == y) continue;
        const AboveTest& t = is_long ? long_test : short_test;
        int sum = 0;
        for (int i = 0; i < t.n; ++i) sum += image.row(t.top_y - 1 - i)[scan_x[c]];
        // A start that fails the test writes its hit where the column's next one goes, and the
        // count does not move.
        column_hits[static_cast<std::size_t>(c) * kMaxHits + found[c]] = {c, y};
        found[c] += static_cast<int>(sum >= t.min_sum);
        const bool full = found[c] == kMaxHits;
        open_bits[k] &= ~(static_cast<std::uint64_t>(full) << bit);
        open -= static_cast<int>(full);
      }
    }
  }
  int hit_count = 0;
  for (int c = 0; c < columns; ++c) hit_count += found[c];
  hits.reserve(hit_count);
  first_hit.reserve(static_cast<std::size_t>(columns) + 1);
  out.silhouette_px.reserve(columns);
  out.silhouette_in_robot.reserve(columns);
  const std::optional<Eigen::Vector2d> feet_ground = camera.pixelToGround(robot.feet_px);
  const FieldMarkingsAtFeet markings(p, field, camera, feet_ground, x_left, x_right, y_top, y_bottom,
                                     line_half_width_m_, centre_circle_radius_m_);
  // A sole's dark stripe under the feet's edge: thin, darker than the carpet, lighter below it,
  // inside the feet region.
  const bool sole_seen = p.field_line_sole_max_gray_ratio > 0 && h >= p.field_line_sole_min_box_height_px;
  const DarkPanel sole{p.field_line_sole_max_gray_ratio * carpet_gray, 1,
                       std::max(1, static_cast<int>(p.field_line_sole_max_height_fraction * h)), y_bottom};
  const auto onFieldLine = [&](const Hit& hit) {
    if (!markings.covers(camera, {scan_x[hit.column] + 0.5, hit.row + 0.5})) return false;
    return !sole_seen || belowDarkPanel(image, scan_x[hit.column], hit.row, sole) == hit.row;
  };
  for (int c = 0; c < columns; ++c) {
    first_hit.push_back(static_cast<int>(hits.size()));
    for (int k = 0; k < found[c]; ++k) {
      const Hit& hit = column_hits[static_cast<std::size_t>(c) * kMaxHits + k];
      if (!onFieldLine(hit)) hits.push_back(hit);
    }
  }
  first_hit.push_back(static_cast<int>(hits.size()));
  // Chains: hits on neighbouring scan lines within a few rows. The feet's edges make long chains,
  // the carpet's texture short ones.
  std::vector<int> parent(hits.size());
  for (std::size_t i = 0; i < hits.size(); ++i) parent[i] = static_cast<int>(i);
  auto root = [&](int i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  for (int c = 0; c + 1 < columns; ++c) {
    for (int i = first_hit[c]; i < first_hit[c + 1]; ++i) {
      for (int j = first_hit[c + 1]; j < first_hit[c + 2]; ++j) {
        if (std::abs(hits[i].row - hits[j].row) <= p.silhouette_neighbour_rows_px) parent[root(i)] = root(j);
      }
    }
  }
  std::vector<int> chain_columns(hits.size(), 0);
  for (std::size_t i = 0; i < hits.size(); ++i) ++chain_columns[root(static_cast<int>(i))];
  const double min_chain = std::max<double>(p.silhouette_min_chain_px,
                                            p.silhouette_min_chain_fraction * robot.box.width() / p.scan_step_px);
  // Per scan line, the lowest hit on a long chain is the lower silhouette (below a dark panel:
  // its lower end): its hit, and the row below a panel there (-1: none); a chain's points move
  // below panels only where most of its points have one (a heel's edge does; a cast shadow's
  // slanted edge gives a short dark stretch on a few scan lines).
  std::vector<int> chosen(columns, -1), below_panel(columns, -1);
  std::vector<int> chain_chosen(hits.size(), 0), chain_panels(hits.size(), 0);
  for (int c = 0; c < columns; ++c) {
    for (int i = first_hit[c]; i < first_hit[c + 1]; ++i) {
      if (chain_columns[root(i)] < min_chain) continue;
      chosen[c] = i;
      ++chain_chosen[root(i)];
      if (p.dark_panel_max_gray_ratio > 0) {
        const int row = belowDarkPanel(image, scan_x[c], hits[i].row, panel);
        if (row != hits[i].row) {
          below_panel[c] = row;
          ++chain_panels[root(i)];
        }
      }
      break;
    }
  }
  std::vector<int> panel_rows;  // per silhouette point, the rows it moved down below a panel
  for (int c = 0; c < columns; ++c) {
    const int i = chosen[c];
    if (i < 0) continue;
    const int r = root(i);
    const bool move =
        below_panel[c] >= 0 && chain_panels[r] >= p.dark_panel_min_chain_share * chain_chosen[r];
    const int row = move ? below_panel[c] : hits[i].row;
    const Eigen::Vector2d pt(scan_x[c] + 0.5, row + 0.5);
    if (const auto g = camera.pixelToGround(pt)) {
      out.silhouette_px.push_back(pt);
      out.silhouette_in_robot.push_back(*g);
      panel_rows.push_back(row - hits[i].row);
    }
  }
  SilhouetteLineBounds bounds;
  bounds.vote_distance = p.vote_distance_m;
  bounds.vote_margin = p.vote_margin_m;
  bounds.min_length = p.second_line_min_length_m;
  bounds.max_length = p.second_line_max_length_m;
  bounds.max_orthogonality_cos = p.second_line_max_cos;
  bounds.viewpoint = camera.position().head<2>();
  bounds.max_voter_gap = p.line_max_voter_gap_m;
  const SilhouetteLines lines = findSilhouetteLines(out.silhouette_in_robot, bounds);
  std::optional<Eigen::Vector2d> first_direction;
  for (auto line : {lines.first, lines.second}) {
    if (!line || line->votes < p.min_line_votes) continue;
    // Twice: the hull edge's direction is rough, the first fit's much less so.
    line = refineLine(*line, out.silhouette_in_robot, p.vote_distance_m, p.vote_margin_m,
                      p.line_max_voter_gap_m);
    line =
        refineLine(*line, out.silhouette_in_robot, p.vote_distance_m, 0.0, p.line_max_voter_gap_m);
    // The feet's edges meet at right angles: a refitted second line far from orthogonal to the
    // refitted first is no edge of the feet (its class would contradict or mislead the first's).
    if (first_direction && std::abs(line->direction().dot(*first_direction)) > p.second_line_max_refined_cos) {
      continue;
    }
    // Far behind the feet point it is the edge of lit carpet or of a field line in the feet
    // region, not the feet's.
    if (p.line_max_feet_distance_m > 0 && feet_ground &&
        ((line->a + line->b) / 2 - *feet_ground).norm() > p.line_max_feet_distance_m) {
      continue;
    }
    if (!first_direction) first_direction = line->direction();
    const auto a = camera.robotToPixel({line->a.x(), line->a.y(), 0});
    const auto b = camera.robotToPixel({line->b.x(), line->b.y(), 0});
    if (!a || !b) continue;
    // The region hangs from the edges the silhouette found (a panel's upper edge), where the nets
    // were trained to see it: the mean move of the silhouette points between the line's ends
    // moves it back up.
    double up = 0;
    int n_up = 0;
    for (std::size_t k = 0; k < panel_rows.size(); ++k) {
      const double x = out.silhouette_px[k].x();
      if (x >= std::min(a->x(), b->x()) && x <= std::max(a->x(), b->x())) {
        up += panel_rows[k];
        ++n_up;
      }
    }
    if (n_up > 0) up /= n_up;
    const Eigen::Vector2d mid = (*a + *b) / 2 - Eigen::Vector2d(0, up);
    const auto hpx = camera.robotHeightPx(mid, robot_height_m_);
    if (!hpx) continue;
    const double margin = std::max(2.0, p.region_margin_fraction * std::abs(a->x() - b->x()));
    LineRegion region;
    region.line_in_robot = *line;
    region.box.x0 = std::min(a->x(), b->x()) - margin;
    region.box.x1 = std::max(a->x(), b->x()) + margin;
    region.box.y0 = std::min(a->y(), b->y()) - up - p.region_above_fraction * *hpx;
    region.box.y1 = std::max(a->y(), b->y()) - up + p.region_below_fraction * *hpx;
    out.regions.push_back(region);
  }
  return out;
}

RobotLines RobotOrientationEstimator::estimate(const GrayView& image, const CameraModel& camera,
                                               const RobotPercept& robot,
                                               const FieldFeatures& field) const {
  RobotLines out = findLines(image, camera, robot, field);
  if (out.regions.empty()) return out;
  std::vector<cnn::PatchBox> boxes;
  for (const LineRegion& r : out.regions) {
    boxes.push_back({static_cast<float>(r.box.x0), static_cast<float>(r.box.y0),
                     static_cast<float>(r.box.width()), static_cast<float>(r.box.height())});
  }
  std::vector<float> usable, sides;
  boost_.classify(image, boxes, usable);
  // OriNet only on the regions OriBoostNet accepts (the others are not classified).
  std::vector<cnn::PatchBox> accepted;
  std::vector<int> accepted_index(out.regions.size(), -1);
  for (std::size_t i = 0; i < out.regions.size(); ++i) {
    if (usable[2 * i + 1] < params_.min_usable_confidence) continue;
    accepted_index[i] = static_cast<int>(accepted.size());
    accepted.push_back(boxes[i]);
  }
  if (!accepted.empty()) {
    // OriNet's inputs, extracted once: as they are, then (with the mirrored look) mirrored. A
    // region mirrored shows the same robot facing the other way in the image: the mirrored look's
    // side classes are swapped (OriNet never learnt from mirrored side regions).
    const cnn::Shape& in = ori_.input();
    const std::size_t n = static_cast<std::size_t>(in.size());
    const std::size_t count = accepted.size();
    std::vector<float> inputs(count * n);
    for (std::size_t i = 0; i < count; ++i) {
      ori_.extract(image, accepted[i], inputs.data() + i * n);
    }
    sides.resize(count * 4);
    ori_.run(inputs.data(), static_cast<int>(count), sides.data());
    if (params_.ori_net_mirrored_look) {
      std::vector<float> mirrored(count * n), mirrored_sides(count * 4);
      for (std::size_t i = 0; i < count; ++i) {
        cnn::mirrorPatch(inputs.data() + i * n, in.width, in.height, mirrored.data() + i * n);
      }
      ori_.run(mirrored.data(), static_cast<int>(count), mirrored_sides.data());
      for (std::size_t i = 0; i < count; ++i) {
        float* s = &sides[4 * i];
        const float* m = &mirrored_sides[4 * i];
        const float swapped[4] = {m[0], m[1], m[3], m[2]};
        for (int c = 0; c < 4; ++c) s[c] = 0.5f * (s[c] + swapped[c]);
      }
    }
  }
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  if (robot.position_in_robot) {
    position = *robot.position_in_robot;
  } else {
    for (const auto& q : out.silhouette_in_robot) position += q;
    position /= static_cast<double>(out.silhouette_in_robot.size());
  }
  std::vector<RobotOrientation> orientations;
  std::vector<RobotSide> classes;
  std::vector<float> confidences;
  for (std::size_t i = 0; i < out.regions.size(); ++i) {
    LineRegion& r = out.regions[i];
    r.usable = usable[2 * i + 1];
    if (accepted_index[i] < 0) continue;  // OriBoostNet rejected it
    // OriNet: front, back, side facing the observer's left, side facing its right. The class is
    // decided over front / back / side (the two side classes summed); a side region's facing is
    // known only when one of its two classes clearly dominates.
    const float* s = &sides[4 * static_cast<std::size_t>(accepted_index[i])];
    const float side_sum = s[2] + s[3];
    const float scores[3] = {s[0], s[1], side_sum};
    const int best = static_cast<int>(std::max_element(scores, scores + 3) - scores);
    r.side_confidence = scores[best];
    if (scores[best] < params_.min_side_confidence) continue;
    r.side = static_cast<RobotSide>(best);
    if (*r.side == RobotSide::kSide && side_sum > 0 &&
        std::max(s[2], s[3]) >= params_.min_side_facing_share * side_sum) {
      r.side_facing_known = true;
      r.faces_left = s[2] >= s[3];
      orientations.push_back(
          orientationFromSideLine(r.line_in_robot.a, r.line_in_robot.b, r.faces_left, position));
    } else {
      orientations.push_back(
          orientationFromLine(r.line_in_robot.a, r.line_in_robot.b, *r.side, position));
    }
    classes.push_back(*r.side);
    confidences.push_back(r.side_confidence);
  }
  if (params_.keep_most_confident_of_a_class) keepMostConfidentOfEachClass(orientations, classes, confidences);
  out.orientation = combineLineOrientations(orientations, classes);
  return out;
}

void RobotOrientationEstimator::run(const GrayView& image, const CameraModel& camera,
                                    std::vector<RobotPercept>& robots, RobotTracks& tracks,
                                    double time_s, const FieldFeatures& field) const {
  for (RobotPercept& r : robots) r.orientation_raw = estimate(image, camera, r, field).orientation;
  OrientationFilterParams filter;
  filter.buffer_size = params_.filter_buffer_size;
  filter.expiry_s = params_.track_expiry_s;
  updateRobotTracks(tracks, robots, time_s, params_.track_max_distance_m, filter);
}

namespace {
bool expired(const RobotTracks::Track& t, double time_s, double expiry_s) {
  return time_s - t.last_seen_s > expiry_s;
}
}  // namespace

std::vector<Eigen::Vector2d> trackedRobots(const RobotTracks& tracks, double time_s, int min_hits,
                                           double expiry_s) {
  std::vector<Eigen::Vector2d> out;
  for (const RobotTracks::Track& t : tracks.tracks) {
    if (t.hits >= min_hits && !expired(t, time_s, expiry_s)) out.push_back(t.position_in_robot);
  }
  return out;
}

void updateRobotTracks(RobotTracks& tracks, std::vector<RobotPercept>& robots, double time_s,
                       double max_distance_m, const OrientationFilterParams& filter) {
  auto& list = tracks.tracks;
  list.erase(std::remove_if(list.begin(), list.end(),
                            [&](const RobotTracks::Track& t) { return expired(t, time_s, filter.expiry_s); }),
             list.end());
  // Greedy nearest-first association.
  struct Pair {
    double d;
    int robot, track;
  };
  std::vector<Pair> pairs;
  for (std::size_t i = 0; i < robots.size(); ++i) {
    if (!robots[i].position_in_robot) continue;
    for (std::size_t t = 0; t < list.size(); ++t) {
      const double d = (list[t].position_in_robot - *robots[i].position_in_robot).norm();
      if (d <= max_distance_m) pairs.push_back({d, static_cast<int>(i), static_cast<int>(t)});
    }
  }
  std::stable_sort(pairs.begin(), pairs.end(), [](const Pair& a, const Pair& b) { return a.d < b.d; });
  std::vector<int> robot_track(robots.size(), -1);
  std::vector<bool> track_used(list.size(), false);
  for (const Pair& p : pairs) {
    if (robot_track[p.robot] >= 0 || track_used[p.track]) continue;
    robot_track[p.robot] = p.track;
    track_used[p.track] = true;
  }
  for (std::size_t i = 0; i < robots.size(); ++i) {
    RobotPercept& r = robots[i];
    if (!r.position_in_robot) {
      r.track_id = -1;
      r.orientation_filtered.reset();
      continue;
    }
    if (robot_track[i] < 0) {
      RobotTracks::Track t;
      t.id = tracks.next_id++;
      list.push_back(t);
      robot_track[i] = static_cast<int>(list.size()) - 1;
    }
    RobotTracks::Track& t = list[robot_track[i]];
    t.position_in_robot = *r.position_in_robot;
    t.last_seen_s = time_s;
    ++t.hits;
    r.track_id = t.id;
    r.orientation_filtered = updateOrientationTrack(t.orientation, r.orientation_raw, time_s, filter);
  }
}

}  // namespace colorfree
