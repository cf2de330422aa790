#include "colorfree/perception/robot_proposer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

#include "colorfree/perception/error.h"
#include "colorfree/perception/noise.h"
#include "colorfree/perception/param_file.h"

namespace colorfree {

RobotProposerParams RobotProposerParams::load(const std::string& path) {
  ParamFile f(path);
  RobotProposerParams p;
  p.column_step_px = static_cast<int>(f.getInRange("column_step_px", 1, 32));
  p.min_jump_gray = f.getInRange("min_jump_gray", 1, 255);
  p.jump_ratio = f.getInRange("jump_ratio", 0, 1);
  p.noise_jump_factor = f.getInRange("noise_jump_factor", 0, 20);
  p.carpet_update_weight = f.getInRange("carpet_update_weight", 0, 1);
  p.carpet_dark_decay = f.getInRange("carpet_dark_decay", 0, 1);
  p.smooth_min_noise_gray = f.getInRange("smooth_min_noise_gray", 0, 255);
  p.smooth_width_px = static_cast<int>(f.getInRange("smooth_width_px", 1, 15));
  if (p.smooth_width_px % 2 == 0) {
    throw Error(path + ": smooth_width_px must be odd (the pixel and as many on each side)");
  }
  p.lit_band_beside_width_factor = f.getInRange("lit_band_beside_width_factor", 0, 10);
  p.lit_band_height_fraction = f.getInRange("lit_band_height_fraction", 0, 1);
  p.border_robot_min_width_factor = f.getInRange("border_robot_min_width_factor", 0, 10);
  p.border_robot_rise_width_fraction = f.getInRange("border_robot_rise_width_fraction", 0, 10);
  p.border_robot_jump_factor = f.getInRange("border_robot_jump_factor", 0, 20);
  p.max_gap_px = static_cast<int>(f.getInRange("max_gap_px", 0, 64));
  p.max_gap_height_fraction = f.getInRange("max_gap_height_fraction", 0, 1);
  p.feet_dark_height_fraction = f.getInRange("feet_dark_height_fraction", 0, 1);
  p.min_run_height_fraction = f.getInRange("min_run_height_fraction", 0, 1);
  p.min_fill_fraction = f.getInRange("min_fill_fraction", 0, 1);
  p.beside_width_factor = f.getInRange("beside_width_factor", 0, 10);
  p.border_reference_beside = f.get<bool>("border_reference_beside");
  p.line_stripe_factor = f.getInRange("line_stripe_factor", 0, 100);
  p.line_beside_width_factor = f.getInRange("line_beside_width_factor", 0, 10);
  p.knee_gap_height_fraction = f.getInRange("knee_gap_height_fraction", 0, 1);
  p.knee_min_lit_height_fraction = f.getInRange("knee_min_lit_height_fraction", 0, 1);
  p.max_knee_proposals = static_cast<int>(f.getInRange("max_knee_proposals", 0, 100));
  p.short_object_height_fraction = f.getInRange("short_object_height_fraction", 0, 1);
  p.short_object_min_height_fraction = f.getInRange("short_object_min_height_fraction", 0, 1);
  p.min_expected_height_px = f.getInRange("min_expected_height_px", 1, 1000);
  p.max_distance_carpet_diagonals = f.getInRange("max_distance_carpet_diagonals", 0, 10);
  p.join_height_fraction = f.getInRange("join_height_fraction", 0, 1);
  p.join_gap_width_fraction = f.getInRange("join_gap_width_fraction", 0, 5);
  p.min_width_fraction = f.getInRange("min_width_fraction", 0, 10);
  p.split_width_factor = f.getInRange("split_width_factor", 1, 10);
  p.defer_width_factor = f.getInRange("defer_width_factor", 1, 100);
  p.box_width_factor = f.getInRange("box_width_factor", 0.1, 10);
  p.box_height_factor = f.getInRange("box_height_factor", 0.1, 10);
  p.box_below_feet_fraction = f.getInRange("box_below_feet_fraction", 0, 1);
  p.own_body_height_fraction = f.getInRange("own_body_height_fraction", 0.1, 1);
  p.max_overlap_iou = f.getInRange("max_overlap_iou", 0, 1);
  p.max_proposals = static_cast<int>(f.getInRange("max_proposals", 0, 1000));
  p.max_held_back = static_cast<int>(f.getInRange("max_held_back", 0, 1000));
  f.finish();
  return p;
}

RobotProposerParams RobotProposerParams::loadDefault() {
  return load(defaultParamDir() + "/robot_proposer.yaml");
}

const char* robotRejectReasonName(RobotRejectReason reason) {
  switch (reason) {
    case RobotRejectReason::kRunTooShort: return "run too short";
    case RobotRejectReason::kTooNarrow: return "too narrow";
    case RobotRejectReason::kTooFar: return "too far";
    case RobotRejectReason::kAboveHorizon: return "above horizon";
    case RobotRejectReason::kOverlap: return "overlap";
    case RobotRejectReason::kTooMany: return "too many";
    case RobotRejectReason::kFieldLine:
      return "field line";
    case RobotRejectReason::kLitCarpet:
      return "lit carpet";
  }
  return "?";
}

RobotProposer::RobotProposer(RobotProposerParams params, FieldDimensions field)
    : params_(params),
      robot_height_m_(field.robot_height_m),
      robot_width_m_(field.robot_width_m),
      line_width_m_(field.line_width_m),
      carpet_diagonal_m_(2 * std::hypot(field.carpetHalfLength(), field.carpetHalfWidth())) {}

namespace {

// std::lround for a non-negative value (a library call otherwise; here per lit pixel the scan meets).
int roundPx(double v) {
  const int i = static_cast<int>(v);
  return v - i >= 0.5 ? i + 1 : i;
}

struct FeetPoint {
  int x = 0;
  int y = 0;               // first row below the run (the feet's lower edge)
  double expected_h = 0;   // expected robot height there, px
  bool knee = false;       // only a run bridging a knee gap makes it
};

struct Group {
  int first_x = 0, last_x = 0;
  std::vector<int> ys;
  double expected_h = 0;
  int last_y = 0;
  bool knee = false;  ///< holds a knee-bridged feet point
};

struct ScanConstants {
  double min_jump_gray, jump_ratio, carpet_update_weight, dark_keep;  // dark_keep: 1 - decay
  int max_gap_px;
};

// The state of a scan line's walk up a marked stretch.
struct CarpetWalk {
  double carpet, ref;
  int dark_bottom, dark_top;
  double thr;  ///< the brightness threshold at the row the walk stopped at
};

// GCC's straight-line vectoriser packs the carpet and the reference into one register here, which
// lengthens the loop's dependency chain (some 20 % of the proposer's time); the values are the same.
#if defined(__GNUC__) && !defined(__clang__)
#define CARPET_WALK_ATTRIBUTES __attribute__((noinline, optimize("no-tree-slp-vectorize")))
#else
#define CARPET_WALK_ATTRIBUTES __attribute__((noinline))
#endif

// a * b + c, rounded once where the target has FMA: the dependency chain through b is one
// instruction.
inline double mulAdd(double a, double b, double c) {
#ifdef __FMA__
  return std::fma(a, b, c);
#else
  return a * b + c;
#endif
}

// Walks a scan line up from row y over the carpet and pixels darker than the reference, to the
// first pixel brighter than the reference (returns its row; y_lo - 1 when there is none), updating
// the carpet, the reference and the last dark stretch on the way. Not inlined: in its own frame
// the loop's state stays in registers.
//   Per row: carpet += weight (v - carpet); reference = max(carpet, reference (1 - decay)). The
// walk takes two rows a step, the carpet and the reference two rows on from the step's start in
// one multiply-add and one multiply (those dependency chains are the walk's cost), the row between
// from them as well; the values differ from a row-by-row walk's by rounding only.
CARPET_WALK_ATTRIBUTES int walkCarpet(const std::uint8_t* column, std::ptrdiff_t stride, int y, int y_lo,
                                      const ScanConstants& c, CarpetWalk& walk) {
  double carpet = walk.carpet, ref = walk.ref, thr = walk.thr;
  int dark_bottom = walk.dark_bottom, dark_top = walk.dark_top;
  const double min_jump = c.min_jump_gray, jump_ratio = c.jump_ratio;
  const double weight = c.carpet_update_weight, carpet_keep = 1 - weight, keep = c.dark_keep;
  const double carpet_keep2 = carpet_keep * carpet_keep, keep_weight = carpet_keep * weight,
               keep2 = keep * keep;
  const int max_gap = c.max_gap_px;
  // Shadows are darker than the carpet, the robots' feet and legs brighter.
  const auto dark = [&](double v, double reference, double threshold, int row) {
    if (reference - v > threshold) {
      if (dark_top < 0 || dark_top - row > max_gap + 1) dark_bottom = row;
      dark_top = row;
    }
  };
  const std::uint8_t* px = column + y * stride;
  bool lit = false;
  for (; y - 1 >= y_lo; y -= 2, px -= 2 * stride) {
    const double v1 = px[0], v2 = px[-stride];
    thr = std::max(min_jump, jump_ratio * ref);
    if (v1 - ref > thr) {
      lit = true;
      break;
    }
    dark(v1, ref, thr, y);
    const double carpet1 = mulAdd(carpet_keep, carpet, weight * v1);
    const double ref1 = std::max(carpet1, ref * keep);
    const double thr2 = std::max(min_jump, jump_ratio * ref1);
    if (v2 - ref1 > thr2) {
      carpet = carpet1;
      ref = ref1;
      thr = thr2;
      --y;
      lit = true;
      break;
    }
    dark(v2, ref1, thr2, y - 1);
    carpet = mulAdd(carpet_keep2, carpet, mulAdd(keep_weight, v1, weight * v2));
    ref = std::max(carpet, std::max(carpet1 * keep, ref * keep2));
    thr = thr2;
  }
  if (!lit && y >= y_lo) {  // the last row of an odd count
    const double v = *px;
    thr = std::max(min_jump, jump_ratio * ref);
    if (v - ref <= thr) {
      dark(v, ref, thr, y);
      carpet = mulAdd(carpet_keep, carpet, weight * v);
      ref = std::max(carpet, ref * keep);
      --y;
    }
  }
  walk.carpet = carpet;
  walk.ref = ref;
  walk.thr = thr;
  walk.dark_bottom = dark_bottom;
  walk.dark_top = dark_top;
  return y;
}

// Whether a pixel is brighter than the reference, and, unless no_side, than the carpet beside it
// to one side or the other as well (left_px to the left, right_px to the right; 0: that side is
// outside the image).
struct LitTest {
  double ref, thr;
  bool no_side;
  int left_px, right_px;
  bool operator()(const std::uint8_t* px) const {
    const double d = *px;
    return d - ref > thr && (no_side || (left_px > 0 && d - px[-left_px] > thr) ||
                             (right_px > 0 && d - px[right_px] > thr));
  }
};

// The test with the pixels side_px to the left and right where they lie inside a row `width`
// pixels wide; none (side_px 0, or both outside): no test beside.
LitTest litTest(double ref, double thr, int x, int width, int side_px) {
  const bool left = side_px > 0 && x - side_px >= 0, right = side_px > 0 && x + side_px < width;
  return {ref, thr, !left && !right, left ? side_px : 0, right ? side_px : 0};
}

constexpr double kNoEnough = std::numeric_limits<double>::infinity();

struct RobotRun {
  int top;     ///< the run's top row
  int filled;  ///< its rows that differ from the carpet
  /// The lowest row above y that is not lit (the lit stretch at the feet ends below it); -1 when
  /// every row the run looked at is lit.
  int first_unlit;
  /// Where the run bridged a knee gap, the run's top below the gap (where the scan goes on when
  /// the run is rejected); -1: no knee gap.
  int below_knee_top = -1;
  int filled_below_knee = 0;  ///< filled rows below the knee gap (where it was bridged)
};

// The knee gap a run may bridge once (rows; 0: none), and the test of the lit stretch below it.
struct KneeGap {
  int max_rows = 0;
  int min_lit_rows = 0;           ///< the lit stretch at the run's lower end at least this tall
  int left_px = 0, right_px = 0;  ///< the columns beside it to look at (0: outside the image)
};

// Whether the lit stretch from row y up to first_unlit (exclusive) has lit pixels beside it, at
// the knee test's columns, on at most half of its rows (a robot's legs end within its width; the
// lit side of a light edge on the carpet runs on).
bool litAlone(const std::uint8_t* column, std::ptrdiff_t stride, int y, int first_unlit,
              const LitTest& lit, const KneeGap& knee) {
  const double lit_above = lit.ref + lit.thr;
  int beside = 0;
  const std::uint8_t* px = column + y * stride;
  for (int yy = y; yy > first_unlit; --yy, px -= stride) {
    beside += (knee.left_px > 0 && px[-knee.left_px] > lit_above) ||
              (knee.right_px > 0 && px[knee.right_px] > lit_above);
  }
  return 2 * beside <= y - first_unlit;
}

// The run of a robot's pixels from row y (the lowest pixel brighter than the reference) up to
// `needed` rows above the feet row; a carpet gap longer than max_gap ends it, but for one knee
// gap (see KneeGap). A pixel counts when it is lit (no_side: no test beside, as where the carpet
// is known), or darker than the carpet (legs in shade) where the carpet is known.
//   With enough_filled, the run stops at the hit that makes it that many rows, once its first
// unlit row is known: the caller then asks nothing else of it (its top, a knee gap above).
__attribute__((noinline)) RobotRun robotRun(const std::uint8_t* column, std::ptrdiff_t stride,
                                            int y, int feet_y, int needed, int max_gap,
                                            const LitTest& lit_test, double carpet,
                                            bool carpet_unknown, const KneeGap& knee,
                                            double enough_filled = kNoEnough) {
  const double thr = lit_test.thr;
  int run_top = y, gap = 0, filled = 0, first_unlit = -1;
  int gap_limit = max_gap;
  bool may_bridge = knee.max_rows > max_gap;
  RobotRun out{};
  const std::uint8_t* px = column + y * stride;
  for (int yy = y; yy >= 0 && feet_y - yy <= needed; --yy, px -= stride) {
    const double d = *px;
    const bool lit = lit_test(px);
    const bool shaded = !carpet_unknown && carpet - d > thr;
    if (!lit && first_unlit < 0) first_unlit = yy;
    if (lit || shaded) {
      if (gap_limit > max_gap) {  // the end of the knee gap
        out.below_knee_top = run_top;
        out.filled_below_knee = filled;
        gap_limit = max_gap;
      }
      ++filled;
      run_top = yy;
      gap = 0;
      if (filled >= enough_filled && first_unlit >= 0) break;
    } else if (++gap > gap_limit) {
      if (!may_bridge || first_unlit < 0 || y - first_unlit < knee.min_lit_rows ||
          !litAlone(column, stride, y, first_unlit, lit_test, knee)) {
        break;
      }
      may_bridge = false;
      gap_limit = knee.max_rows;
    }
  }
  out.top = run_top;
  out.filled = filled;
  out.first_unlit = first_unlit;
  return out;
}

// The top row of the object whose lowest pixel is at row y when it ends within `rows` rows above
// y. Its pixels differ by more than thr from the pixels beside_px to the left and right (brighter
// than one of them: the ball's white, a robot's legs; darker than both: the ball's black patches,
// a dark jersey, which keeps a robot's object going up its body); it ends where more than max_gap
// rows follow that are like the carpet beside them (a field line runs on: like its carpet).
// -1: a taller object, none to compare with beside it, or no such end in the stretch (to y_lo).
int shortObjectTop(const std::uint8_t* column, std::ptrdiff_t stride, int x, int width, int y,
                   int y_lo, int rows, int max_gap, double thr, int beside_px) {
  const bool left = beside_px > 0 && x - beside_px >= 0,
             right = beside_px > 0 && x + beside_px < width;
  if (!left && !right) return -1;
  const auto brighter = [&](const std::uint8_t* px) {
    return (left && *px - px[-beside_px] > thr) || (right && *px - px[beside_px] > thr);
  };
  const auto darker = [&](const std::uint8_t* px) {
    return (!left || px[-beside_px] - *px > thr) && (!right || px[beside_px] - *px > thr);
  };
  // Such a gap holds two neighbours of every `step`-th row: without two neutral ones there is
  // none (most objects are robots' legs: a cheap no).
  const int step = std::max(1, (max_gap + 1) / 2);
  const int last = std::max(y_lo, y - rows - max_gap - 1);
  bool pair = false;
  for (int yy = y, before = 0; yy >= last && !pair; yy -= step) {
    const std::uint8_t* px = column + yy * stride;
    const int neutral = !brighter(px) && !darker(px);
    pair = before && neutral;
    before = neutral;
  }
  if (!pair) return -1;
  int top = y, gap = 0;
  for (int yy = y; yy >= y_lo; --yy) {
    const std::uint8_t* px = column + yy * stride;
    if (brighter(px) || darker(px)) {
      if (y - yy > rows) return -1;
      top = yy;
      gap = 0;
    } else if (++gap > max_gap) {
      return top;
    }
  }
  return -1;
}

// The rows a field line line_width_m wide covers in the image with its near edge at `px` (0 where
// the ground there is not seen).
double linePx(const CameraModel& camera, const Eigen::Vector2d& px, double line_width_m) {
  const auto near = camera.pixelToGround(px);
  if (!near || near->norm() <= 0) return 0;
  const Eigen::Vector2d far = *near + near->normalized() * line_width_m;
  const auto far_px = camera.robotToPixel({far.x(), far.y(), 0});
  return far_px ? std::max(0.0, px.y() - far_px->y()) : 0;
}

// Where a field line crosses a scan line in front of shade (a robot's shadow, a farther robot's
// darker legs), the run from the line's lower edge takes the shade for legs in shade and reaches
// the robot above: a box on the line. The lit stretch from row y up to first_unlit (exclusive; -1:
// the stretch filled the whole run, legs) is such a line when more than max_gap unlit rows follow
// above it, when lit pixels lie beside_px to its left or right within 0.3 beside_px of its rows
// (a line runs on; feet end within their robot's width), and when it is no taller than
// max_stripe_px() (line_stripe_factor field-line widths seen there; asked for last: two
// projections). Returns the row above the line, where the scan goes on; -1 when it is no line.
template <typename MaxStripePx>
int rowAboveLine(const std::uint8_t* column, std::ptrdiff_t stride, int x, int width, int y,
                 int first_unlit, int y_lo, int y_hi, const LitTest& lit, int beside_px,
                 int max_gap, const MaxStripePx& max_stripe_px) {
  if (first_unlit < y_lo) return -1;
  const int stripe_top = first_unlit + 1;
  int unlit = 0;
  for (int yy = first_unlit; yy >= y_lo && unlit <= max_gap && !lit(column + yy * stride); --yy) {
    ++unlit;
  }
  if (unlit <= max_gap) return -1;
  const int slack = static_cast<int>(0.3 * beside_px + 0.5);
  bool beside = false;
  for (int dx : {-beside_px, beside_px}) {
    if (x + dx < 0 || x + dx >= width) continue;
    for (int r = std::max(y_lo, stripe_top - slack); r <= std::min(y_hi, y + slack) && !beside;
         ++r) {
      beside = column[r * stride + dx] - lit.ref > lit.thr;
    }
  }
  return beside && y + 1 - stripe_top <= max_stripe_px() ? stripe_top - 1 : -1;
}

// Each row's pixels averaged over `width` neighbours (the window shrinks at the row's ends),
// rounded; integer arithmetic, vectorised along the row.
GrayImage horizontalMean(const GrayView& image, int width) {
  GrayImage out(image.width, image.height);
  const int n = image.width, half = width / 2;
  // acc × scale / 65536 is acc / width for every sum of `width` pixels (at most 15 × 255).
  const std::uint32_t scale = (65536u + static_cast<std::uint32_t>(width) - 1) / width;
  std::vector<std::uint16_t> acc(static_cast<std::size_t>(n));
  for (int y = 0; y < image.height; ++y) {
    const std::uint8_t* in = image.row(y);
    std::uint8_t* o = out.data() + static_cast<std::size_t>(y) * n;
    std::fill(acc.begin(), acc.end(), 0);
    for (int k = -half; k <= half; ++k) {
      const int lo = std::max(0, -k), hi = std::min(n, n - k);
      for (int x = lo; x < hi; ++x) acc[x] = static_cast<std::uint16_t>(acc[x] + in[x + k]);
    }
    const int inner_lo = std::min(half, n), inner_hi = std::max(inner_lo, n - half);
    for (int x = inner_lo; x < inner_hi; ++x) {
      o[x] = static_cast<std::uint8_t>((acc[x] * scale + 32768u) >> 16);
    }
    // The row's two ends, where the window is cut short.
    const auto cut_short = [&](int from, int to) {
      for (int x = from; x < to; ++x) {
        const int count = std::min(n - 1, x + half) - std::max(0, x - half) + 1;
        o[x] = static_cast<std::uint8_t>((acc[x] + count / 2) / count);
      }
    };
    cut_short(0, inner_lo);
    cut_short(inner_hi, n);
  }
  return out;
}

// The proposal box of a robot `h` pixels tall whose feet are at feet_px.
RobotProposal proposalAt(const RobotProposerParams& p, double width_per_height,
                         const Eigen::Vector2d& feet_px, double h) {
  RobotProposal rp;
  rp.feet_px = feet_px;
  const double bw = p.box_width_factor * (h * width_per_height);
  rp.box.x0 = feet_px.x() - bw / 2;
  rp.box.x1 = feet_px.x() + bw / 2;
  rp.box.y1 = feet_px.y() + p.box_below_feet_fraction * h;
  rp.box.y0 = rp.box.y1 - p.box_height_factor * h;
  return rp;
}

// Robots nearer than the lowest ground row the image shows (their feet below it, the lower border
// across their body): spans of the image's lowest row, on every column_step_px-th column, brighter
// than the carpet beside them by border_robot_jump_factor jumps (min_jump, jump_ratio), gaps up to
// join_gap_width_fraction of a robot's width, at least min_fill_fraction of them bright, wider than
// border_robot_min_width_factor robots standing on that row, and unlike that carpet
// border_robot_rise_width_fraction robot widths up too (a field line along the border ends lower).
// Each is proposed as a robot whose box is as wide as the span, its feet below the image where a
// robot is that wide. Only where the image's own border is the lowest row looked at (no own body).
std::vector<RobotProposal> borderRobots(const GrayView& image, const IgnoreMask& ignore,
                                        const CameraModel& camera, const RobotProposerParams& p,
                                        double robot_height_m, double width_per_height,
                                        double min_jump) {
  std::vector<RobotProposal> out;
  if (p.border_robot_min_width_factor <= 0) return out;
  const int step = p.column_step_px, yb = image.height - 1;
  const auto widthAt = [&](double x, double y) -> std::optional<double> {
    const auto h = camera.robotHeightPx({x, y}, robot_height_m);
    if (!h) return std::nullopt;
    return *h * width_per_height;
  };
  const auto at = [&](int x, int y) { return static_cast<double>(image.row(y)[x]); };
  int first = -1, last = -1, bright = 0;  // the span's first and last bright column, their count
  double max_gap = 0;
  const auto endSpan = [&] {
    if (first < 0) return;
    const double x0 = first, x1 = last + step, cx = (x0 + x1) / 2, wide = x1 - x0;
    first = -1;
    const auto w_border = widthAt(cx, image.height);
    if (bright * step < p.min_fill_fraction * wide || !w_border ||
        wide < p.border_robot_min_width_factor * *w_border) {
      return;
    }
    // The feet row where a robot's box is as wide as the span: between the lowest row and where a
    // robot's head leaves the camera's front (nearer robots there are wider).
    const double w_needed = wide / p.box_width_factor;
    double lo = image.height, hi = 8.0 * image.height;
    std::optional<double> w_hi = widthAt(cx, hi);
    while (!w_hi && hi - lo > 1) {
      hi = (lo + hi) / 2;
      w_hi = widthAt(cx, hi);
    }
    if (!w_hi || *w_hi < w_needed) return;
    // (hi stays a row with a width at least w_needed; a row without one counts as too narrow.)
    while (hi - lo > 0.5) {
      const double mid = (lo + hi) / 2;
      const auto w_mid = widthAt(cx, mid);
      if (w_mid && *w_mid >= w_needed) {
        hi = mid;
        w_hi = w_mid;
      } else {
        lo = mid;
      }
    }
    out.push_back(proposalAt(p, width_per_height, {cx, hi}, *w_hi / width_per_height));
  };
  // A robot's width on the lowest row, taken every 16 px (it varies slowly).
  std::optional<double> w;
  for (int x = step / 2, w_next = 0; x < image.width; x += step) {
    if (x >= w_next) {
      w = widthAt(x + 0.5, image.height);
      w_next = x + 16;
    }
    bool robot = false;
    if (w && ignore.bottom_y[x] == image.height) {
      const int side = roundPx(p.beside_width_factor * *w);
      const int rise = roundPx(p.border_robot_rise_width_fraction * *w);
      // The carpet beside: the lower median of the pixels one to three robot widths to the left
      // and right (a near robot is wider than one: some of them lie on it).
      double beside[6];
      int n = 0;
      for (int k = 1; k <= 3 && side > 0; ++k) {
        for (const int xs : {x - k * side, x + k * side}) {
          if (xs >= 0 && xs < image.width && ignore.looked(xs, yb)) {
            beside[n++] = at(xs, yb);
          }
        }
      }
      const double v = at(x, yb);
      double ref = v;
      if (n > 0) {
        std::nth_element(beside, beside + (n - 1) / 2, beside + n);
        ref = std::min(v, beside[(n - 1) / 2]);
      }
      const double thr = std::max(min_jump, p.jump_ratio * ref);
      robot = v - ref > p.border_robot_jump_factor * thr && yb - rise >= ignore.top_y[x] &&
              std::abs(at(x, yb - rise) - ref) > thr;
    }
    if (first >= 0 && x - last > max_gap) endSpan();
    if (robot) {
      if (first < 0) {
        first = x;
        bright = 0;
      }
      last = x;
      ++bright;
      max_gap = std::max(2.0 * step, p.join_gap_width_fraction * *w);
    }
  }
  endSpan();
  return out;
}

// A kept box whose feet point lies in the lower part of a nearer box kept after it, in the
// proposals [behind_from, behind_to) (boxes behind a still nearer one come after the free-standing
// ones), is held back behind it, as it would have been had the nearer box come first. A held-back
// candidate that stood behind such a box stands behind those of that box's nearer boxes it lies
// in the lower part of, or, with none, is a proposal, as it would have been (then one or two more
// proposals than max_proposals may reach RobotNet).
void holdBackBehindLaterNearer(RobotProposals& out, int behind_from, int behind_to,
                               double lower_part_fraction) {
  const int n = static_cast<int>(out.proposals.size());
  std::vector<int> order(n);
  for (int i = 0; i < n; ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return out.proposals[a].feet_px.y() > out.proposals[b].feet_px.y();
  });
  std::vector<std::vector<int>> nearer(n);
  std::vector<bool> held(n, false);
  for (int i : order) {
    for (int j = std::max(i + 1, behind_from); j < behind_to; ++j) {
      if (!held[j] &&
          feetInLowerPart(out.proposals[i].feet_px, out.proposals[j], lower_part_fraction)) {
        nearer[i].push_back(j);
      }
    }
    held[i] = !nearer[i].empty();
  }
  if (std::none_of(held.begin(), held.end(), [](bool h) { return h; })) return;
  std::vector<int> index(n, -1);
  std::vector<RobotProposal> kept;
  for (int i = 0; i < n; ++i) {
    if (held[i]) continue;
    index[i] = static_cast<int>(kept.size());
    kept.push_back(out.proposals[i]);
  }
  std::vector<HeldBackRobotProposal> held_back;
  for (HeldBackRobotProposal& h : out.held_back) {
    std::vector<int> now;
    for (int k : h.nearer) {
      for (int m : held[k] ? nearer[k] : std::vector<int>{k}) {
        if ((m == k ||
             feetInLowerPart(h.proposal.feet_px, out.proposals[m], lower_part_fraction)) &&
            std::find(now.begin(), now.end(), index[m]) == now.end()) {
          now.push_back(index[m]);
        }
      }
    }
    if (now.empty()) {
      kept.push_back(h.proposal);
    } else {
      held_back.push_back({h.proposal, now});
    }
  }
  for (int i = 0; i < n; ++i) {
    if (!held[i]) continue;
    std::vector<int> now;
    for (int m : nearer[i]) now.push_back(index[m]);
    held_back.push_back({out.proposals[i], now});
  }
  out.proposals = std::move(kept);
  out.held_back = std::move(held_back);
}

}  // namespace

