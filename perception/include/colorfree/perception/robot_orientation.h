#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/cnn/classifier.h"
#include "colorfree/perception/field_dimensions.h"
#include "colorfree/perception/image.h"
#include "colorfree/perception/orientation/geometry.h"
#include "colorfree/perception/orientation/orientation_filter.h"
#include "colorfree/perception/percepts.h"

namespace colorfree {

/// A region of the image, clamped to it (pixels).
struct CnsRegion {
  int x0 = 0, y0 = 0, width = 0, height = 0;
};
/// Contrast-normalized Sobel of a region: each pixel's Sobel gradient divided by
/// sqrt(64 · local variance + σ²) over a (2·radius+1)² window, so a clean step edge answers about
/// 1 whatever its contrast and the lighting. Row-major, region size; gx right, gy down.
struct CnsImage : CnsRegion {
  std::vector<float> gx, gy;
  float gyAt(int x, int y) const { return gy[(y - y0) * width + (x - x0)]; }
};
CnsImage contrastNormalizedSobel(const GrayView& image, int x0, int y0, int width, int height,
                                 int variance_radius_px, double sigma_gray);

/// The lower silhouette's edge pixels of a region: 1 where minus the CNS's gy exceeds
/// `threshold` (brighter above than below), else 0; row-major, the region clamped to the image as
/// for CnsImage. The same answers as thresholding contrastNormalizedSobel's -gy, with no gx and no
/// normalizer where the Sobel alone is too weak to pass (the normalizer is never above 1/σ).
struct CnsEdgeMask : CnsRegion {
  std::vector<std::uint8_t> on;
  bool at(int x, int y) const { return on[(y - y0) * width + (x - x0)] != 0; }
};
/// variance_radius_px at most kMaxEdgeMaskRadiusPx (the window's sums are 32-bit; Error above).
constexpr int kMaxEdgeMaskRadiusPx = 6;
CnsEdgeMask brightAboveEdgeMask(const GrayView& image, int x0, int y0, int width, int height,
                                int variance_radius_px, double sigma_gray, double threshold);

/// Parameters of the orientation stage (perception/params/robot_orientation.yaml).
struct RobotOrientationParams {
  double feet_region_above_fraction = 0.22;  ///< feet region: from this fraction of the box height above the feet ...
  double feet_region_below_fraction = 0.08;  ///< ... to this fraction below them
  int scan_step_px = 1;                      ///< between vertical scan lines
  int median_width_px = 3;                   ///< horizontal median filter over the CNS response
  int variance_radius_px = 2;                ///< CNS local variance window radius (at most kMaxEdgeMaskRadiusPx)
  double cns_sigma_gray = 40;                ///< CNS noise floor
  double cns_threshold = 0.5;                ///< minus the vertical CNS (bright above dark) above this is the silhouette
  int silhouette_min_rows = 2;               ///< ... on this many rows in a row (noise answers on one)
  int silhouette_neighbour_rows_px = 2;      ///< edge points on neighbouring scan lines this close chain
  int silhouette_min_chain_px = 4;           ///< a silhouette point's chain spans at least this many scan lines ...
  double silhouette_min_chain_fraction = 0.12;  ///< ... and this fraction of the robot box's width
  /// An edge is the feet's only when the mean gray just above it is at least this many times the
  /// carpet's (the median gray of the feet region's outer columns): the feet are brighter than the
  /// carpet, a cast shadow's upper edge has only the carpet above it (0: no such test).
  double silhouette_min_above_carpet_ratio = 1.15;
  int silhouette_above_rows_px = 3;  ///< px above an edge whose mean gray is its "above" value
  /// A back view's heels: a dark panel above the ground, the white shoe above it. Where a
  /// silhouette edge has, within two rows below it, a stretch whose 3-px mean is darker than
  /// dark_panel_max_gray_ratio × the carpet's gray, between dark_panel_min_height_fraction and
  /// dark_panel_max_height_fraction of the box height tall and ending at most
  /// dark_panel_below_feet_fraction of it below the feet point, on at least
  /// dark_panel_min_chain_share of its chain's points, the edge is the panel's upper edge: the
  /// points move to the stretch's lower end, the ground (a contact shadow is thinner, a cast
  /// shadow runs on). The line regions still hang from the upper edge (the nets' training). 0: off.
  double dark_panel_max_gray_ratio = 0.7;
  double dark_panel_min_height_fraction = 0.045;
  double dark_panel_max_height_fraction = 0.1;
  double dark_panel_below_feet_fraction = 0.03;
  double dark_panel_min_chain_share = 0.7;
  /// An edge with such a panel right below it needs only this many rows above the threshold (at
  /// most silhouette_min_rows): a heel's thin white rim over the panel answers on one.
  int dark_panel_edge_min_rows = 1;
  double vote_distance_m = 0.012;            ///< line voting: a point this close to the line votes ...
  double vote_margin_m = 0.3;                ///< ... when it projects within this of the hull edge's ends
  double second_line_min_length_m = 0.04;
  double second_line_max_length_m = 0.25;
  double second_line_max_cos = 0.35;
  double second_line_max_refined_cos = 0.25;  ///< the same bound after both lines are refitted
  double min_line_votes = 6;                 ///< a line with fewer votes is not classified
  /// A line's voters further apart than this along it are two pieces; only the one with the most
  /// voters votes and is refitted (0: no limit)
  double line_max_voter_gap_m = 0.1;
  /// A line whose middle lies farther than this from the feet point's ground position is not the
  /// feet's edge (0: no limit)
  double line_max_feet_distance_m = 0.3;
  /// A detected field line or centre circle in the feet region (a line at least
  /// field_line_min_length_m long on the ground; crossing the line of sight to the robot at
  /// field_line_min_angle_deg or more near the feet) has a bright-above-dark lower edge like the
  /// feet's: silhouette edges whose ground point lies within the line's half width, grown by
  /// field_line_margin_px pixels' depth on the ground, of its middle (a straight line's extended
  /// as far beyond its ends) are dropped, so the feet above it are the silhouette there (0: off).
  double field_line_margin_px = 2;
  double field_line_min_length_m = 0.5;
  double field_line_min_angle_deg = 30;
  /// ... but on a robot box at least field_line_sole_min_box_height_px tall, an edge there with a
  /// thin stretch right below it darker than field_line_sole_max_gray_ratio × the carpet's gray (at
  /// most field_line_sole_max_height_fraction of the box height tall, then lighter again) is a
  /// sole's upper edge over the marking, the feet's: it stays (0: every edge on the marking is
  /// dropped). A smaller robot's sole is under a pixel: any contact shadow passes for it.
  double field_line_sole_max_gray_ratio = 0.7;
  double field_line_sole_min_box_height_px = 120;
  double field_line_sole_max_height_fraction = 0.02;
  double region_margin_fraction = 0.25;      ///< region: line width grown by this at both ends
  double region_above_fraction = 0.35;       ///< region height above the line, in robot heights
  double region_below_fraction = 0.06;       ///< below the line, in robot heights
  double min_usable_confidence = 0.35;       ///< OriBoostNet's usable probability needed
  double min_side_confidence = 0.5;          ///< OriNet's best class probability needed (its two side classes summed)
  double min_side_facing_share = 0.7;        ///< a side region's facing is known when one side class has this share of the side probability
  bool ori_net_mirrored_look = true;  ///< OriNet also looks at each region mirrored (its side
                                      ///< classes swapped): its classes are the mean of both looks
  bool keep_most_confident_of_a_class = true;  ///< regions that share a class: keep OriNet's most confident one (false: drop all, the paper's check)
  double track_max_distance_m = 0.5;         ///< association of a percept with a track
  double track_expiry_s = 1.0;               ///< a track and its estimate expire after this without samples
  int filter_buffer_size = 11;

