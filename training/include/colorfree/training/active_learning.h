#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "colorfree/groundtruth/truth_in_image.h"
#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/cnn/classifier.h"
#include "colorfree/perception/cnn/dataset.h"
#include "colorfree/perception/cnn/patch.h"
#include "colorfree/perception/cnn/trainer.h"
#include "colorfree/perception/image.h"

namespace colorfree::training {

/// One region of a frame that a net should learn, with its label from the truth.
struct Candidate {
  cnn::PatchBox box;  ///< the patch every net of the kind is cut from (resized to its input)
  int label = 0;
  std::string key;    ///< decorrelation: two candidates with the same key are the same sample
  std::string truth;  ///< what the truth says is there (manifest text, no commas)
};

/// The object-specific part of the active-learning loop (ball, robot, orientation): which nets it
/// trains, what the real proposal stage offers in a frame and what the truth says about each.
class ObjectKind {
 public:
  virtual ~ObjectKind() = default;
  virtual std::string name() const = 0;
  virtual std::vector<std::string> classNames() const = 0;
  /// Per class: whether a horizontally mirrored sample keeps its label (the trainer's flip
  /// augmentation). Default: every class.
  virtual std::vector<bool> flipAllowed() const { return std::vector<bool>(classNames().size(), true); }
  /// Net stems in perception/models that learn from these samples, first the one whose errors
  /// are reported first (all share the candidates; each cuts them at its own input size).
  virtual std::vector<std::string> netStems() const = 0;
  /// The label whose high-confidence predictions on scenes without the object become hard
  /// negatives, and the label they get.
  virtual int positiveLabel() const = 0;
  virtual int negativeLabel() const = 0;
  /// Candidates of the real proposal stage on a frame, labelled from the truth (ambiguous ones,
  /// e.g. a proposal half on the ball, are left out).
  virtual std::vector<Candidate> proposals(const GrayImage& image, const CameraModel& camera,
                                           const FrameTruth& truth) const = 0;
  /// Candidates cut directly around the true objects (the first round's positives).
  virtual std::vector<Candidate> truthSamples(const GrayImage& image, const CameraModel& camera,
                                              const FrameTruth& truth) const = 0;
};

/// One scenario file with the frames the loop takes from each of its cases.
struct ScenarioSource {
  std::string path;
  int frames_per_case = 10;  ///< frames 0, stride, 2·stride, … of every case
  int frame_stride = 3;
};

struct LearnConfig {
  std::vector<ScenarioSource> train;       ///< rendered afresh every round (new frames each round)
  std::vector<ScenarioSource> bootstrap;   ///< scenes without the object: hard negatives
  std::vector<ScenarioSource> validation;  ///< held-out scenarios: early stopping of every round
  /// Test scenarios, used for nothing but the final accuracy figures (neither training nor early
  /// stopping); written to <dataset_dir>/test/<stem> when given.
  std::vector<ScenarioSource> test;
  int rounds = 3;             ///< active-learning rounds after the first (truth-cut) round
  int bootstrap_rounds = 1;
  float bootstrap_min_confidence = 0.5f;  ///< positive score for a hard negative
  std::string dataset_dir;    ///< <dataset_dir>/<stem>/<class>/*.png + manifest.csv per net
  std::string model_dir;      ///< the cfgs are read from here and the weights written here
  cnn::TrainerParams trainer;
  bool quiet = false;
};

/// What one round did, per net (in netStems() order).
struct RoundReport {
  std::string phase;  ///< "truth", "active", "bootstrap"
  int round = 0;
  int frames = 0;
  int new_samples = 0;          ///< added to the dataset (after decorrelation)
  int duplicates = 0;           ///< dropped as the same sample as one already held
  std::vector<int> wrong;       ///< new samples the net before this round got wrong (-1: no net yet)
  std::vector<int> dataset_size;
  std::vector<double> validation_accuracy;  ///< on the held-out scenarios, after retraining
  std::vector<int> validation_samples;
};

struct LearnResult {
  std::vector<RoundReport> rounds;
  std::vector<double> test_accuracy;  ///< per net, on the test scenarios (empty without them)
  std::vector<int> test_samples;
  std::vector<std::string> weights_written;
};

/// The paper's active learning (3.2) in the simulator: render scenarios, run the real proposal
/// stage, keep uncorrelated samples, label them from the truth, add them to the dataset folder,
/// retrain; then bootstrap hard negatives on scenes without the object. Deterministic.
LearnResult learn(const ObjectKind& kind, const LearnConfig& config,
                  const std::function<void(const std::string&)>& log = {});

/// Samples of `candidates` cut from `image` at `size`×`size` with the net's `resampling` (grey
/// values, not normalised).
std::vector<cnn::Sample> cutSamples(const GrayImage& image,
                                    const std::vector<Candidate>& candidates, int size,
                                    cnn::PatchResampling resampling, const std::string& scenario,
                                    int frame);

}  // namespace colorfree::training
