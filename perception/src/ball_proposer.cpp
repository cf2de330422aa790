#include "colorfree/perception/ball_proposer.h"

#include <algorithm>
#include <cmath>

#include "colorfree/perception/error.h"
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
  p.per_window_count = static_cast<int>(f.getInRange("per_window_count", 1, 16));
  p.nms_fraction = f.getInRange("nms_fraction", 0, 10);
  p.max_count = static_cast<int>(f.getInRange("max_count", 1, 1000));
  p.line_count = static_cast<int>(f.getInRange("line_count", 0, 1000));
  p.line_min_response = f.getInRange("line_min_response", -255, 255);
  p.feet_region_diameters = f.getInRange("feet_region_diameters", 0, 20);
  p.feet_boost = f.getInRange("feet_boost", 0, 10);
  p.texture_weight = f.getInRange("texture_weight", 0, 10);
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

// An integral image over a region of interest: sums of any box inside the image, with the box
// clamped to the region (which covers every box the scan asks for, clamped to the image).
class Integral {
 public:
  Integral(const GrayView& image, int x0, int y0, int x1, int y1)
      : x0_(x0), y0_(y0), w_(x1 - x0), h_(y1 - y0), stride_(w_ + 1),
        sums_(static_cast<std::size_t>(stride_) * (h_ + 1), 0u) {
    for (int y = 0; y < h_; ++y) {
      const std::uint8_t* src = image.row(y0 + y) + x0;
      const std::uint32_t* above = sums_.data() + static_cast<std::size_t>(y) * stride_;
      std::uint32_t* out = sums_.data() + static_cast<std::size_t>(y + 1) * stride_;
      std::uint32_t run = 0;
      for (int x = 0; x < w_; ++x) {
        run += src[x];
        out[x + 1] = above[x + 1] + run;
      }
    }
  }
  // Integral value at image coordinates (x, y) (the sum of pixels left of x and above y),
  // coordinates clamped into the region.
  std::uint32_t at(int x, int y) const {
    x = std::clamp(x - x0_, 0, w_);
    y = std::clamp(y - y0_, 0, h_);
    return sums_[static_cast<std::size_t>(y) * stride_ + x];
  }
  int clampX(int x) const { return std::clamp(x, x0_, x0_ + w_); }
  int clampY(int y) const { return std::clamp(y, y0_, y0_ + h_); }

 private:
  int x0_, y0_, w_, h_, stride_;
  std::vector<std::uint32_t> sums_;
};