RobotProposals RobotProposer::run(const GrayView& input, const CameraModel& camera,
                                  const IgnoreMask& ignore, const ContrastRegions& regions,
                                  bool keep_rejected,
                                  std::optional<double> pixel_noise_gray) const {
  if (input.empty()) throw Error("robot proposer: empty image");
  if (ignore.width != input.width || ignore.height != input.height) {
    throw Error("robot proposer: ignore mask size does not match the image");
  }
  const RobotProposerParams& p = params_;
  RobotProposals out;
  const int win = regions.window_px;
  const double width_per_height = robot_width_m_ / robot_height_m_;

  // (knee_feet: those only a bridged run makes; upper_feet: those above a short object)
  std::vector<FeetPoint> feet, knee_feet, upper_feet;
  const int step = p.column_step_px;
  // The frame's noise raises the jump (each scan pixel is compared on its own).
  double noise = 0;
  if (p.noise_jump_factor > 0 || p.smooth_min_noise_gray > 0) {
    noise = pixel_noise_gray ? *pixel_noise_gray : pixelNoiseGray(input, ignore);
  }
  // A noisy frame (a dark hall's high gain) is scanned on a copy whose rows are averaged over
  // smooth_width_px pixels: the noise falls by its square root, a robot's legs (wider than that)
  // keep their brightness.
  GrayImage smoothed;
  GrayView image = input;
  if (p.smooth_min_noise_gray > 0 && noise >= p.smooth_min_noise_gray && p.smooth_width_px > 1) {
    smoothed = horizontalMean(input, p.smooth_width_px);
    image = smoothed.view();
    noise /= std::sqrt(static_cast<double>(p.smooth_width_px));
  }
  const double min_jump = p.noise_jump_factor > 0
                              ? std::max(p.min_jump_gray, p.noise_jump_factor * noise)
                              : p.min_jump_gray;
  const ScanConstants scan{min_jump, p.jump_ratio, p.carpet_update_weight,
                           1 - p.carpet_dark_decay, p.max_gap_px};
  const std::ptrdiff_t stride = image.stride;
  // The marked vertical stretches of a window column, bottom up (window rows, top and bottom).
  std::vector<std::pair<int, int>> stretches;
  for (int wc = 0; wc < regions.columns; ++wc) {
    stretches.clear();
    for (int r = regions.rows - 1; r >= 0; --r) {
      if (!regions.marked(wc, r)) continue;
      int r_top = r;
      while (r_top - 1 >= 0 && regions.marked(wc, r_top - 1)) --r_top;
      stretches.emplace_back(r_top, r);
      r = r_top;
    }
    if (stretches.empty()) continue;
    const int x_end = std::min(image.width, (wc + 1) * win);
    for (int x = wc * win + step / 2; x < x_end; x += step) {
      const int top = ignore.top_y[x];
      const int bottom = ignore.bottom_y[x];
      // Those up to the row of the lower edge (the image's or the own body's) at this column.
      const int r_bottom = std::min(regions.rows - 1, (bottom - 1) / win);
      for (const auto& [r_top, r_last] : stretches) {
        if (r_top > r_bottom) continue;
        const int r = std::min(r_last, r_bottom);
        const int y_hi = std::min(bottom - 1, (r + 1) * win - 1);
        const int y_lo = std::max(top, r_top * win);
        if (y_hi - y_lo < 2) continue;
        const std::uint8_t* const column = image.data + x;
        double carpet = column[y_hi * stride];
        // A stretch starting at the lower edge of the image (or of the own body) starts on
        // whatever is there: its "carpet" may be an object (the ball cut by the border, its lit
        // black patches), against which the real carpet above would count as a robot's legs in
        // shade. There only pixels brighter than the reference fill a robot's run.
        const bool carpet_unknown = y_hi == bottom - 1;
        if (carpet_unknown && p.border_reference_beside) {
          // The reference starts at the darkest of its pixel and of those beside_width_factor
          // robot widths to its left and right (inside the field, outside the own body): a robot
          // cut by the border starts brighter than the carpet beside it, and its run starts at
          // the border (README robot19).
          if (const auto h = camera.robotHeightPx({x + 0.5, y_hi + 1.0}, robot_height_m_)) {
            const int side = roundPx(p.beside_width_factor * *h * width_per_height);
            for (const int xs : {x - side, x + side}) {
              if (side > 0 && xs >= 0 && xs < image.width && ignore.looked(xs, y_hi)) {
                carpet = std::min(carpet, static_cast<double>(image.row(y_hi)[xs]));
              }
            }
          }
        }
        // The reference the robot must be brighter than: the running carpet luminance, but after
        // a darker stretch (a shadow, the ball's black patches) it falls back to it only by
        // carpet_dark_decay per row, so the carpet after a short dark stretch is no robot.
        double ref = carpet;
        // The stretch of pixels darker than the reference the scan passed last (rows, bottom
        // and top; -1: none): the feet's dark side panels, or the contact shadow under them.
        int dark_bottom = -1, dark_top = -1;
        bool above_short = false;  // the scan went on above a short object's feet point
        int y = y_hi;
        while (y >= y_lo) {
          // Walk up over the carpet (and darker pixels) to the next brighter pixel.
          CarpetWalk walk{carpet, ref, dark_bottom, dark_top, 0};
          y = walkCarpet(column, stride, y, y_lo, scan, walk);
          carpet = walk.carpet;
          ref = walk.ref;
          dark_bottom = walk.dark_bottom;
          dark_top = walk.dark_top;
          const double thr = walk.thr;
          if (y < y_lo) break;
          int feet_y = y + 1;
          const Eigen::Vector2d feet_px(x + 0.5, feet_y);
          const auto expected = camera.robotHeightPx(feet_px, robot_height_m_);
          if (!expected) {
            if (keep_rejected) out.rejected.push_back({feet_px, RobotRejectReason::kAboveHorizon});
            break;
          }
          const int needed = static_cast<int>(std::ceil(p.min_run_height_fraction * *expected));
          // Above the feet, most pixels up to the needed height must differ from the carpet
          // (a robot's legs, with gaps at the joints). Only the run that starts at the feet
          // counts: a gap of carpet longer than a joint ends it, so a field line below a robot
          // does not borrow the robot's pixels above the carpet between them.
          const int max_gap =
              std::max(p.max_gap_px, static_cast<int>(p.max_gap_height_fraction * *expected));
          // Where the stretch starts at the lower edge the carpet is unknown, and a pixel
          // brighter than the reference is a robot's only where it is brighter than the carpet
          // beside it as well: the carpet above a ball cut by the border is no robot.
          const int side_px = carpet_unknown
                                  ? roundPx(p.beside_width_factor * *expected * width_per_height)
                                  : 0;
          const LitTest lit = litTest(ref, thr, x, image.width, side_px);
          // How far beside a lit stretch a field line would still be lit (the line and knee tests).
          const int line_beside_px =
              roundPx(p.line_beside_width_factor * *expected * width_per_height);
          KneeGap knee;
          if (p.knee_gap_height_fraction > 0) {
            knee.max_rows = static_cast<int>(p.knee_gap_height_fraction * *expected);
            knee.min_lit_rows =
                static_cast<int>(std::ceil(p.knee_min_lit_height_fraction * *expected));
            knee.left_px = x - line_beside_px >= 0 ? line_beside_px : 0;
            knee.right_px = x + line_beside_px < image.width ? line_beside_px : 0;
          }
          // (A run long enough to be accepted is looked at no further, but where its expected
          // height is too small: then its top is where the scan goes on.)
          const RobotRun run = robotRun(column, stride, y, feet_y, needed, max_gap, lit, carpet,
                                        carpet_unknown, knee,
                                        *expected < p.min_expected_height_px
                                            ? kNoEnough
                                            : p.min_fill_fraction * needed);
          const int run_top = run.top, filled = run.filled;
          // Where only the bridged run makes a feet point, with knee candidates apart, the point
          // goes to them and the scan goes on as it would without the gap.
          const bool knee_apart = p.max_knee_proposals > 0 && run.below_knee_top >= 0 &&
                                  run.filled_below_knee < p.min_fill_fraction * needed;
          if (*expected < p.min_expected_height_px) {
            if (keep_rejected) out.rejected.push_back({feet_px, RobotRejectReason::kTooFar});
          } else if (filled >= p.min_fill_fraction * needed) {
            const int above_line =
                p.line_stripe_factor > 0
                    ? rowAboveLine(column, stride, x, image.width, y, run.first_unlit, y_lo, y_hi,
                                   lit, line_beside_px, max_gap,
                                   [&] {
                                     return p.line_stripe_factor *
                                            linePx(camera, feet_px, line_width_m_);
                                   })
                    : -1;
            if (above_line >= 0 && !knee_apart) {
              if (keep_rejected) out.rejected.push_back({feet_px, RobotRejectReason::kFieldLine});
              y = above_line;
              continue;
            }
            // Lit carpet (uneven light): the scan goes on above its lower edge.
            if (above_line < 0 && lit.no_side && p.lit_band_beside_width_factor > 0) {
              const int band_px =
                  roundPx(p.lit_band_beside_width_factor * *expected * width_per_height);
              const LitTest lit_beside = litTest(ref, thr, x, image.width, band_px);
              const int band_needed =
                  std::max(1, static_cast<int>(p.lit_band_height_fraction * needed));
              // (Nothing beside inside the image: no test.)
              if (!lit_beside.no_side) {
                const auto band = [&](int from) {
                  return robotRun(column, stride, from, from + 1, band_needed, max_gap, lit_beside,
                                  carpet, carpet_unknown, KneeGap{});
                };
                const auto lit_carpet = [&](const RobotRun& run) {
                  return run.filled < p.min_fill_fraction * band_needed;
                };
                // A field line along the lit carpet's lower edge is brighter than the lit carpet
                // beside it: there the band starts above the line, a stripe of rows lit beside
                // no taller than line_stripe_factor line widths (asked for last: two projections).
                const RobotRun at_feet = band(y);
                const int stripe_top = at_feet.first_unlit;
                int band_y = -1;
                if (lit_carpet(at_feet)) {
                  band_y = y;
                } else if (p.line_stripe_factor > 0 && stripe_top > y_lo && stripe_top < y &&
                           lit_carpet(band(stripe_top)) &&
                           y - stripe_top <=
                               p.line_stripe_factor * linePx(camera, feet_px, line_width_m_)) {
                  band_y = stripe_top;
                }
                if (band_y >= 0) {
                  if (keep_rejected) {
                    out.rejected.push_back({feet_px, RobotRejectReason::kLitCarpet});
                  }
                  // The reference is the band's own lowest pixel, which the walk then takes for
                  // carpet (it is not brighter than itself by the jump): the scan moves on and
                  // never looks at this run again.
                  y = band_y;
                  carpet = ref = column[y * stride];
                  dark_bottom = dark_top = -1;
                  continue;
                }
              }
            }
            if (above_line < 0) {
              // A dark stretch just below the bright feet (a joint's gap away at most) and no
              // taller than a foot is the feet's dark lower part or their contact shadow: the
              // robot stands at its bottom. (The darker reference after it hides those rows
              // from the brightness test; the orientation stage's feet region hangs from this
              // row.)
              if (dark_top >= 0 && dark_top - y <= p.max_gap_px + 1 &&
                  dark_bottom + 1 - feet_y <= p.feet_dark_height_fraction * *expected) {
                feet_y = dark_bottom + 1;
              }
              (knee_apart    ? knee_feet
               : above_short ? upper_feet
                             : feet)
                  .push_back({x, feet_y, *expected, knee_apart});
              out.feet_points_px.push_back({x + 0.5, static_cast<double>(feet_y)});
              if (!knee_apart) {
                // One robot per scan line stretch, the lowest, unless its object ends low (the
                // ball in front of a robot): then the scan goes on above it.
                const int top =
                    p.short_object_height_fraction > 0
                        ? shortObjectTop(column, stride, x, image.width, y, y_lo,
                                         static_cast<int>(
                                             std::ceil(p.short_object_height_fraction * *expected)),
                                         max_gap, thr,
                                         roundPx(p.beside_width_factor * *expected *
                                                 width_per_height))
                        : -1;
                if (top < 0 || feet_y - top < p.short_object_min_height_fraction * *expected) break;
                y = top - 1;
                ref = carpet;
                dark_bottom = dark_top = -1;
                above_short = true;
                continue;
              }
            }
            // (Without the gap the run was too short.)
            if (keep_rejected) out.rejected.push_back({feet_px, RobotRejectReason::kRunTooShort});
          } else if (keep_rejected) {
            out.rejected.push_back({feet_px, RobotRejectReason::kRunTooShort});
          }
          // A rejected run goes on from below its knee gap, as it would without the gap.
          y = (run.below_knee_top >= 0 ? run.below_knee_top : run_top) - 1;
        }
      }
    }
  }

  const double max_distance_m = p.max_distance_carpet_diagonals * carpet_diagonal_m_;
  struct Candidate {
    RobotProposal proposal;
    double expected_h;
  };
  // Join feet points of neighbouring scan lines (sorted by x) into groups, and the groups wide
  // enough for a robot (knee_only: and holding a knee-bridged point) into candidates.
  const auto candidatesOf = [&](const std::vector<FeetPoint>& points, bool knee_only) {
    std::vector<Group> groups;
    std::vector<int> open;
    const auto max_join_gap = [&](const Group& g) {
      return std::max(2.0 * step, p.join_gap_width_fraction * g.expected_h * width_per_height);
    };
    for (const FeetPoint& f : points) {
      int best = -1;
      double best_dy = 0;
      for (int gi : open) {
        Group& g = groups[gi];
        if (g.last_x < f.x - max_join_gap(g) || g.last_x == f.x) continue;
        const double tol = p.join_height_fraction * g.expected_h + 2;
        const double dy = std::abs(f.y - g.last_y);
        if (dy <= tol && (best < 0 || dy < best_dy)) {
          best = gi;
          best_dy = dy;
        }
      }
      if (best < 0) {
        groups.push_back({f.x, f.x, {f.y}, f.expected_h, f.y, f.knee});
        open.push_back(static_cast<int>(groups.size()) - 1);
      } else {
        Group& g = groups[best];
        g.last_x = f.x;
        g.last_y = f.y;
        g.ys.push_back(f.y);
        g.knee |= f.knee;
        g.expected_h = std::max(g.expected_h, f.expected_h);
      }
      open.erase(std::remove_if(open.begin(), open.end(),
                                [&](int gi) { return groups[gi].last_x < f.x - max_join_gap(groups[gi]); }),
                 open.end());
    }
    std::vector<Candidate> candidates;
    for (Group& g : groups) {
      if (knee_only && !g.knee) continue;
      std::nth_element(g.ys.begin(), g.ys.begin() + g.ys.size() / 2, g.ys.end());
      const int feet_y = g.ys[g.ys.size() / 2];
      const double cx = (g.first_x + g.last_x + 1) / 2.0;
      const auto h = camera.robotHeightPx({cx, static_cast<double>(feet_y)}, robot_height_m_);
      if (!h) continue;
      // Off the carpet: one ground point per group (the scan checks each feet point only by its
      // expected robot height, min_expected_height_px).
      if (max_distance_m > 0) {
        const auto ground = camera.pixelToGround({cx, static_cast<double>(feet_y)});
        if (!ground || ground->norm() > max_distance_m) {
          if (keep_rejected)
            out.rejected.push_back({{cx, double(feet_y)}, RobotRejectReason::kTooFar});
          continue;
        }
      }
      const double w_expected = *h * width_per_height;
      const double w = g.last_x - g.first_x + step;
      if (w < p.min_width_fraction * w_expected) {
        if (keep_rejected) out.rejected.push_back({{cx, double(feet_y)}, RobotRejectReason::kTooNarrow});
        continue;
      }
      const int n = w > p.split_width_factor * w_expected
                        ? std::max(1, roundPx(w / w_expected))
                        : 1;
      for (int i = 0; i < n; ++i) {
        RobotProposal rp =
            proposalAt(p, width_per_height, {g.first_x + (i + 0.5) * w / n, double(feet_y)}, *h);
        rp.wide_group = w > p.defer_width_factor * w_expected;
        candidates.push_back({rp, *h});
      }
    }
    // Lower in the image first (nearer robots hide the ones behind).
    std::stable_sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
      return a.proposal.feet_px.y() > b.proposal.feet_px.y();
    });
    return candidates;
  };
  const std::vector<Candidate> candidates = candidatesOf(feet, false);
  // Robots nearer than the lowest ground row the image shows: they come last (below).
  const std::vector<RobotProposal> border =
      borderRobots(image, ignore, camera, p, robot_height_m_, width_per_height, min_jump);
  // A candidate overlapping a kept one by more than max_overlap_iou is dropped. One whose feet
  // point lies inside the lower part of nearer robots' boxes is their knee, hip or hand, or a
  // robot beside or behind them: it is held back for the detector, which classifies it only when
  // none of those nearer boxes holds a robot. One inside the upper part of a nearer box is a
  // farther robot's, or the nearer robot's shoulder or arm: it comes after every free-standing
  // candidate, so near robots' arms do not take the places of far robots under the cap.
  enum class Fit { kFree, kBehind, kHeldBack, kOverlap };
  // (fit's: the nearer boxes whose lower part holds the feet point; those it stands behind above
  // it)
  std::vector<int> nearer, behind_of;
  // A knee candidate (knee: true) overlaps only boxes standing about as low as it does: a box
  // higher up is the same robot's without the gap, its feet at the knees, and RobotNet decides.
  const auto overlaps = [&](const RobotProposal& kept, const Candidate& c, bool knee) {
    return boxIou(kept.box, c.proposal.box) > p.max_overlap_iou &&
           (!knee || kept.feet_px.y() >=
                         c.proposal.feet_px.y() - (p.join_height_fraction * c.expected_h + 2));
  };
  const auto fit = [&](const Candidate& c, bool knee) {
    Fit result = Fit::kFree;
    nearer.clear();
    behind_of.clear();
    for (std::size_t k = 0; k < out.proposals.size(); ++k) {
      const RobotProposal& kept = out.proposals[k];
      const Eigen::Vector2d& f = c.proposal.feet_px;
      const bool in_column = f.x() > kept.box.x0 && f.x() < kept.box.x1;
      const bool below_top = f.y() < kept.feet_px.y() - 0.1 * kept.box.height();
      if (overlaps(kept, c, knee)) return Fit::kOverlap;
      if (feetInLowerPart(f, kept, p.own_body_height_fraction)) {
        nearer.push_back(static_cast<int>(k));
      } else if (in_column && below_top && f.y() > kept.box.y0) {
        result = Fit::kBehind;
        behind_of.push_back(static_cast<int>(k));
      }
    }
    return nearer.empty() ? result : Fit::kHeldBack;
  };
  std::vector<const Candidate*> behind, wide;
  const auto keep = [&](const Candidate& c, bool may_defer) {
    const Fit f = fit(c, false);
    if (f == Fit::kBehind && may_defer) {
      behind.push_back(&c);
      return;
    }
    if (f == Fit::kHeldBack && static_cast<int>(out.held_back.size()) < p.max_held_back) {
      out.held_back.push_back({c.proposal, nearer});
      return;
    }
    if (f == Fit::kOverlap || f == Fit::kHeldBack ||
        static_cast<int>(out.proposals.size()) >= p.max_proposals) {
      if (keep_rejected) {
        out.rejected.push_back({c.proposal.feet_px, f == Fit::kOverlap || f == Fit::kHeldBack
                                                        ? RobotRejectReason::kOverlap
                                                        : RobotRejectReason::kTooMany});
      }
      return;
    }
    out.proposals.push_back(c.proposal);
  };
  // Free-standing candidates, then those behind a nearer one, then the boxes of wide groups.
  for (const Candidate& c : candidates) {
    if (c.proposal.wide_group) {
      wide.push_back(&c);
    } else {
      keep(c, true);
    }
  }
  const int behind_from = static_cast<int>(out.proposals.size());
  for (const Candidate* c : behind) keep(*c, false);
  const int behind_to = static_cast<int>(out.proposals.size());
  for (const Candidate* c : wide) keep(*c, false);
  // The knee candidates: groups of all feet points that hold a knee-bridged one (a robot whose
  // feet only some scan lines reach over the knee gap is one group, not two too narrow for a
  // robot), besides the others under their own cap, held back as the others are.
  if (!knee_feet.empty()) {
    int knee_kept = 0;
    std::vector<FeetPoint> all_feet(feet.size() + knee_feet.size());
    std::merge(feet.begin(), feet.end(), knee_feet.begin(), knee_feet.end(), all_feet.begin(),
               [](const FeetPoint& a, const FeetPoint& b) { return a.x < b.x; });
    for (const Candidate& c : candidatesOf(all_feet, true)) {
      // (One overlapping a held-back candidate is that candidate again, a bridged point joined.)
      bool again = false;
      for (const HeldBackRobotProposal& h : out.held_back) again |= overlaps(h.proposal, c, true);
      const Fit f = again ? Fit::kOverlap : fit(c, true);
      if (f == Fit::kHeldBack && static_cast<int>(out.held_back.size()) < p.max_held_back) {
        out.held_back.push_back({c.proposal, nearer});
      } else if ((f == Fit::kFree || f == Fit::kBehind) && knee_kept < p.max_knee_proposals) {
        out.proposals.push_back(c.proposal);
        ++knee_kept;
      } else if (keep_rejected) {
        out.rejected.push_back({c.proposal.feet_px, f == Fit::kFree || f == Fit::kBehind
                                                        ? RobotRejectReason::kTooMany
                                                        : RobotRejectReason::kOverlap});
      }
    }
  }
  // Robots above short objects (the ball in front of them), grouped apart from the others (feet
  // points over a near robot's shaded legs would move the boxes of the robots behind it), last.
  for (const Candidate& c : candidatesOf(upper_feet, false)) {
    if (fit(c, false) != Fit::kBehind) {
      keep(c, false);
      continue;
    }
    // Above a nearer box's lower part: held back behind every box it stands behind (the short
    // object's, which RobotNet rejects, or a robot's, whose body it may be).
    if (static_cast<int>(out.held_back.size()) < p.max_held_back) {
      out.held_back.push_back({c.proposal, behind_of});
    } else if (keep_rejected) {
      out.rejected.push_back({c.proposal.feet_px, RobotRejectReason::kTooMany});
    }
  }
  holdBackBehindLaterNearer(out, behind_from, behind_to, p.own_body_height_fraction);
  // The robots whose body the lower border cuts, after all others (their boxes, reaching far below
  // the image, hold no candidate back), under the cap; one overlapping a kept box is that box's.
  for (const RobotProposal& b : border) {
    bool overlap = false;
    for (const RobotProposal& kept : out.proposals) {
      overlap |= boxIou(kept.box, b.box) > p.max_overlap_iou;
    }
    if (!overlap && static_cast<int>(out.proposals.size()) < p.max_proposals) {
      out.proposals.push_back(b);
    } else if (keep_rejected) {
      out.rejected.push_back(
          {b.feet_px, overlap ? RobotRejectReason::kOverlap : RobotRejectReason::kTooMany});
    }
  }
  return out;
}

}  // namespace colorfree
