#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "colorfree/groundtruth/scoring_params.h"
#include "colorfree/perception/cnn/net.h"
#include "colorfree/perception/error.h"
#include "colorfree/perception/pipeline.h"
#include "colorfree/training/active_learning.h"
#include "colorfree/training/ball_kind.h"
#include "colorfree/training/robot_kind.h"
#include "commands.h"

namespace colorfree::app {

namespace {

std::vector<training::ScenarioSource> sources(const std::vector<std::string>& paths, int frames, int stride) {
  std::vector<training::ScenarioSource> out;
  for (const auto& p : paths) out.push_back({p, frames, stride});
  return out;
}

}  // namespace

void addLearnCommand(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand(
      "learn",
      "Active learning in the simulator (paper 3.2): render scenarios, run the real proposal stage, label "
      "the proposals from the truth, add them to a dataset folder, retrain; then bootstrap hard negatives");
  struct Options {
    std::string object = "ball";
    std::vector<std::string> train, bootstrap, validation, test;
    int frames = 8, stride = 4, rounds = 3, bootstrap_rounds = 1, epochs = 40, patience = 8;
    float bootstrap_confidence = 0.5f;
    float border_cut = 0.0f;
    double min_smear = 0.5;
    std::uint64_t seed = 1;
    std::string dataset = "build/ball_dataset";
    std::string models;
    bool quiet = false;
  };
  auto o = std::make_shared<Options>();
  cmd->add_option("OBJECT", o->object,
                  "what to learn: ball (BoostBallNet, BallNet), smeared_ball (SmearedBallNet), "
                  "robot (RobotNet), robot_behind (RobotBehindNet), robot_feet (RobotFeetNet), "
                  "ori_boost (OriBoostNet), ori (OriNet)")
      ->required();
  cmd->add_option("--train", o->train, "training scenario files (new frames every round)")->required();
  cmd->add_option("--bootstrap", o->bootstrap, "scenario files without the object (hard negatives)");
  cmd->add_option("--validation", o->validation, "held-out scenario files (early stopping)")->required();
  cmd->add_option("--test", o->test,
                  "test scenario files: only the final accuracy (written to DATASET/test/<net> for cnn-table --data)");
  cmd->add_option("--frames", o->frames, "frames per case and round")->capture_default_str();
  cmd->add_option("--stride", o->stride, "frame stride within a case")->capture_default_str();
  cmd->add_option("--rounds", o->rounds, "active rounds after the truth-cut round")->capture_default_str();
  cmd->add_option("--bootstrap-rounds", o->bootstrap_rounds, "bootstrap rounds")->capture_default_str();
  cmd->add_option("--bootstrap-confidence", o->bootstrap_confidence,
                  "positive score that makes a proposal on an object-free scene a hard negative")
      ->capture_default_str();
  cmd->add_option("--epochs", o->epochs, "training epochs per round at most")->capture_default_str();
  cmd->add_option("--patience", o->patience, "early stopping patience, epochs")->capture_default_str();
  cmd->add_option("--seed", o->seed, "trainer seed")->capture_default_str();
  cmd->add_option("--border-cut", o->border_cut,
                  "augmentation: chance of cutting a patch as the image border cuts an object (0..1; up to 0.6 of "
                  "the patch deep, 30 % of the cuts at a corner)")
      ->capture_default_str();
  cmd->add_option("--min-smear", o->min_smear,
                  "smeared_ball: the patchSmear bound of the patches it learns from (the detector's "
                  "smeared_min_coherence when switched on)")
      ->capture_default_str();
  cmd->add_option("--dataset", o->dataset, "dataset folder to write (one sub-folder per net)")->capture_default_str();
  cmd->add_option("--models", o->models, "model folder: cfgs read, weights written (default: perception/models)");
  cmd->add_flag("--quiet", o->quiet, "only the final summary");
  cmd->callback([o, &exit_code] {
    std::unique_ptr<training::ObjectKind> kind_ptr;
    if (o->object == "ball" || o->object == "smeared_ball") {
      PipelineConfig config = PipelineConfig::loadDefault();
      if (o->object == "smeared_ball") config.ball_detector.smeared_min_coherence = o->min_smear;
      kind_ptr = std::make_unique<training::BallKind>(config, ScoringParams::loadDefault(), o->object == "smeared_ball");
    } else if (o->object == "robot" || o->object == "robot_behind" || o->object == "robot_feet" ||
               o->object == "ori_boost" || o->object == "ori") {
      const auto which = o->object == "robot"          ? training::RobotNetChoice::kRobotNet
                         : o->object == "robot_behind" ? training::RobotNetChoice::kBehindNet
                         : o->object == "robot_feet"   ? training::RobotNetChoice::kFeetNet
                         : o->object == "ori_boost"    ? training::RobotNetChoice::kOriBoostNet
                                                       : training::RobotNetChoice::kOriNet;
      if (which != training::RobotNetChoice::kRobotNet &&
          which != training::RobotNetChoice::kBehindNet && !o->bootstrap.empty()) {
        throw Error("learn: " + o->object + " has no hard negatives to bootstrap (leave out --bootstrap)");
      }
      kind_ptr = std::make_unique<training::RobotKind>(which, PipelineConfig::loadDefault(),
                                                       ScoringParams::loadDefault());
    } else {
      throw Error("learn: unknown object '" + o->object +
                  "' (known: ball, smeared_ball, robot, robot_behind, robot_feet, ori_boost, ori)");
    }
    if (o->frames < 1 || o->stride < 1 || o->rounds < 0 || o->bootstrap_rounds < 0 || o->epochs < 1) {
      throw Error("learn: --frames, --stride and --epochs must be positive, --rounds not negative");
    }
    if (!(o->border_cut >= 0.0f && o->border_cut <= 1.0f)) {
      throw Error("learn: --border-cut must lie in 0..1, not " + std::to_string(o->border_cut));
    }
    training::LearnConfig config;
    config.train = sources(o->train, o->frames, o->stride);
    config.bootstrap = sources(o->bootstrap, o->frames, o->stride);
    config.validation = sources(o->validation, o->frames, o->stride);
    config.test = sources(o->test, o->frames, o->stride);
    config.rounds = o->rounds;
    config.bootstrap_rounds = o->bootstrap_rounds;
    config.bootstrap_min_confidence = o->bootstrap_confidence;
    config.dataset_dir = o->dataset;
    config.model_dir = o->models.empty() ? cnn::defaultModelDir() : o->models;
    config.trainer.max_epochs = o->epochs;
    config.trainer.patience_epochs = o->patience;
    config.trainer.seed = o->seed;
    config.trainer.augmentation.border_cut_probability = o->border_cut;
    config.trainer.augmentation.border_cut_max_fraction = 0.6f;        // a ball half out of the image, and more
    config.trainer.augmentation.border_cut_corner_probability = 0.3f;  // cut at an image corner
    const training::ObjectKind& kind = *kind_ptr;
    const auto result = training::learn(kind, config, [o](const std::string& line) {
      if (!o->quiet) std::printf("%s\n", line.c_str());
      std::fflush(stdout);
    });
    const auto& last = result.rounds.back();
    const auto stems = kind.netStems();
    for (std::size_t i = 0; i < stems.size(); ++i) {
      std::printf("%s: held-out accuracy %.4f on %d samples, %d training samples\n", stems[i].c_str(),
                  last.validation_accuracy[i], last.validation_samples[i], last.dataset_size[i]);
    }
    for (std::size_t i = 0; i < result.test_accuracy.size(); ++i) {
      std::printf("%s: test accuracy %.4f on %d samples (test scenarios: neither trained on nor early stopping)\n",
                  stems[i].c_str(), result.test_accuracy[i], result.test_samples[i]);
    }
    for (const auto& w : result.weights_written) std::printf("wrote %s\n", w.c_str());
    exit_code = 0;
  });
}

}  // namespace colorfree::app
