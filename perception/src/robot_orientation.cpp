#include "colorfree/perception/robot_orientation.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <Eigen/Eigenvalues>

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
  p.vote_distance_m = f.getInRange("vote_distance_m", 0.0001, 1);
  p.vote_margin_m = f.getInRange("vote_margin_m", 0, 2);
  p.second_line_min_length_m = f.getInRange("second_line_min_length_m", 0, 2);
  p.second_line_max_length_m = f.getInRange("second_line_max_length_m", 0, 2);
  p.second_line_max_cos = f.getInRange("second_line_max_cos", 0, 1);
  p.second_line_max_refined_cos = f.getInRange("second_line_max_refined_cos", 0, 1);
  p.min_line_votes = f.getInRange("min_line_votes", 0, 1000);
  p.line_max_voter_gap_m = f.getInRange("line_max_voter_gap_m", 0, 2);
  p.region_margin_fraction = f.getInRange("region_margin_fraction", 0, 2);
  p.region_above_fraction = f.getInRange("region_above_fraction", 0, 2);
  p.region_below_fraction = f.getInRange("region_below_fraction", 0, 2);
  p.min_usable_confidence = f.getInRange("min_usable_confidence", 0, 1);
  p.min_side_confidence = f.getInRange("min_side_confidence", 0, 1);
  p.min_side_facing_share = f.getInRange("min_side_facing_share", 0.5, 1);
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

// The CNS's rows of a (non-empty) region: calls row(y, up, mid, down, vs, vs2) for each row y
// (relative to the region), with up / mid / down the image rows y-1, y, y+1 from the region's
// column 0 (reads clamped to the image, valid from column -1 to width) and vs, vs2 the sums of the
// values and their squares over the variance window's 2·radius+1 rows per column (valid from
// column -radius to width-1+radius).
template <typename RowFn>
void forEachCnsRow(const GrayView& image, const CnsRegion& r, int radius, RowFn&& row_fn) {
  // The region grown by a border (the variance window's radius, at least the Sobel's 1 px),
  // copied once with reads clamped to the image: the loops read it without any checks.
  const int border = std::max(radius, 1);
  const int pw = r.width + 2 * border, ph = r.height + 2 * border;
  std::vector<std::int32_t> pix(static_cast<std::size_t>(pw) * ph);
  std::vector<int> col(pw);
  for (int i = 0; i < pw; ++i) col[i] = std::clamp(r.x0 - border + i, 0, image.width - 1);
  // Columns i_lo .. i_hi-1 need no clamping: a plain widening copy.
  const int i_lo = std::min(pw, std::max(0, border - r.x0));
  const int i_hi = std::max(i_lo, std::min(pw, image.width - r.x0 + border));
  for (int j = 0; j < ph; ++j) {
    const std::uint8_t* src = image.row(std::clamp(r.y0 - border + j, 0, image.height - 1));
    std::int32_t* dst = &pix[static_cast<std::size_t>(j) * pw];
    for (int i = 0; i < i_lo; ++i) dst[i] = src[col[i]];
    const std::uint8_t* run = src + (r.x0 - border);
    for (int i = i_lo; i < i_hi; ++i) dst[i] = run[i];
    for (int i = i_hi; i < pw; ++i) dst[i] = src[col[i]];
  }
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
  const auto n = static_cast<std::int32_t>(norm.n);
  const float t = static_cast<float>(threshold);
  const float t2 = t * t;
  std::vector<std::int32_t> minus_gy(r.width), s(r.width), s2(r.width);
  std::vector<std::int32_t> decided(r.width);
  forEachCnsRow(image, r, radius,
                [&](int y, const std::int32_t* up, const std::int32_t*, const std::int32_t* down,
                    const std::int32_t* vs, const std::int32_t* vs2) {
                  // Loops the compiler vectorises: the Sobel, the window sums, the decision.
                  for (int x = 0; x < r.width; ++x) minus_gy[x] = -sobelY(up + x, down + x);
                  if (radius == 2) {
                    // The shipped radius: the five columns' sums in one pass (exact integers,
                    // the same sums as below).
                    std::int32_t* __restrict ps_out = s.data();
                    std::int32_t* __restrict ps2_out = s2.data();
                    for (int x = 0; x < r.width; ++x) {
                      ps_out[x] = vs[x - 2] + vs[x - 1] + vs[x] + vs[x + 1] + vs[x + 2];
                      ps2_out[x] = vs2[x - 2] + vs2[x - 1] + vs2[x] + vs2[x + 1] + vs2[x + 2];
                    }
                  } else {
                    std::fill(s.begin(), s.end(), 0);
                    std::fill(s2.begin(), s2.end(), 0);
                    for (int i = -radius; i <= radius; ++i) {
                      for (int x = 0; x < r.width; ++x) {
                        s[x] += vs[x + i];
                        s2[x] += vs2[x + i];
                      }
                    }
                  }
                  std::uint8_t* on = &out.on[static_cast<std::size_t>(y) * r.width];
                  // Locals, so that the stores below alias none of the loop's inputs.
                  const int width = r.width;
                  const std::int32_t nn = n, *ps = s.data(), *ps2 = s2.data(), *pg = minus_gy.data();
                  const float inv_n2 = norm.inv_n2, sigma2 = norm.sigma2, tt2 = t2;
                  std::int32_t* pd = decided.data();
                  for (int x = 0; x < width; ++x) {
                    // (-gy) / sqrt(q) > t on the squares (the float q as CnsNormalizer::squared
                    // gives it; the squared Sobel is exact in a float) ...
                    const std::int32_t var_n2 = std::max(0, nn * ps2[x] - ps[x] * ps[x]);
                    const float q = 64.0f * static_cast<float>(var_n2) * inv_n2 + sigma2;
                    const float g = static_cast<float>(std::max(pg[x], 0));
                    const float g2 = g * g, t2q = tt2 * q;
                    const auto above = static_cast<std::int32_t>(g2 > t2q * (1 + 1e-5f));
                    const auto near = static_cast<std::int32_t>(g2 >= t2q * (1 - 1e-5f));
                    pd[x] = static_cast<std::int32_t>(pg[x] > 0) * (above + 2 * (near - above));  // 1 on, 2 a tie
                  }
                  // decided is 0, 1 or 2: bit 0 is "on", bit 1 a tie. Two loops the compiler
                  // vectorises (restrict: the byte stores alias none of the decisions).
                  std::uint8_t* __restrict on_out = on;
                  const std::int32_t* __restrict pdc = pd;
                  std::int32_t any = 0;
                  for (int x = 0; x < width; ++x) any |= pdc[x];
                  for (int x = 0; x < width; ++x) on_out[x] = static_cast<std::uint8_t>(pdc[x] & 1);
                  if ((any & 2) == 0) return;
                  // ... and near a tie as contrastNormalizedSobel computes gy (negated: exact in
                  // floating point).
                  for (int x = 0; x < r.width; ++x) {
                    if (decided[x] == 2) on[x] = -(static_cast<float>(-minus_gy[x]) * norm(s[x], s2[x])) > t;
                  }
                });
  return out;
}

