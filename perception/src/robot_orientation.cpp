#include "colorfree/perception/robot_orientation.h"

#include <algorithm>
#include <cmath>
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
  p.variance_radius_px = static_cast<int>(f.getInRange("variance_radius_px", 1, 8));
  p.cns_sigma_gray = f.getInRange("cns_sigma_gray", 0.01, 255);
  p.cns_threshold = f.getInRange("cns_threshold", 0, 2);
  p.silhouette_min_rows = static_cast<int>(f.getInRange("silhouette_min_rows", 1, 8));
  p.silhouette_neighbour_rows_px = static_cast<int>(f.getInRange("silhouette_neighbour_rows_px", 0, 64));
  p.silhouette_min_chain_px = static_cast<int>(f.getInRange("silhouette_min_chain_px", 1, 640));
  p.silhouette_min_chain_fraction = f.getInRange("silhouette_min_chain_fraction", 0, 1);
  p.vote_distance_m = f.getInRange("vote_distance_m", 0.0001, 1);
  p.vote_margin_m = f.getInRange("vote_margin_m", 0, 2);
  p.second_line_min_length_m = f.getInRange("second_line_min_length_m", 0, 2);
  p.second_line_max_length_m = f.getInRange("second_line_max_length_m", 0, 2);
  p.second_line_max_cos = f.getInRange("second_line_max_cos", 0, 1);
  p.min_line_votes = f.getInRange("min_line_votes", 0, 1000);
  p.region_margin_fraction = f.getInRange("region_margin_fraction", 0, 2);
  p.region_above_fraction = f.getInRange("region_above_fraction", 0, 2);
  p.region_below_fraction = f.getInRange("region_below_fraction", 0, 2);
  p.min_usable_confidence = f.getInRange("min_usable_confidence", 0, 1);
  p.min_side_confidence = f.getInRange("min_side_confidence", 0, 1);
  p.track_max_distance_m = f.getInRange("track_max_distance_m", 0, 10);
  p.track_expiry_s = f.getInRange("track_expiry_s", 0, 60);
  p.filter_buffer_size = static_cast<int>(f.getInRange("filter_buffer_size", 1, 101));
  f.finish();
  return p;
}

RobotOrientationParams RobotOrientationParams::loadDefault() {
  return load(defaultParamDir() + "/robot_orientation.yaml");
}