// The response at (x, y) for expected radius r: a 3×3 grid of cells, the centre cell the inner box.
// Centre mean minus, over the four pairs of opposite surround cells, the brightest pair's darker
// cell (a line or a crossing through the centre lights both cells of a pair; a robot's foot or a
// line beside the ball only one), plus the print term: the spread of the centre's four quadrants.
float response(const Integral& ii, int x, int y, double r, const BallProposerParams& p,
               float* on_line = nullptr) {
  const int a = std::max(1, static_cast<int>(std::lround(p.inner_fraction * r)));
  const int b = std::max(a + 1, static_cast<int>(std::lround(p.outer_fraction * r)));
  const int xs[4] = {ii.clampX(x - b), ii.clampX(x - a), ii.clampX(x + a), ii.clampX(x + b)};
  const int ys[4] = {ii.clampY(y - b), ii.clampY(y - a), ii.clampY(y + a), ii.clampY(y + b)};
  std::uint32_t v[4][4];
  for (int j = 0; j < 4; ++j) {
    for (int i = 0; i < 4; ++i) v[j][i] = ii.at(xs[i], ys[j]);
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

}  // namespace

std::vector<BallProposal> BallProposer::run(const GrayView& image, const CameraModel& camera,
                                            const IgnoreMask& ignore, const ContrastRegions& regions,
                                            const std::vector<RobotPercept>* robots) const {
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
  std::vector<ScanRect> rects;
  const int s = regions.window_px;
  for (int r = 0; r < regions.rows; ++r) {
    for (int c = 0; c < regions.columns; ++c) {
      if (regions.marked(c, r)) rects.push_back({c * s, r * s, (c + 1) * s, (r + 1) * s, 1.0});
    }
  }
  if (robots != nullptr) {
    for (const RobotPercept& robot : *robots) {
      const auto rad = camera.ballRadiusPx(robot.feet_px, p.ball_radius_m);
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

  // Expected radius at the top and bottom of every rectangle (interpolated in between).
  struct RectRadius {
    std::optional<double> top, bottom;
  };
  std::vector<RectRadius> radii(rects.size());
  int rx0 = image.width, ry0 = image.height, rx1 = 0, ry1 = 0;
  for (std::size_t k = 0; k < rects.size(); ++k) {
    const ScanRect& rc = rects[k];
    const double cx = (rc.x0 + rc.x1) / 2.0;
    radii[k].top = camera.ballRadiusPx({cx, rc.y0 + 0.5}, p.ball_radius_m);
    radii[k].bottom = camera.ballRadiusPx({cx, rc.y1 - 0.5}, p.ball_radius_m);
    const double rmax = std::min(p.max_radius_px, std::max({p.min_radius_px, radii[k].top.value_or(0),
                                                            radii[k].bottom.value_or(0)}));
    const int margin = static_cast<int>(std::ceil(p.outer_fraction * rmax)) + 2;
    rx0 = std::min(rx0, rc.x0 - margin);
    ry0 = std::min(ry0, rc.y0 - margin);
    rx1 = std::max(rx1, rc.x1 + margin);
    ry1 = std::max(ry1, rc.y1 + margin);
  }
  rx0 = std::max(rx0, 0);
  ry0 = std::max(ry0, 0);
  rx1 = std::min(rx1, image.width);
  ry1 = std::min(ry1, image.height);
  const Integral ii(image, rx0, ry0, rx1, ry1);

  std::vector<Candidate> candidates;
  std::vector<Candidate> line_candidates;
  std::vector<Candidate> best;
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
        rad = camera.ballRadiusPx({cx, y + 0.5}, p.ball_radius_m);
      }
      if (!rad || *rad > p.max_radius_px || *rad < p.min_radius_px) {
        ++y;
        continue;
      }
      const double r = *rad;
      const int step = std::max(1, static_cast<int>(p.step_fraction * r));
      const int x_start = rc.x0 + (step - 1) / 2;
      const int yy = std::min(y + (step - 1) / 2, rc.y1 - 1);
      for (int x = x_start; x < rc.x1; x += step) {
        if (!ignore.looked(x, yy)) continue;
        float line_resp = 0;
        const float resp = response(ii, x, yy, r, p, &line_resp) * static_cast<float>(rc.boost);
        if (p.line_count > 0 && line_resp > best_line.response) {
          best_line = {x + 0.5f, yy + 0.5f, static_cast<float>(r), line_resp};
        }
        if (resp < p.min_response) continue;
        const Candidate cand{x + 0.5f, yy + 0.5f, static_cast<float>(r), resp};
        if (static_cast<int>(best.size()) < keep) {
          best.push_back(cand);
        } else {
          auto weakest = std::min_element(best.begin(), best.end(), [](const Candidate& l, const Candidate& m) {
            return l.response < m.response;
          });
          if (cand.response > weakest->response) *weakest = cand;
        }
      }
      y += step;
    }
    candidates.insert(candidates.end(), best.begin(), best.end());
    if (best_line.response >= p.line_min_response) line_candidates.push_back(best_line);
  }
  // Ranking: the ball's black print makes its centre box textured where robots' feet and hands,
  // lines and marks are flat; the per-window winners (placed by the DoG) are ranked by the DoG
  // plus texture_weight × the standard deviation of the centre box's pixels.
  if (p.texture_weight > 0) {
    for (Candidate& c : candidates) {
      const int a = std::max(1, static_cast<int>(std::lround(p.inner_fraction * c.r)));
      const int sub = std::max(1, a / 4);
      const int cx = static_cast<int>(c.x), cy = static_cast<int>(c.y);
      double sum = 0, sq = 0;
      int n = 0;
      for (int y = std::max(0, cy - a); y <= std::min(image.height - 1, cy + a); y += sub) {
        const std::uint8_t* row = image.row(y);
        for (int x = std::max(0, cx - a); x <= std::min(image.width - 1, cx + a); x += sub) {
          sum += row[x];
          sq += static_cast<double>(row[x]) * row[x];
          ++n;
        }
      }
      if (n > 1) {
        const double mean = sum / n;
        c.response += static_cast<float>(p.texture_weight * std::sqrt(std::max(0.0, sq / n - mean * mean)));
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
  const auto take = [&](const std::vector<Candidate>& list, int limit) {
    for (const Candidate& c : list) {
      if (static_cast<int>(out.size()) >= limit) break;
      bool suppressed = false;
      for (const BallProposal& o : out) {
        const double d = p.nms_fraction * std::max<double>(c.r, o.radius_px);
        const double dx = c.x - o.centre_px.x(), dy = c.y - o.centre_px.y();
        if (dx * dx + dy * dy < d * d) {
          suppressed = true;
          break;
        }
      }
      if (suppressed) continue;
      // Refine the centre at single pixels within the scan step around the winner.
      const int step = std::max(1, static_cast<int>(p.step_fraction * c.r));
      const int cx = static_cast<int>(c.x), cy = static_cast<int>(c.y);
      float best_resp = c.response;
      int bx = cx, by = cy;
      const bool line = &list == &line_candidates;
      const auto score = [&](int x, int y) {
        float on_line = 0;
        const float r1 = response(ii, x, y, c.r, p, &on_line);
        return line ? on_line : r1;
      };
      const float base = score(cx, cy);
      float best_base = base;
      for (int dy = -step / 2; dy <= step / 2 && step > 1; ++dy) {
        for (int dx = -step / 2; dx <= step / 2; ++dx) {
          const int x = cx + dx, y = cy + dy;
          if ((dx == 0 && dy == 0) || !image.contains(x, y) || !ignore.looked(x, y)) continue;
          const float r2 = score(x, y);
          if (r2 > best_base) best_base = r2, bx = x, by = y;
        }
      }
      BallProposal prop;
      prop.centre_px = {bx + 0.5, by + 0.5};
      prop.radius_px = c.r;
      prop.response = best_resp + (best_base - base);
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
