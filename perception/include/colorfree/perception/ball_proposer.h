#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/high_contrast.h"
#include "colorfree/perception/ignore_regions.h"
#include "colorfree/perception/image.h"
#include "colorfree/perception/percepts.h"

namespace colorfree {

/// Parameters of the ball proposal stage (perception/params/ball_proposer.yaml).
struct BallProposerParams {
  double ball_radius_m = 0.05;      ///< the ball (SPL: 0.1 m diameter)
  /// The camera model's ball radius holds on the optical axis; off it, it is multiplied by
  /// (1 / cos of the angle off the axis) ^ off_axis_exponent (1: across, 2: along the radial line).
  double off_axis_exponent = 1.5;
  double min_radius_px = 2.4;       ///< positions where the ball would be smaller are skipped
  double max_radius_px = 90.0;      ///< positions where the ball would be larger are skipped
  /// Scan step in pixels: max(1, floor(step_fraction × expected radius)), along x and y inside
  /// every scanned window; the first position half a step in, clamped into the window, so a step
  /// wider than the window (large radii) gives one evaluation per window.
  double step_fraction = 0.5;
  /// Difference of box filters (a box-shaped DoG): the centre box has half-side
  /// inner_fraction × r, the surround box half-side outer_fraction × r; the response is the centre
  /// mean minus the surround, taken over the 3×3 grid of cells these boxes make: of the four pairs
  /// of opposite surround cells, the brightest pair's darker cell (a line through the centre lights
  /// both cells of a pair, an object beside the ball only one) or the ring's mean if larger.
  /// The winners are not refined on the pixel grid; the kept proposals are re-centred by the
  /// gradient voting below (centre_search_fraction).
  double inner_fraction = 0.65;
  double outer_fraction = 1.6;
  /// The ball's black print: the spread (brightest minus darkest mean) of the centre box's four
  /// quadrants is added to the response with this weight.
  double print_weight = 0.0;
  double min_response = 40.0;       ///< grey levels; weaker responses never become proposals
  /// Thresholds that follow the image's light (a dark hall, a soft lens: the ball is plainly
  /// visible but its contrast falls with the light). `light` is the median grey level of the
  /// looked-at part of the frame (every 4th pixel of every 4th row; the carpet, mostly). Responses
  /// count from min(min_response, light_response_fraction × light); and a 16×16 window the
  /// high-contrast stage left unmarked is scanned too when its grey-level standard deviation
  /// (every 2nd row) is at least light_contrast_fraction × light and below the high-contrast stage's
  /// own threshold in a bright frame (so: only in dark frames), grown by one window like theirs.
  double light_response_fraction = 0.0;
  double light_contrast_fraction = 0.25;
  double light_max_window_contrast = 22.0;  ///< grey levels: windows are only added below this threshold
  int per_window_count = 1;         ///< best responses kept per 16×16 window (grid cell)
  /// Two proposals closer than nms_fraction × the larger radius: only the stronger one is kept.
  double nms_fraction = 1.0;
  int max_count = 12;               ///< proposals per frame at most
  /// Of these, up to line_count slots for balls on lines: candidates scored against the second
  /// brightest opposite pair (a line lights one pair, as does the ball on it), at least
  /// line_min_response; slots they do not fill go to the others.
  int line_count = 3;
  double line_min_response = 40.0;
  /// Robots' feet: a region this many ball diameters wide and deep around the feet point is
  /// scanned too (when robot percepts exist), and its responses are multiplied by feet_boost.
  double feet_region_diameters = 3.0;
  double feet_boost = 1.5;
  /// Candidates on a detected robot's body above its feet region (its white, textured parts; no
  /// ball on the ground in front of it shows there): response × this. The body: the middle
  /// robot_body_width_fraction of the robot's box across (the box is 1.25 robot widths: 0.8 is
  /// the robot's own width), from the box's top down to the feet region. Beside the body, in the
  /// box's margins, a ball behind the robot shows in full (1: the whole box, as before).
  double robot_body_factor = 0.7;
  double robot_body_width_fraction = 0.8;
  /// The response adds texture_weight × the mean edge strength (|horizontal| + |vertical| grey
  /// level difference to the next pixel) in the centre box: the ball's print is full of edges where
  /// feet, hands, lines, marks and an overexposed carpet are flat.
  double texture_weight = 2.0;
  /// The edge density of the print falls with the ball's size: the texture term is multiplied by
  /// (radius / texture_reference_radius_px) ^ texture_scale_exponent.
  double texture_reference_radius_px = 8.0;
  double texture_scale_exponent = 0.75;
  /// Sensor noise lights every pixel's edges: the mean edge strength in the centre box counts from
  /// texture_noise_factor × n on, never below 0, where n = sqrt(max(0, s^2 - noise_free_gray^2)) is
  /// the frame's pixel noise s (pixelNoiseGray, gray levels) beyond what the texture term was tuned
  /// with (the carpet's texture and a camera's ordinary noise; independent noises' variances add).
  /// Pure Gaussian noise of deviation s gives |dx| + |dy| a mean of (4 / sqrt(pi)) s ≈ 2.26 s.
  double texture_noise_factor = 2.26;
  double noise_free_gray = 6.0;
  /// ... and responses (on lines too) count net of response_noise_factor × n / (2 a): that many
  /// deviations of the centre box's mean under the noise, a = the box's half-side in pixels (small,
  /// far balls' boxes average few pixels, and noise makes their blobs).
  double response_noise_factor = 12.0;
  /// Centring of the kept proposals: circle-centre voting by the gradients around the winner at
  /// radii (1 ± radius_tolerance) × the expected radius, within centre_search_fraction × radius;
  /// pixels with a gradient below min_gradient (grey levels per pixel) do not vote.
  double centre_search_fraction = 1.0;
  double radius_tolerance = 0.12;
  double min_gradient = 6.0;
  /// The centre is the weighted centroid (weights: votes minus the threshold) of the cells
  /// connected to the best one whose smoothed votes reach centre_ridge_fraction × the best: a ball
  /// smeared along its motion (a long exposure, a turning head) votes along a ridge the length of
  /// the smear, whose middle is the ball's centre at mid-exposure and whose best cell can be at
  /// either end. 0 (or 1): the best cell itself.
  double centre_ridge_fraction = 0.3;
  /// ... for expected radii of at least centre_ridge_min_radius_px: below, the search disc (one
  /// radius) is a few one-pixel cells, too small for a smear's ridge, and the centroid only moves a
  /// far ball's proposal by noise.
  double centre_ridge_min_radius_px = 6.0;
  /// The camera's exposure smear (CameraModel::exposureSmearPx: its own turn over the exposure)
  /// draws a ball out along it, into the surround's cells: the surround box widens by this
  /// fraction of half the smear each way, in x and in y apart (0: square whatever the smear).
  double smear_surround_fraction = 0.5;