  bool operator==(const RobotOrientationParams&) const = default;
  static RobotOrientationParams load(const std::string& path);
  static RobotOrientationParams loadDefault();
};

/// A classified region around one silhouette line (for training and drawing).
struct LineRegion {
  LineHypothesis line_in_robot;  ///< metres, observer's robot frame
  PixelBox box;
  float usable = 0;              ///< OriBoostNet's usable probability (0 when not run)
  std::optional<RobotSide> side; ///< OriNet's class when the region was usable
  float side_confidence = 0;
  /// For a side region: OriNet saw which way the robot faces along the line (its classes 2 and
  /// 3: towards the observer's left, to its right), and `faces_left` says which.
  bool side_facing_known = false;
  bool faces_left = false;
};

/// The lines generator's output for one robot.
struct RobotLines {
  std::vector<Eigen::Vector2d> silhouette_px;
  std::vector<Eigen::Vector2d> silhouette_in_robot;
  std::vector<LineRegion> regions;  ///< one per line found (first, then second)
  std::optional<RobotOrientation> orientation;  ///< after the consistency check
};

/// Tracked robots with their orientation filters: explicit state, passed in and returned by the
/// caller (the stage keeps none).
struct RobotTracks {
  struct Track {
    int id = 0;
    Eigen::Vector2d position_in_robot = Eigen::Vector2d::Zero();
    double last_seen_s = 0;
    int hits = 0;  ///< frames with a percept
    OrientationTrack orientation;
  };
  std::vector<Track> tracks;
  int next_id = 0;
};

/// The paper's orientation pipeline (2.4) on detected robots.
class RobotOrientationEstimator {
 public:
  RobotOrientationEstimator(RobotOrientationParams params, FieldDimensions field,
                            cnn::Classifier ori_boost_net, cnn::Classifier ori_net);
  static RobotOrientationEstimator loadDefault();

