#pragma once

#include <optional>
#include <string>
#include <vector>

#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/cnn/classifier.h"
#include "colorfree/perception/cnn/patch.h"
#include "colorfree/perception/image.h"
#include "colorfree/perception/percepts.h"

namespace colorfree {

/// Parameters of the ball classification stage (perception/params/ball_detector.yaml).
struct BallDetectorParams {
  double ball_radius_m = 0.05;
  /// Side of the square patch cut around a proposal, in ball diameters (both nets, and training).
  double patch_diameters = 1.25;
  int boost_keep_count = 5;              ///< BoostBallNet passes at most this many to BallNet
  double boost_min_confidence = 0.05;    ///< ... and only those with at least this "ball" score
  /// 1: a proposal the image border cuts is scored by BoostBallNet's look at its patch and at the
  /// patch mirrored about the border, the larger counting (0: the first look only).
  int boost_border_mirror = 1;
  double ball_min_confidence = 0.5;      ///< BallNet's "ball" score for a detection
  int max_balls = 1;                     ///< detections per frame at most (the strongest)
  /// A proposal whose centre lies more than this × its radius outside the image shows less than
  /// about half of a ball: it is not passed on to BallNet (nor reported).
  double max_centre_outside_radii = 0.25;
  /// A kept proposal BallNet rejects whose patch lies inside the image and is at least this
  /// elongated (`patchSmear`: a ball smeared by the camera's motion) goes to SmearedBallNet too,
  /// which may accept it. Above 1: never (SmearedBallNet is not loaded).
  double smeared_min_coherence = 0.5;
  double smeared_ball_min_confidence = 0.9;  ///< SmearedBallNet's "ball" score for a detection
  /// ... and only for proposals of at least this radius: the smeared balls it learnt from are
  /// 0.8-1.7 m away (radius 10 px and more); a far ball's few pixels are BallNet's alone.
  double smeared_min_radius_px = 10;
  /// ... and only where the camera's own turn smeared the frame (`CameraModel::exposureSmearPx`,
  /// from the robot's kinematics) by at least this many of the proposal's radii (0: whatever it
  /// did), along a direction within smeared_max_direction_deg of the patch's smear (90: any).
  double smeared_min_camera_smear_radii = 0.5;
  double smeared_max_direction_deg = 30;
  /// A ball SmearedBallNet accepts is put at the middle of its smear (`smearedBallCentre`), looked
  /// for up to this many radii either side of the proposal along the smear ...
  double smeared_centre_reach_radii = 3;
  /// ... when the smear is at least this much brighter than the carpet beyond its ends.
  double smeared_centre_min_contrast_gray = 8;
  /// A kept patch BallNet rejects gets a look at rescale_up and at rescale_down times the
  /// proposal's radius (a camera pose that is off frames the ball too tight or too loose); a score of
  /// at least rescale_min_confidence there detects it with that radius. 0: no such look.
  double rescale_up = 1.6;
  double rescale_down = 0.7;
  double rescale_min_confidence = 0.99;
  /// ... for proposals of at least this radius (0: any): a smaller one's patch, some 12 px, says
  /// too little at another scale (far boards' stripes at the floor took that look).
  double rescale_min_radius_px = 5;
  /// A kept patch BallNet rejects (and the rescaled look did not take) gets a look through an
  /// unsharp mask (`cnn::unsharpMask`) of this blur, in ball radii (a soft lens blurs the ball's
  /// print, which BallNet reads; the mask restores some of it) ... 0: no such look.
  double sharpen_sigma_radii = 0.2;
  double sharpen_amount = 4;  ///< ... and strength ...
  /// ... for proposals of at least this radius: a smaller ball's patch is enlarged to the net's
  /// input, blurred by the resampling rather than the lens, and sharpening it makes up prints ...
  double sharpen_min_radius_px = 10;
  double sharpen_min_confidence = 0.99;  ///< ... and is detected from this BallNet score there.
  /// A kept patch BallNet rejects (and neither the rescaled nor the sharpened look took), where the
  /// camera's own turn smeared the frame by at least deblur_min_camera_smear_radii × the radius
  /// (`CameraModel::exposureSmearPx`), gets a look with that smear taken back (`cnn::deblurAlong`,
  /// this many Richardson–Lucy steps; 0: no such look) ...
  int deblur_iterations = 10;
  double deblur_min_camera_smear_radii = 0.5;
  double deblur_min_radius_px = 10;      ///< ... for proposals of at least this radius ...
  double deblur_min_confidence = 0.9;    ///< ... and is detected from this BallNet score there.
  /// A kept patch BallNet rejects (and no other look took) that the image border cuts gets a look
  /// with the part beyond the border mirrored about it (the ball's visible part completing it, where
  /// the patch otherwise repeats the border pixel), detected from this BallNet score (above 1: never).
  double border_mirror_min_confidence = 0.9;

