#include "colorfree/groundtruth/scoring_params.h"

#include <sstream>

#include "colorfree/perception/param_file.h"

namespace colorfree {

ScoringParams ScoringParams::load(const std::string& path) {
  ParamFile f(path);
  ScoringParams p;
  p.ball_min_visible_fraction = f.getInRange("ball_min_visible_fraction", 0, 1);
  p.ball_min_distance_m = f.getInRange("ball_min_distance_m", 0, 100);
  p.ball_max_distance_m = f.getInRange("ball_max_distance_m", 0, 100);
  p.ball_min_radius_px = f.getInRange("ball_min_radius_px", 0, 1000);
  p.robot_min_visible_fraction = f.getInRange("robot_min_visible_fraction", 0, 1);
  p.robot_min_distance_m = f.getInRange("robot_min_distance_m", 0, 100);
  p.robot_max_distance_m = f.getInRange("robot_max_distance_m", 0, 100);
  p.robot_min_height_px = f.getInRange("robot_min_height_px", 0, 10000);
  p.robot_depth_m = f.getInRange("robot_depth_m", 0.01, 3);
  p.robot_feet_region_height_m = f.getInRange("robot_feet_region_height_m", 0.01, 3);
  p.foot_lateral_offset_m = f.getInRange("foot_lateral_offset_m", 0, 1);
  p.ball_match_radius_fraction = f.getInRange("ball_match_radius_fraction", 0.01, 10);
  p.ball_match_min_px = f.getInRange("ball_match_min_px", 0, 100);
  p.robot_match_min_iou = f.getInRange("robot_match_min_iou", 0.01, 1);
  p.robot_match_max_feet_distance_m = f.getInRange("robot_match_max_feet_distance_m", 0, 10);
  p.orientation_tolerance_deg = f.getInRange("orientation_tolerance_deg", 0.1, 90);
  p.orientation_heading_bin_deg = f.getInRange("orientation_heading_bin_deg", 1, 360);
  p.field_feature_max_distance_m = f.getInRange("field_feature_max_distance_m", 0.1, 100);
  p.line_min_length_px = f.getInRange("line_min_length_px", 1, 10000);
  p.line_match_max_px = f.getInRange("line_match_max_px", 0.1, 1000);
  p.intersection_match_max_px = f.getInRange("intersection_match_max_px", 0.1, 1000);
  p.feature_visibility_window_px =
      static_cast<int>(f.getInRange("feature_visibility_window_px", 0, 100));
  p.pose_guess_offset_m = f.getInRange("pose_guess_offset_m", 0, 5);
  p.pose_guess_offset_deg = f.getInRange("pose_guess_offset_deg", -90, 90);
  p.distance_bin_m = f.getInRange("distance_bin_m", 0.05, 100);
  p.visibility_bin_fraction = f.getInRange("visibility_bin_fraction", 0.01, 1);
  p.gallery_max_crops = static_cast<int>(f.getInRange("gallery_max_crops", 0, 1000));
  p.gallery_worst_frames = static_cast<int>(f.getInRange("gallery_worst_frames", 0, 1000));
  f.finish();
  if (p.ball_min_distance_m > p.ball_max_distance_m) {
    throw Error(path + ": ball_min_distance_m is larger than ball_max_distance_m");
  }
  if (p.robot_min_distance_m > p.robot_max_distance_m) {
    throw Error(path + ": robot_min_distance_m is larger than robot_max_distance_m");
  }
  return p;
}

std::string ScoringParams::defaultPath() {
  return std::string(COLORFREE_SOURCE_DIR) + "/groundtruth/params/scoring.yaml";
}

std::string ScoringParams::shouldDetectRule() const {
  std::ostringstream s;
  s << "A ball should be detected when at least " << ball_min_visible_fraction * 100
    << " % of its projected disc is visible in the object map (pixels cut by the image border "
       "or hidden by a robot count as not visible), its ground distance from the observer is in ["
    << ball_min_distance_m << ", " << ball_max_distance_m << "] m, its projected radius is at "
    << "least " << ball_min_radius_px << " px and its centre lies inside the image. "
    << "A robot should be detected when at least " << robot_min_visible_fraction * 100
    << " % of it is visible (its object-map pixels against those pixels plus the pixels of its "
       "projected body hidden by nearer objects, times the share of that body inside the image), "
       "its distance is in ["
    << robot_min_distance_m << ", " << robot_max_distance_m << "] m, its projected body box is at "
    << "least " << robot_min_height_px << " px tall and the box centre lies inside the image. "
    << "Objects in view that fail the rule are 'don't care': a detection of one is neither a hit "
       "nor a false positive.";
  return s.str();
}

std::string ScoringParams::matchingRule() const {
  std::ostringstream s;
  s << "One-to-one, greedy from the best pair. Ball: centre within max("
    << ball_match_radius_fraction << " x true radius, " << ball_match_min_px
    << " px) of the true centre. Robot: box IoU with the true whole-body box >= "
    << robot_match_min_iou << ", or feet point on the ground within "
    << robot_match_max_feet_distance_m << " m of the true ground point. Orientation tolerance "
    << orientation_tolerance_deg << " deg. Lines: both ends of a detected segment within "
    << line_match_max_px << " px of a true line in view (at least " << line_min_length_px
    << " px of it visible within " << field_feature_max_distance_m
    << " m of the observer). Intersections: same type within " << intersection_match_max_px
    << " px.";
  return s.str();
}

}  // namespace colorfree