  /// Lines generator and line regions (no classification).
  /// `field`: the frame's detected field lines and centre circle (their lower edges are not the
  /// feet's).
  RobotLines findLines(const GrayView& image, const CameraModel& camera, const RobotPercept& robot,
                       const FieldFeatures& field = {}) const;
  /// Lines, OriBoostNet, OriNet, consistency check and orientation of one robot.
  RobotLines estimate(const GrayView& image, const CameraModel& camera, const RobotPercept& robot,
                      const FieldFeatures& field = {}) const;
  /// Fills orientation_raw, track_id and orientation_filtered of every percept; updates `tracks`
  /// (association by ground position, expiry). `time_s` is the frame's time.
  void run(const GrayView& image, const CameraModel& camera, std::vector<RobotPercept>& robots,
           RobotTracks& tracks, double time_s, const FieldFeatures& field = {}) const;
  const RobotOrientationParams& params() const { return params_; }

 private:
  RobotOrientationParams params_;
  double robot_height_m_;
  double line_half_width_m_;      ///< the field lines', from the field dimensions
  double centre_circle_radius_m_;  ///< to its line's middle, from the field dimensions
  cnn::Classifier boost_;
  cnn::Classifier ori_;
};

/// Associates percepts with tracks (nearest first, within max_distance_m), starts new tracks,
/// drops tracks unseen for longer than expiry_s, and feeds each percept's raw orientation to its
/// track's filter. Fills track_id and orientation_filtered.
void updateRobotTracks(RobotTracks& tracks, std::vector<RobotPercept>& robots, double time_s,
                       double max_distance_m, const OrientationFilterParams& filter);

/// The ground points of the tracks seen in at least `min_hits` frames and, at `time_s`, not
/// unseen for longer than `expiry_s` (those updateRobotTracks would still keep): the robots the
/// detector's track prior lifts.
std::vector<Eigen::Vector2d> trackedRobots(const RobotTracks& tracks, double time_s, int min_hits,
                                           double expiry_s);

}  // namespace colorfree
