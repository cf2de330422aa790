#include "colorfree/perception/pipeline.h"

#include <algorithm>
#include <chrono>
#include <cstdio>

#include "colorfree/perception/cnn/net.h"
#include "colorfree/perception/error.h"
#include "colorfree/perception/noise.h"
#include "colorfree/perception/param_file.h"

namespace colorfree {

const char* stageName(Stage stage) {
  switch (stage) {
    case Stage::kIgnoreRegions: return "ignore regions (field boundary, own body)";
    case Stage::kHighContrast: return "high contrast regions";
    case Stage::kFieldLines: return "field lines and features";
    case Stage::kRobotProposals: return "robot proposals";
    case Stage::kRobotDetector: return "robot detector";
    case Stage::kRobotOrientation: return "robot orientation";
    case Stage::kBallProposals: return "ball proposals";
    case Stage::kBallDetector: return "ball detector";
  }
  return "?";
}

void PipelineStats::add(Stage stage, double ms) {
  auto& t = timings_[static_cast<int>(stage)];
  if (!t) t = StageTiming{};
  ++t->frames;
  t->total_ms += ms;
  t->max_ms = std::max(t->max_ms, ms);
}

std::string PipelineStats::table() const {
  std::string out = "stage                                       mean ms    max ms  frames\n";
  char line[160];
  for (int i = 0; i < kStageCount; ++i) {
    const auto& t = timings_[i];
    if (t) {
      std::snprintf(line, sizeof line, "%-42s %9.4f %9.4f %7ld\n", stageName(static_cast<Stage>(i)),
                    t->meanMs(), t->max_ms, t->frames);
    } else {
      std::snprintf(line, sizeof line, "%-42s    absent\n", stageName(static_cast<Stage>(i)));
    }
    out += line;
  }
  return out;
}

PipelineConfig PipelineConfig::load(const std::string& dir) {
  PipelineConfig c;
  c.field_boundary = FieldBoundaryParams::load(dir + "/field_boundary.yaml");
  c.body_model = BodyModelParams::load(dir + "/body_model.yaml");
  c.high_contrast = HighContrastParams::load(dir + "/high_contrast.yaml");
  c.field_lines = FieldLineParams::load(dir + "/field_lines.yaml");
  c.field = FieldDimensions::load(dir + "/field_dimensions.yaml");
  c.robot_proposer = RobotProposerParams::load(dir + "/robot_proposer.yaml");
  c.robot_detector = RobotDetectorParams::load(dir + "/robot_detector.yaml");
  c.robot_orientation = RobotOrientationParams::load(dir + "/robot_orientation.yaml");
  c.ball_proposer = BallProposerParams::load(dir + "/ball_proposer.yaml");
  c.ball_detector = BallDetectorParams::load(dir + "/ball_detector.yaml");
  return c;
}

PipelineConfig PipelineConfig::loadDefault() { return load(defaultParamDir()); }

Pipeline::Pipeline(PipelineConfig config)
    : config_(config),
      field_boundary_(config.field_boundary),
      body_contour_(config.body_model),
      high_contrast_(config.high_contrast),
      field_lines_(config.field_lines, config.field),
      robot_proposer_(config.robot_proposer, config.field),
      ball_proposer_(config.ball_proposer) {
  if (config_.robot_stages) {
    const std::string dir = config_.model_dir.empty() ? cnn::defaultModelDir() : config_.model_dir;
    auto net = [&](const char* stem) {
      return cnn::Classifier::load(dir + "/" + stem + ".cfg", dir + "/" + stem + ".weights");
    };
    robot_detector_.emplace(config_.robot_detector, net("robot_net"), config_.field,
                            net("robot_feet_net"), net("robot_behind_net"));
    robot_orientation_.emplace(config_.robot_orientation, config_.field, net("ori_boost_net"),
                               net("ori_net"));
  }
  if (config_.ball_stages) ball_detector_ = BallDetector::load(config_.ball_detector, config_.model_dir);
}

namespace {

// A white blob a detected ball explains is no penalty mark: marks centred within `radii` × a
// ball's image radius of its centre are dropped.
void dropPenaltyMarksUnderBalls(Frame& frame, double radii) {
  if (radii <= 0 || !frame.field_lines || !frame.ball_percepts) return;
  auto& marks = frame.field_lines->features.penalty_marks;
  std::erase_if(marks, [&](const CircleMarkPercept& m) {
    return std::any_of(frame.ball_percepts->begin(), frame.ball_percepts->end(),
                       [&](const BallPercept& b) {
                         return (m.centre_px - b.centre_px).norm() < radii * b.radius_px;
                       });
  });
}

// Runs `f` and returns its duration (ms).
template <typename F>
double elapsedMs(F&& f) {
  const auto start = std::chrono::steady_clock::now();
  f();
  const auto end = std::chrono::steady_clock::now();
  return std::chrono::duration<double, std::milli>(end - start).count();
}

// Runs `f` and adds its duration to the stage's timing.
template <typename F>
void timed(PipelineStats* stats, Stage stage, F&& f) {
  const double ms = elapsedMs(f);
  if (stats) stats->add(stage, ms);
}

}  // namespace

void Pipeline::process(Frame& frame, PipelineStats* stats, RobotTracks* tracks) const {
  const GrayView& image = frame.image;
  if (image.empty()) throw Error("pipeline: empty image");
  if (image.width != frame.camera.width() || image.height != frame.camera.height()) {
    throw Error("pipeline: image is " + std::to_string(image.width) + "x" +
                std::to_string(image.height) + " but the camera model is " +
                std::to_string(frame.camera.width()) + "x" + std::to_string(frame.camera.height()));
  }
  if (image.stride < image.width) throw Error("pipeline: image stride is smaller than its width");

  // The order of the stages, as in the paper's framework.
  timed(stats, Stage::kIgnoreRegions, [&] {
    frame.field_boundary = field_boundary_.run(image, frame.camera);
    if (config_.use_body_contour) {
      frame.body_contour = body_contour_.run(frame.camera);
    } else {
      BodyContour none;
      none.top_y.assign(image.width, image.height);
      frame.body_contour = std::move(none);
    }
    frame.ignore_mask =
        IgnoreMask::combine(*frame.field_boundary, *frame.body_contour, image.width, image.height);
    frame.pixel_noise_gray = pixelNoiseGray(image, *frame.ignore_mask);
    frame.light_gray = frameLightGray(image, *frame.ignore_mask);
  });
  timed(stats, Stage::kHighContrast, [&] {
    frame.contrast_regions = high_contrast_.run(image, *frame.ignore_mask, frame.light_gray);
  });
  timed(stats, Stage::kFieldLines, [&] {
    frame.field_lines = field_lines_.run(image, frame.camera, *frame.ignore_mask, config_.keep_rejected);
  });
  double robot_detector_ms = 0;  // RobotNet's work, with its second look at boxes on the ball
  if (robot_detector_) {
    RobotProposals proposals;
    timed(stats, Stage::kRobotProposals, [&] {
      proposals = robot_proposer_.run(image, frame.camera, *frame.ignore_mask, *frame.contrast_regions, false,
                                      frame.pixel_noise_gray);
    });
    robot_detector_ms = elapsedMs([&] {
      std::vector<RobotProposal> classified;
      std::vector<float> confidences;
      // The robots tracked over the frames before (explicit state: the caller's tracks).
      const std::vector<Eigen::Vector2d> tracked =
          tracks ? trackedRobots(*tracks, frame.time_s, config_.robot_detector.track_prior_min_hits,
                                 config_.robot_orientation.track_expiry_s)
                 : std::vector<Eigen::Vector2d>{};
      frame.robot_percepts = robot_detector_->run(image, frame.camera, proposals.proposals,
                                                  proposals.held_back, &classified, &confidences,
                                                  &tracked);
      frame.robot_proposals = std::move(classified);
      frame.robot_net_confidences = std::move(confidences);
    });
  }
  // The ball proposals also scan the regions in front of the detected robots' feet.
  if (ball_detector_) {
    timed(stats, Stage::kBallProposals, [&] {
      frame.ball_proposals =
          ball_proposer_.run(image, frame.camera, *frame.ignore_mask, *frame.contrast_regions,
                             frame.robot_percepts ? &*frame.robot_percepts : nullptr,
                             frame.pixel_noise_gray, frame.light_gray);
    });
    timed(stats, Stage::kBallDetector, [&] {
      std::vector<BallDecision> decisions;
      frame.ball_percepts = ball_detector_->run(image, frame.camera, *frame.ball_proposals, &decisions);
      frame.ball_decisions = std::move(decisions);
    });
    dropPenaltyMarksUnderBalls(frame, config_.field_lines.penalty_mark_ball_radii);
  }
  if (robot_detector_) {
    // A robot box stood on a detected ball: looked at again above it, or dropped; then the
    // orientation of the robots that stay.
    if (ball_detector_ && frame.ball_percepts) {
      robot_detector_ms += elapsedMs([&] {
        frame.robot_percepts = robot_detector_->liftOffBalls(
            image, frame.camera, *frame.robot_percepts, *frame.ball_percepts);
      });
    }
    if (stats) stats->add(Stage::kRobotDetector, robot_detector_ms);
    timed(stats, Stage::kRobotOrientation, [&] {
      RobotTracks this_frame_only;
      robot_orientation_->run(image, frame.camera, *frame.robot_percepts,
                              tracks ? *tracks : this_frame_only, frame.time_s, frame.fieldFeatures());
    });
  }
}

}  // namespace colorfree