RobotOrientationEstimator::RobotOrientationEstimator(RobotOrientationParams params,
                                                     FieldDimensions field,
                                                     cnn::Classifier ori_boost_net,
                                                     cnn::Classifier ori_net)
    : params_(params),
      robot_height_m_(field.robot_height_m),
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
}  // namespace

RobotLines RobotOrientationEstimator::findLines(const GrayView& image, const CameraModel& camera,
                                                const RobotPercept& robot) const {
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
  double min_above_gray = 0;
  if (p.silhouette_min_above_carpet_ratio > 0) {
    // The median by a histogram of the gray levels: the same value as sorting them.
    std::array<int, 256> histogram{};
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
      for (int x : columns_beside) ++histogram[row[x]];
      outer_count += static_cast<int>(columns_beside.size());
    }
    // The gray at rank outer_count / 2 in ascending order.
    int median = 0;
    for (int rank = outer_count / 2; rank >= histogram[median]; ++median) rank -= histogram[median];
    min_above_gray = p.silhouette_min_above_carpet_ratio * median;
  }
  // The mean gray of the rows just above an edge whose upper row is y_edge.
  auto aboveGray = [&](int x, int y_edge) {
    int sum = 0, n = 0;
    for (int y = y_edge - 1; y >= y_edge - p.silhouette_above_rows_px && y >= 0; --y, ++n) sum += image.row(y)[x];
    return n > 0 ? static_cast<double>(sum) / n : 0.0;
  };
  std::vector<int> scan_x;
  for (int x = edges.x0 + half; x < edges.x0 + edges.width - half; x += p.scan_step_px) scan_x.push_back(x);
  const int columns = static_cast<int>(scan_x.size());
  // The median of the 2·half+1 responses around a pixel exceeds the threshold when more than
  // half of them do: `majority`, row-major as the mask, on the scanned rows (all but the region's
  // first and last) and zero elsewhere.
  const int w = edges.width, m = p.silhouette_min_rows;
  std::vector<std::uint8_t> majority(edges.on.size(), 0);
  for (int r = 1; r + 1 < edges.height; ++r) {
    const std::uint8_t* row = &edges.on[static_cast<std::size_t>(r) * w];
    std::uint8_t* out_row = &majority[static_cast<std::size_t>(r) * w];
    if (half == 1) {
      for (int x = 1; x + 1 < w; ++x) out_row[x] = row[x - 1] + row[x] + row[x + 1] >= 2;
    } else {
      int on = 0;
      for (int x = 0; x < 2 * half; ++x) on += row[x];
      for (int x = half; x + half < w; ++x) {
        on += row[x + half];
        out_row[x] = on > half;
        on -= row[x - half];
      }
    }
  }
  // Scanning a line bottom-up, an edge is where the run of majority rows reaches m: rows r .. r+m-1
  // on and the row below them off (or not scanned). All scan lines together, row by row.
  std::vector<int> found(columns, 0);
  std::vector<Hit> column_hits(static_cast<std::size_t>(columns) * kMaxHits);
  // Padded by 8 zero bytes: each 8-byte word below is read whole.
  std::vector<std::uint8_t> start(static_cast<std::size_t>(w) + 8, 0);
  // The scan line of each mask column, -1 where none is.
  std::vector<int> column_of(w, -1);
  for (int x = 0; x < w; ++x) {
    if ((x - half) % p.scan_step_px != 0) continue;
    const int c = (x - half) / p.scan_step_px;
    if (c >= 0 && c < columns) column_of[x] = c;
  }
  int open = columns;
  for (int r = edges.height - 1 - m; r >= 1 && open > 0; --r) {
    const std::uint8_t* below = &majority[static_cast<std::size_t>(r + m) * w];
    const std::uint8_t* first = &majority[static_cast<std::size_t>(r) * w];
    if (m == 2) {
      for (int x = 0; x < w; ++x) start[x] = first[x] & first[x + w] & (below[x] ^ 1);
    } else {
      for (int x = 0; x < w; ++x) {
        std::uint8_t all = below[x] ^ 1;
        for (int k = 0; k < m; ++k) all &= first[static_cast<std::size_t>(k) * w + x];
        start[x] = all;
      }
    }
    // The few starts, eight bytes at a time past the empty stretches.
    const int y = edges.y0 + r;
    for (int x0 = 0; x0 < w; x0 += 8) {
      std::uint64_t word = 0;
      std::memcpy(&word, &start[x0], 8);
      if (word == 0) continue;
      for (int x = x0; x < std::min(w, x0 + 8); ++x) {
        if (!start[x]) continue;
        const int c = column_of[x];
        if (c < 0 || found[c] == kMaxHits) continue;
        if (min_above_gray > 0 && aboveGray(scan_x[c], y) < min_above_gray) continue;
        column_hits[static_cast<std::size_t>(c) * kMaxHits + found[c]] = {c, y + m - 1};
        if (++found[c] == kMaxHits) --open;
      }
    }
  }
  for (int c = 0; c < columns; ++c) {
    first_hit.push_back(static_cast<int>(hits.size()));
    for (int k = 0; k < found[c]; ++k) hits.push_back(column_hits[static_cast<std::size_t>(c) * kMaxHits + k]);
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
  // Per scan line, the lowest hit on a long chain is the lower silhouette.
  for (int c = 0; c < columns; ++c) {
    for (int i = first_hit[c]; i < first_hit[c + 1]; ++i) {
      if (chain_columns[root(i)] < min_chain) continue;
      const Eigen::Vector2d pt(scan_x[c] + 0.5, hits[i].row + 0.5);
      if (const auto g = camera.pixelToGround(pt)) {
        out.silhouette_px.push_back(pt);
        out.silhouette_in_robot.push_back(*g);
      }
      break;
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
    if (!first_direction) first_direction = line->direction();
    const auto a = camera.robotToPixel({line->a.x(), line->a.y(), 0});
    const auto b = camera.robotToPixel({line->b.x(), line->b.y(), 0});
    if (!a || !b) continue;
    const Eigen::Vector2d mid = (*a + *b) / 2;
    const auto hpx = camera.robotHeightPx(mid, robot_height_m_);
    if (!hpx) continue;
    const double margin = std::max(2.0, p.region_margin_fraction * std::abs(a->x() - b->x()));
    LineRegion region;
    region.line_in_robot = *line;
    region.box.x0 = std::min(a->x(), b->x()) - margin;
    region.box.x1 = std::max(a->x(), b->x()) + margin;
    region.box.y0 = std::min(a->y(), b->y()) - p.region_above_fraction * *hpx;
    region.box.y1 = std::max(a->y(), b->y()) + p.region_below_fraction * *hpx;
    out.regions.push_back(region);
  }
  return out;
}

RobotLines RobotOrientationEstimator::estimate(const GrayView& image, const CameraModel& camera,
                                               const RobotPercept& robot) const {
  RobotLines out = findLines(image, camera, robot);
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
  if (!accepted.empty()) ori_.classify(image, accepted, sides);
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
                                    double time_s) const {
  for (RobotPercept& r : robots) r.orientation_raw = estimate(image, camera, r).orientation;
  OrientationFilterParams filter;
  filter.buffer_size = params_.filter_buffer_size;
  filter.expiry_s = params_.track_expiry_s;
  updateRobotTracks(tracks, robots, time_s, params_.track_max_distance_m, filter);
}

void updateRobotTracks(RobotTracks& tracks, std::vector<RobotPercept>& robots, double time_s,
                       double max_distance_m, const OrientationFilterParams& filter) {
  auto& list = tracks.tracks;
  list.erase(std::remove_if(list.begin(), list.end(),
                            [&](const RobotTracks::Track& t) {
                              return time_s - t.last_seen_s > filter.expiry_s;
                            }),
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
    r.track_id = t.id;
    r.orientation_filtered = updateOrientationTrack(t.orientation, r.orientation_raw, time_s, filter);
  }
}

}  // namespace colorfree