  bool operator==(const BallProposerParams&) const = default;
  static BallProposerParams load(const std::string& path);
  static BallProposerParams loadDefault();
};

/// Ball proposals (paper 2.4): a scan (positions step_fraction × the expected radius apart) of
/// the high-contrast windows (and the regions in front of detected robots' feet) with box
/// Difference-of-Gaussians filters whose supports follow the ball's expected radius from the camera
/// model, evaluated on an integral image; the strongest responses per window survive non-maximum
/// suppression, sorted by response, capped in count; a few slots are kept for the best on-line
/// candidates (a ball lying on a line).
class BallProposer {
 public:
  explicit BallProposer(BallProposerParams params = {});
  /// `robots` may be null (no robot detector in the pipeline). `pixel_noise_gray` and
  /// `light_gray`: the frame's pixelNoiseGray(image, ignore) and frameLightGray(image, ignore) when
  /// the caller has them (the pipeline's Frame does); estimated here when absent. Throws
  /// colorfree::Error when the inputs do not match the image size.
  std::vector<BallProposal> run(const GrayView& image, const CameraModel& camera,
                                const IgnoreMask& ignore, const ContrastRegions& regions,
                                const std::vector<RobotPercept>* robots = nullptr,
                                std::optional<double> pixel_noise_gray = std::nullopt,
                                std::optional<double> light_gray = std::nullopt) const;
  const BallProposerParams& params() const { return params_; }

 private:
  BallProposerParams params_;
};

}  // namespace colorfree
