#include "colorfree/training/active_learning.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>

#include "colorfree/groundtruth/field_markings.h"
#include "colorfree/groundtruth/scoring_params.h"
#include "colorfree/perception/cnn/net.h"
#include "colorfree/perception/error.h"
#include "colorfree/perception/field_dimensions.h"
#include "colorfree/sim/runner.h"
#include "colorfree/sim/scenario.h"
#include "colorfree/sim/world_renderer.h"

namespace colorfree::training {

std::vector<cnn::Sample> cutSamples(const GrayImage& image,
                                    const std::vector<Candidate>& candidates, int size,
                                    cnn::PatchResampling resampling, const std::string& scenario,
                                    int frame) {
  std::vector<cnn::Sample> out;
  std::vector<float> buf(static_cast<std::size_t>(size) * size);
  for (const Candidate& c : candidates) {
    cnn::extractPatch(image.view(), c.box, size, size, cnn::PatchNormalization::kUnitRange,
                      buf.data(), resampling);
    cnn::Sample s;
    s.patch = GrayImage(size, size);
    for (int i = 0; i < size * size; ++i) {
      s.patch.data()[i] = static_cast<std::uint8_t>(std::clamp(std::lround(buf[i] * 255.0f), 0L, 255L));
    }
    s.label = c.label;
    s.origin.scenario = scenario;
    s.origin.frame = frame;
    s.origin.x_px = c.box.x_px;
    s.origin.y_px = c.box.y_px;
    s.origin.width_px = c.box.width_px;
    s.origin.height_px = c.box.height_px;
    s.origin.truth = c.truth;
    out.push_back(std::move(s));
  }
  return out;
}

namespace {

struct NetState {
  std::string stem;
  cnn::Net net;
  bool trained = false;
  cnn::Dataset data;
  cnn::Dataset validation;
};

// A rendered frame's candidates with the frame's image (for cutting at every net's size).
struct FrameCandidates {
  std::string scenario;
  int frame = 0;
  GrayImage image;
  std::vector<Candidate> candidates;
};

enum class Collect { kTruthAndProposals, kProposals };

// Renders, for every case of every source, the frames of every round (round r: frames
// r + k·stride, k < frames_per_case), each case's scene built once. Returns them per round.
std::vector<std::vector<FrameCandidates>> renderSources(const ObjectKind& kind,
                                                        const std::vector<ScenarioSource>& sources,
                                                        int rounds, int first_offset,
                                                        const std::function<Collect(int)>& what,
                                                        const std::function<void(const std::string&)>& log) {
  const FieldDimensions dims = FieldDimensions::loadDefault();
  const FieldMarkings markings = FieldMarkings::fromDimensions(dims);
  const ScoringParams scoring = ScoringParams::loadDefault();
  std::vector<std::vector<FrameCandidates>> out(static_cast<std::size_t>(rounds));
  for (const ScenarioSource& src : sources) {
    sim::ScenarioRunner runner(sim::Scenario::load(src.path), sim::worldRendererFactory());
    for (int c = 0; c < runner.caseCount(); ++c) {
      const std::string case_name = runner.scenario().name + "/" + runner.scenarioCase(c).name();
      for (int round = 0; round < rounds; ++round) {
        for (int k = 0; k < src.frames_per_case; ++k) {
          const int index = first_offset + round + k * src.frame_stride;
          sim::RenderedFrame f = runner.render(c, index, true);
          const FrameTruth truth = computeFrameTruth(f.truth, markings, dims, scoring);
          FrameCandidates fc;
          fc.scenario = case_name;
          fc.frame = index;
          fc.candidates = kind.proposals(f.image, f.perception_camera, truth);
          if (what(round) == Collect::kTruthAndProposals) {
            auto t = kind.truthSamples(f.image, f.truth.camera.model, truth);
            fc.candidates.insert(fc.candidates.begin(), t.begin(), t.end());
          }
          for (Candidate& cand : fc.candidates) cand.key = case_name + ":" + cand.key;
          fc.image = std::move(f.image);
          out[round].push_back(std::move(fc));
        }
      }
      if (log) log("rendered " + case_name);
    }
  }
  return out;
}

// Positive-class probability of every sample of `samples` under `net`.
std::vector<float> positiveScores(const cnn::Net& net, const std::vector<cnn::Sample>& samples, int positive) {
  const cnn::Classifier classifier(net);
  const int n = net.input().size();
  std::vector<float> in(static_cast<std::size_t>(n));
  std::vector<float> prob(static_cast<std::size_t>(net.classes()));
  std::vector<float> out;
  for (const cnn::Sample& s : samples) {
    for (int i = 0; i < n; ++i) in[i] = s.patch.data()[i];
    cnn::normalizePatch(in.data(), n, net.normalization());
    classifier.run(in.data(), 1, prob.data());
    out.push_back(prob[positive]);
  }
  return out;
}

int predicted(const std::vector<float>& prob) {
  return static_cast<int>(std::max_element(prob.begin(), prob.end()) - prob.begin());
}

int countWrong(const cnn::Net& net, const std::vector<cnn::Sample>& samples) {
  const cnn::Classifier classifier(net);
  const int n = net.input().size();
  std::vector<float> in(static_cast<std::size_t>(n));
  std::vector<float> prob(static_cast<std::size_t>(net.classes()));
  int wrong = 0;
  for (const cnn::Sample& s : samples) {
    for (int i = 0; i < n; ++i) in[i] = s.patch.data()[i];
    cnn::normalizePatch(in.data(), n, net.normalization());
    classifier.run(in.data(), 1, prob.data());
    if (predicted(prob) != s.label) ++wrong;
  }
  return wrong;
}

}  // namespace

LearnResult learn(const ObjectKind& kind, const LearnConfig& config,
                  const std::function<void(const std::string&)>& log_fn) {
  auto log = [&](const std::string& s) {
    if (log_fn) log_fn(s);
  };
  if (config.train.empty()) throw Error("learn: no training scenario");
  if (config.validation.empty()) throw Error("learn: no validation scenario (held-out accuracy)");
  if (config.model_dir.empty()) throw Error("learn: no model directory");
  std::vector<NetState> nets;
  for (const std::string& stem : kind.netStems()) {
    NetState st;
    st.stem = stem;
    st.net = cnn::readDarknetCfg(config.model_dir + "/" + stem + ".cfg");
    if (st.net.input().width != st.net.input().height || st.net.input().channels != 1) {
      throw Error(config.model_dir + "/" + stem + ".cfg: the loop cuts square grayscale patches");
    }
    if (st.net.classes() != static_cast<int>(kind.classNames().size())) {
      throw Error(config.model_dir + "/" + stem + ".cfg: " + std::to_string(st.net.classes()) +
                  " outputs, but the " + kind.name() + " kind has " +
                  std::to_string(kind.classNames().size()) + " classes");
    }
    st.data.width = st.data.height = st.net.input().width;
    st.data.class_names = kind.classNames();
    st.validation = st.data;
    nets.push_back(std::move(st));
  }
  std::set<std::string> seen;
  LearnResult result;

  // Held-out samples: proposals and truth cuts from scenarios never trained on, one dataset per net.
  auto heldOut = [&](const std::vector<ScenarioSource>& sources, const std::string& what) {
    std::vector<cnn::Dataset> sets;
    for (const NetState& st : nets) sets.push_back(st.validation);
    std::set<std::string> vseen;
    auto frames = renderSources(kind, sources, 1, 0, [](int) { return Collect::kTruthAndProposals; }, log);
    for (FrameCandidates& fc : frames[0]) {
      std::vector<Candidate> keep;
      for (const Candidate& c : fc.candidates) {
        if (vseen.insert(c.key).second) keep.push_back(c);
      }
      for (std::size_t i = 0; i < nets.size(); ++i) {
        auto s = cutSamples(fc.image, keep, nets[i].data.width, nets[i].net.resampling(),
                            fc.scenario, fc.frame);
        sets[i].samples.insert(sets[i].samples.end(), s.begin(), s.end());
      }
    }
    for (std::size_t i = 0; i < nets.size(); ++i) {
      const auto counts = sets[i].classCounts();
      std::string msg = what + " " + nets[i].stem + ":";
      for (std::size_t k = 0; k < counts.size(); ++k) msg += " " + kind.classNames()[k] + "=" + std::to_string(counts[k]);
      log(msg);
      for (int count : counts) {
        if (count == 0) throw Error("learn: the " + what + " scenarios give no sample of a class");
      }
    }
    return sets;
  };
  {
    auto sets = heldOut(config.validation, "validation");
    for (std::size_t i = 0; i < nets.size(); ++i) nets[i].validation = std::move(sets[i]);
  }
  std::vector<cnn::Dataset> test_sets;
  if (!config.test.empty()) test_sets = heldOut(config.test, "test");

  auto retrain = [&](RoundReport& rep) {
    for (NetState& st : nets) {
      cnn::Net start = st.net;
      cnn::TrainerParams tp = config.trainer;
      if (!st.trained) start.initialise(tp.seed);
      tp.augmentation.flip_allowed = kind.flipAllowed();
      const cnn::TrainResult tr = cnn::train(start, st.data, st.validation, tp);
      st.net = tr.net;
      st.trained = true;
      rep.dataset_size.push_back(static_cast<int>(st.data.samples.size()));
      rep.validation_accuracy.push_back(tr.validation.accuracy);
      rep.validation_samples.push_back(tr.validation.samples);
    }
  };
  auto logRound = [&](const RoundReport& r) {
    char line[512];
    std::snprintf(line, sizeof line, "round %d (%s): %d frames, %d new samples, %d duplicates dropped", r.round,
                  r.phase.c_str(), r.frames, r.new_samples, r.duplicates);
    std::string msg = line;
    for (std::size_t i = 0; i < nets.size(); ++i) {
      std::snprintf(line, sizeof line, "\n  %-16s wrong before retraining %s, dataset %d, held-out accuracy %.4f (%d)",
                    nets[i].stem.c_str(), r.wrong[i] < 0 ? "-" : std::to_string(r.wrong[i]).c_str(),
                    r.dataset_size[i], r.validation_accuracy[i], r.validation_samples[i]);
      msg += line;
    }
    log(msg);
  };

  // Adds a frame's new candidates (decorrelated) to every net's data; returns the samples per net.
  auto addFrame = [&](FrameCandidates& fc, RoundReport& rep, std::vector<std::vector<cnn::Sample>>& added) {
    std::vector<Candidate> keep;
    for (const Candidate& c : fc.candidates) {
      if (seen.insert(c.key).second) {
        keep.push_back(c);
      } else {
        ++rep.duplicates;
      }
    }
    rep.new_samples += static_cast<int>(keep.size());
    for (std::size_t i = 0; i < nets.size(); ++i) {
      auto s = cutSamples(fc.image, keep, nets[i].data.width, nets[i].net.resampling(), fc.scenario,
                          fc.frame);
      added[i].insert(added[i].end(), s.begin(), s.end());
    }
  };

  const int phases = 1 + config.rounds + (config.bootstrap.empty() ? 0 : config.bootstrap_rounds);
  // Every round's frames rendered up front (each scene built once); the rounds then run in order.
  auto train_frames = renderSources(kind, config.train, 1 + config.rounds, 0, [](int r) {
    return r == 0 ? Collect::kTruthAndProposals : Collect::kProposals;
  }, log);
  std::vector<std::vector<FrameCandidates>> bootstrap_frames;
  if (!config.bootstrap.empty() && config.bootstrap_rounds > 0) {
    bootstrap_frames = renderSources(kind, config.bootstrap, config.bootstrap_rounds, 0,
                                     [](int) { return Collect::kProposals; }, log);
  }
  for (int round = 0; round < phases; ++round) {
    RoundReport rep;
    rep.round = round;
    const bool bootstrap = round > config.rounds;
    rep.phase = round == 0 ? "truth" : bootstrap ? "bootstrap" : "active";
    std::vector<std::vector<cnn::Sample>> added(nets.size());
    if (!bootstrap) {
      for (FrameCandidates& fc : train_frames[round]) addFrame(fc, rep, added);
      rep.frames = static_cast<int>(train_frames[round].size());
      train_frames[round].clear();
    } else {
      // Scenes without the object: the proposals the current first net calls positive with high
      // confidence become hard negatives for every net.
      auto& frames = bootstrap_frames[round - config.rounds - 1];
      rep.frames = static_cast<int>(frames.size());
      for (FrameCandidates& fc : frames) {
                                 {
                                   std::vector<Candidate> confident;
                                   const auto cut =
                                       cutSamples(fc.image, fc.candidates, nets[0].data.width,
                                                  nets[0].net.resampling(), fc.scenario, fc.frame);
                                   const auto score = positiveScores(nets[0].net, cut, kind.positiveLabel());
                                   for (std::size_t k = 0; k < fc.candidates.size(); ++k) {
                                     if (fc.candidates[k].label == kind.negativeLabel() &&
                                         score[k] >= config.bootstrap_min_confidence) {
                                       confident.push_back(fc.candidates[k]);
                                     }
                                   }
                                   fc.candidates = std::move(confident);
                                   addFrame(fc, rep, added);
                                 }
      }
    }
    for (std::size_t i = 0; i < nets.size(); ++i) {
      rep.wrong.push_back(nets[i].trained ? countWrong(nets[i].net, added[i]) : -1);
      auto& d = nets[i].data.samples;
      d.insert(d.end(), std::make_move_iterator(added[i].begin()), std::make_move_iterator(added[i].end()));
    }
    retrain(rep);
    logRound(rep);
    result.rounds.push_back(rep);
  }

  // The dataset folders, then the weights (each through a temporary name).
  namespace fs = std::filesystem;
  if (!config.dataset_dir.empty()) {
    for (NetState& st : nets) {
      const std::string dir = config.dataset_dir + "/" + st.stem;
      const std::string tmp = dir + ".tmp";
      fs::remove_all(tmp);
      for (std::size_t k = 0; k < st.data.samples.size(); ++k) {
        char name[64];
        std::snprintf(name, sizeof name, "%06zu.png", k);
        st.data.samples[k].origin.file = st.data.class_names[st.data.samples[k].label] + "/" + name;
      }
      cnn::writeDataset(st.data, tmp);
      fs::remove_all(dir);
      fs::rename(tmp, dir);
    }
  }
  for (std::size_t i = 0; i < test_sets.size(); ++i) {
    const cnn::Evaluation e = cnn::evaluate(nets[i].net, test_sets[i]);
    result.test_accuracy.push_back(e.accuracy);
    result.test_samples.push_back(e.samples);
    if (!config.dataset_dir.empty()) {
      cnn::Dataset& d = test_sets[i];
      for (std::size_t k = 0; k < d.samples.size(); ++k) {
        char name[64];
        std::snprintf(name, sizeof name, "%06zu.png", k);
        d.samples[k].origin.file = d.class_names[d.samples[k].label] + "/" + name;
      }
      const std::string dir = config.dataset_dir + "/test/" + nets[i].stem;
      fs::create_directories(config.dataset_dir + "/test");
      fs::remove_all(dir + ".tmp");
      cnn::writeDataset(d, dir + ".tmp");
      fs::remove_all(dir);
      fs::rename(dir + ".tmp", dir);
    }
  }
  for (NetState& st : nets) {
    const std::string path = config.model_dir + "/" + st.stem + ".weights";
    cnn::writeDarknetWeights(st.net, path);  // through a temporary name
    result.weights_written.push_back(path);
  }
  return result;
}

}  // namespace colorfree::training