CnsImage contrastNormalizedSobel(const GrayView& image, int x0, int y0, int width, int height,
                                 int radius, double sigma) {
  CnsImage out;
  x0 = std::clamp(x0, 0, image.width);
  y0 = std::clamp(y0, 0, image.height);
  width = std::clamp(width, 0, image.width - x0);
  height = std::clamp(height, 0, image.height - y0);
  out.x0 = x0;
  out.y0 = y0;
  out.width = width;
  out.height = height;
  out.gx.assign(static_cast<std::size_t>(width) * height, 0.0f);
  out.gy.assign(out.gx.size(), 0.0f);
  if (width == 0 || height == 0) return out;
  auto px = [&](int x, int y) -> double {
    return image.at(std::clamp(x, 0, image.width - 1), std::clamp(y, 0, image.height - 1));
  };
  // Integral images of the values and their squares over the region grown by the window radius.
  const int gw = width + 2 * radius, gh = height + 2 * radius;
  std::vector<double> s((gw + 1) * (gh + 1), 0.0), s2((gw + 1) * (gh + 1), 0.0);
  for (int j = 0; j < gh; ++j) {
    double row = 0, row2 = 0;
    for (int i = 0; i < gw; ++i) {
      const double v = px(x0 - radius + i, y0 - radius + j);
      row += v;
      row2 += v * v;
      s[(j + 1) * (gw + 1) + i + 1] = s[j * (gw + 1) + i + 1] + row;
      s2[(j + 1) * (gw + 1) + i + 1] = s2[j * (gw + 1) + i + 1] + row2;
    }
  }
  const int side = 2 * radius + 1;
  const double n = side * side;
  const double sigma2 = sigma * sigma;
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int ix = x0 + x, iy = y0 + y;
      const double gx = (px(ix + 1, iy - 1) + 2 * px(ix + 1, iy) + px(ix + 1, iy + 1)) -
                        (px(ix - 1, iy - 1) + 2 * px(ix - 1, iy) + px(ix - 1, iy + 1));
      const double gy = (px(ix - 1, iy + 1) + 2 * px(ix, iy + 1) + px(ix + 1, iy + 1)) -
                        (px(ix - 1, iy - 1) + 2 * px(ix, iy - 1) + px(ix + 1, iy - 1));
      // Window [x, x + side) in the grown grid is centred on (x, y) of the region.
      auto sum = [&](const std::vector<double>& t) {
        return t[(y + side) * (gw + 1) + x + side] - t[y * (gw + 1) + x + side] -
               t[(y + side) * (gw + 1) + x] + t[y * (gw + 1) + x];
      };
      const double mean = sum(s) / n;
      const double var = std::max(0.0, sum(s2) / n - mean * mean);
      const double norm = std::sqrt(64.0 * var + sigma2);
      out.gx[y * width + x] = static_cast<float>(gx / norm);
      out.gy[y * width + x] = static_cast<float>(gy / norm);
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
      boost_(std::move(ori_boost_net)),
      ori_(std::move(ori_net)) {
  if (boost_.classes() != 2 || ori_.classes() != 3) {
    throw Error("robot orientation: OriBoostNet must give 2 classes and OriNet 3");
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
LineHypothesis refineLine(const LineHypothesis& line, const std::vector<Eigen::Vector2d>& points,
                          double vote_distance, double vote_margin) {
  const Eigen::Vector2d u = line.direction();
  const Eigen::Vector2d n(-u.y(), u.x());
  const double len = line.length();
  std::vector<Eigen::Vector2d> in;
  for (const auto& q : points) {
    const double t = (q - line.a).dot(u);
    if (std::abs((q - line.a).dot(n)) <= vote_distance && t >= -vote_margin && t <= len + vote_margin) {
      in.push_back(q);
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
  const CnsImage cns = contrastNormalizedSobel(image, x_left, y_top, x_right - x_left,
                                               y_bottom - y_top, p.variance_radius_px,
                                               p.cns_sigma_gray);
  if (cns.width < 3 || cns.height < 3) return out;
  const int half = p.median_width_px / 2;
  float window[9];
  // Per scan line, the edges from the bottom up (the lowest row of each run of rows above the
  // threshold; a real edge answers on several rows, noise on one), at most kMaxHits.
  constexpr int kMaxHits = 4;
  struct Hit {
    int column, row;
  };
  std::vector<Hit> hits;
  std::vector<int> first_hit;  // per scan line, its first entry in `hits`
  int columns = 0;
  for (int x = cns.x0 + half; x < cns.x0 + cns.width - half; x += p.scan_step_px, ++columns) {
    first_hit.push_back(static_cast<int>(hits.size()));
    int run = 0, found = 0;
    for (int y = cns.y0 + cns.height - 2; y > cns.y0 && found < kMaxHits; --y) {
      int n = 0;
      // Bright feet above the darker carpet: the vertical response is negative there.
      for (int dx = -half; dx <= half; ++dx) window[n++] = -cns.gyAt(x + dx, y);
      std::nth_element(window, window + n / 2, window + n);
      run = window[n / 2] > p.cns_threshold ? run + 1 : 0;
      if (run == p.silhouette_min_rows) {
        hits.push_back({columns, y + p.silhouette_min_rows - 1});
        ++found;
      }
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
  // Per scan line, the lowest hit on a long chain is the lower silhouette.
  for (int c = 0; c < columns; ++c) {
    for (int i = first_hit[c]; i < first_hit[c + 1]; ++i) {
      if (chain_columns[root(i)] < min_chain) continue;
      const Eigen::Vector2d pt(cns.x0 + half + static_cast<double>(c) * p.scan_step_px + 0.5, hits[i].row + 0.5);
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
  const SilhouetteLines lines = findSilhouetteLines(out.silhouette_in_robot, bounds);
  for (auto line : {lines.first, lines.second}) {
    if (!line || line->votes < p.min_line_votes) continue;
    // Twice: the hull edge's direction is rough, the first fit's much less so.
    line = refineLine(*line, out.silhouette_in_robot, p.vote_distance_m, p.vote_margin_m);
    line = refineLine(*line, out.silhouette_in_robot, p.vote_distance_m, 0.0);
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
  ori_.classify(image, boxes, sides);
  Eigen::Vector2d position = Eigen::Vector2d::Zero();
  if (robot.position_in_robot) {
    position = *robot.position_in_robot;
  } else {
    for (const auto& q : out.silhouette_in_robot) position += q;
    position /= static_cast<double>(out.silhouette_in_robot.size());
  }
  std::vector<RobotOrientation> orientations;
  std::vector<RobotSide> classes;
  for (std::size_t i = 0; i < out.regions.size(); ++i) {
    LineRegion& r = out.regions[i];
    r.usable = usable[2 * i + 1];
    if (r.usable < params_.min_usable_confidence) continue;
    const float* s = &sides[3 * i];
    const int best = static_cast<int>(std::max_element(s, s + 3) - s);
    r.side_confidence = s[best];
    if (s[best] < params_.min_side_confidence) continue;
    r.side = static_cast<RobotSide>(best);
    orientations.push_back(
        orientationFromLine(r.line_in_robot.a, r.line_in_robot.b, *r.side, position));
    classes.push_back(*r.side);
  }
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