  bool operator==(const BallDetectorParams&) const = default;
  static BallDetectorParams load(const std::string& path);
  static BallDetectorParams loadDefault();
};

/// The square patch the nets see for a ball of `radius_px` at `centre_px`.
cnn::PatchBox ballPatchBox(const Eigen::Vector2d& centre_px, double radius_px,
                           double patch_diameters);

/// How far `centre_px` lies outside an image of `width` × `height` pixels, in units of `radius_px`
/// (0 inside; the image spans [0, width] × [0, height], pixel centres at +0.5).
double centreOutsideRadii(const Eigen::Vector2d& centre_px, double radius_px, int width, int height);

/// Side in pixels of the patch `patchSmear` measures (BallNet's input size).
inline constexpr int kSmearPatchSide = 26;

/// How elongated the kSmearPatchSide² patch cut from `box` (as the nets cut it) is, 0..1: the
/// coherence (λ1 − λ2) / (λ1 + λ2) of the structure tensor of its Sobel gradients. A sharp whole
/// ball is near 0 (its outline and patches turn every way); smeared sideways by the camera's
/// motion it rises towards 1 with the smear's length; a straight edge is 1. -1 when the box
/// reaches beyond the image (a ball cut by the border is elongated too).
/// `along`, when given, gets the smear's direction (unit; the direction of least change).
double patchSmear(const GrayView& image, const cnn::PatchBox& box, Eigen::Vector2d* along = nullptr);

/// The middle of a smeared ball: the gray profile along `along` through `centre_px` (each point the
/// mean over ±radius/2 across the smear), `reach_radii` × `radius_px` either side; its level beyond
/// the ends (the median of the outer radius/2 on both sides) is the carpet's; the run of the
/// profile above half-way from that level to its peak (within a radius of `centre_px`) that lies
/// nearest `centre_px` is the smear, and its middle the ball's centre. None when the peak is less
/// than `min_contrast_gray` above the carpet, or the run reaches an end (a line, not a ball).
std::optional<Eigen::Vector2d> smearedBallCentre(const GrayView& image, const Eigen::Vector2d& centre_px,
                                                 double radius_px, const Eigen::Vector2d& along,
                                                 double reach_radii, double min_contrast_gray);

/// What the cascade decided for every proposal (for scoring, active learning and the report).
struct BallDecision {
  int proposal = 0;                ///< index into the proposals
  float boost_confidence = 0;      ///< BoostBallNet's "ball" probability
  bool passed_boost = false;       ///< among the kept ones
  float ball_confidence = -1;      ///< BallNet's "ball" probability; -1 when it did not run
  float smear = -1;                ///< `patchSmear` of a kept proposal BallNet rejected; else -1, or beyond the image
  float smeared_confidence = -1;   ///< SmearedBallNet's "ball" probability; -1 when it did not run
  /// BallNet's "ball" probability on the sharpened patch; -1 when it did not look
  float sharpened_confidence = -1;
  /// BallNet's "ball" probability on the patch with the camera's smear taken back; -1 when it did not look
  float deblurred_confidence = -1;
  /// BallNet's "ball" probability on the patch mirrored at the image border; -1 when it did not look
  float mirrored_confidence = -1;
  bool detected = false;
};

/// Ball classification (paper 2.4): BoostBallNet (12×12) sorts the proposals by confidence and
/// keeps at most five; BallNet (26×26) decides; a patch it rejects that the camera's motion smeared
/// (`smeared_min_coherence`) gets a second look by SmearedBallNet (BallNet's shape, trained on such
/// patches only), and BallNet looks again at it framed larger and smaller (rescale_*: the camera
/// pose the expected radius came from may be off) and, if neither framing takes, sharpened
/// (sharpen_*: a soft lens), and, if the camera turned, with its smear taken back (deblur_*), and,
/// cut by the image border, mirrored about it (border_mirror_*;
/// BoostBallNet scores such a proposal by the better of both looks too).
/// Nets read from perception/models by default.
class BallDetector {
 public:
  /// `smeared_net` is required when `params.smeared_min_coherence` ≤ 1.
  BallDetector(BallDetectorParams params, cnn::Classifier boost_net, cnn::Classifier ball_net,
               std::optional<cnn::Classifier> smeared_net = std::nullopt);
  /// The shipped nets (boost_ball_net, ball_net, smeared_ball_net when used) from `model_dir`
  /// (default: perception/models); throws colorfree::Error naming the file when a model is missing
  /// or broken.
  static BallDetector load(BallDetectorParams params, const std::string& model_dir = "");

  std::vector<BallPercept> run(const GrayView& image, const CameraModel& camera,
                               const std::vector<BallProposal>& proposals,
                               std::vector<BallDecision>* decisions = nullptr) const;
  const BallDetectorParams& params() const { return params_; }

 private:
  BallDetectorParams params_;
  cnn::Classifier boost_net_;
  cnn::Classifier ball_net_;
  std::optional<cnn::Classifier> smeared_net_;
};

}  // namespace colorfree
