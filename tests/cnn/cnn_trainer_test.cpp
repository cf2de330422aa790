// The trainer learns separable synthetic patches, is deterministic, honours flip permissions;
// datasets round-trip through folders and reject bad files by name.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <set>

#include "colorfree/perception/cnn/classifier.h"
#include "colorfree/perception/cnn/dataset.h"
#include "colorfree/perception/cnn/net.h"
#include "colorfree/perception/cnn/trainer.h"
#include "colorfree/perception/error.h"

namespace colorfree::cnn {
namespace {

// Class 1: a dark disc of random radius near the centre on a lighter background; class 0: the
// same background with a dark straight edge somewhere. Brightness, contrast and noise vary.
Dataset discDataset(int side, int count, std::uint64_t seed) {
  Dataset d;
  d.width = d.height = side;
  d.class_names = {"none", "disc"};
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::normal_distribution<float> noise(0.0f, 6.0f);
  for (int i = 0; i < count; ++i) {
    Sample s;
    s.label = i % 2;
    s.patch = GrayImage(side, side);
    const float bg = 120.0f + 100.0f * u(rng), fg = bg * (0.2f + 0.4f * u(rng));
    const float cx = side * (0.4f + 0.2f * u(rng)), cy = side * (0.4f + 0.2f * u(rng));
    const float r = side * (0.2f + 0.15f * u(rng));
    const float angle = 6.2832f * u(rng), offset = side * (u(rng) - 0.5f);
    for (int y = 0; y < side; ++y) {
      for (int x = 0; x < side; ++x) {
        const bool dark =
            s.label == 1
                ? std::hypot(x + 0.5f - cx, y + 0.5f - cy) < r
                : (x - side / 2) * std::cos(angle) + (y - side / 2) * std::sin(angle) > offset;
        s.patch.at(x, y) =
            static_cast<std::uint8_t>(std::clamp((dark ? fg : bg) + noise(rng), 0.0f, 255.0f));
      }
    }
    s.origin.scenario = "synthetic";
    s.origin.frame = i;
    d.samples.push_back(std::move(s));
  }
  return d;
}

// Class 0: bright left half; class 1: bright right half. Only a mirror tells them apart.
Dataset sideDataset(int side, int count, std::uint64_t seed) {
  Dataset d;
  d.width = d.height = side;
  d.class_names = {"left", "right"};
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> noise(0.0f, 10.0f);
  for (int i = 0; i < count; ++i) {
    Sample s;
    s.label = i % 2;
    s.patch = GrayImage(side, side);
    for (int y = 0; y < side; ++y) {
      for (int x = 0; x < side; ++x) {
        const bool bright = (x < side / 2) == (s.label == 0);
        s.patch.at(x, y) = static_cast<std::uint8_t>(
            std::clamp((bright ? 180.0f : 70.0f) + noise(rng), 0.0f, 255.0f));
      }
    }
    d.samples.push_back(std::move(s));
  }
  return d;
}

Net boostNet(std::uint64_t seed) {
  Net net = readDarknetCfg(defaultModelDir() + "/boost_ball_net.cfg");
  net.initialise(seed);
  return net;
}

TrainerParams quickParams() {
  TrainerParams p;
  p.max_epochs = 8;
  p.patience_epochs = 8;
  p.seed = 4;
  return p;
}

TEST(CnnTrainer, LearnsSeparablePatchesAndScoresHeldOutData) {
  const Dataset data = discDataset(12, 1200, 1);
  const TrainResult r = train(boostNet(1), data, quickParams());
  EXPECT_GE(r.validation.accuracy, 0.95);
  EXPECT_EQ(r.validation.samples, 180);  // 15 % of each class
  EXPECT_EQ(r.train_samples, 1020);
  EXPECT_GE(r.best_epoch, 1);
  EXPECT_LT(r.epochs.back().train_loss, r.epochs.front().train_loss);
  // Fresh samples from the same distribution, never seen.
  const Evaluation fresh = evaluate(r.net, discDataset(12, 400, 99));
  EXPECT_GE(fresh.accuracy, 0.95);
  EXPECT_EQ(fresh.confusion[0][0] + fresh.confusion[0][1], 200);
  // The classifier (inference engine) agrees with the trainer's evaluation.
  const Classifier classifier(r.net);
  std::vector<float> probs(2);
  int wrong = 0;
  for (const Sample& s : discDataset(12, 400, 99).samples) {
    std::vector<float> patch(144);
    for (int i = 0; i < 144; ++i) patch[i] = s.patch.data()[i];
    normalizePatch(patch.data(), 144, r.net.normalization());
    classifier.run(patch.data(), 1, probs.data());
    wrong += (probs[1] > probs[0]) != (s.label == 1);
  }
  EXPECT_EQ(wrong, static_cast<int>(fresh.wrong.size()));
}

TEST(CnnTrainer, UntrainedNetIsNoBetterThanChance) {
  const Evaluation e = evaluate(boostNet(1), discDataset(12, 400, 99));
  EXPECT_LT(e.accuracy, 0.8);
}

TEST(CnnTrainer, SameSeedSameWeightsOtherSeedOtherWeights) {
  const Dataset data = discDataset(12, 300, 2);
  TrainerParams p = quickParams();
  p.max_epochs = 2;
  const TrainResult a = train(boostNet(3), data, p);
  const TrainResult b = train(boostNet(3), data, p);
  EXPECT_EQ(a.net.params(), b.net.params());
  p.seed = 5;
  const TrainResult c = train(boostNet(3), data, p);
  EXPECT_NE(a.net.params(), c.net.params());
}

TEST(CnnTrainer, SgdWithMomentumLearnsToo) {
  TrainerParams p = quickParams();
  p.optimizer = Optimizer::kSgd;
  p.learning_rate = 0.02f;
  const TrainResult r = train(boostNet(1), discDataset(12, 1200, 1), p);
  EXPECT_GE(r.validation.accuracy, 0.9);
}

TEST(CnnTrainer, FlipsOnlyWhereTheLabelAllows) {
  const Dataset data = sideDataset(12, 600, 3);
  TrainerParams p = quickParams();
  p.augmentation.flip_allowed = {false, false};
  EXPECT_GE(train(boostNet(2), data, p).validation.accuracy, 0.95);
  // Mirroring left into right with the label kept makes the classes indistinguishable.
  p.augmentation.flip_allowed = {true, true};
  EXPECT_LT(train(boostNet(2), data, p).validation.accuracy, 0.8);
}

TEST(CnnTrainer, BorderCutRepeatsTheEdgeRowOrColumnOnOneSide) {
  // A patch whose every pixel differs: the cut shows as runs of equal values.
  GrayImage patch(12, 12);
  for (int y = 0; y < 12; ++y)
    for (int x = 0; x < 12; ++x) patch.at(x, y) = static_cast<std::uint8_t>(10 + 12 * y + x);
  AugmentationParams p;  // geometry and photometry off: only the cut remains
  p.brightness = p.contrast = p.noise_stddev = p.blur_probability = p.shift_px = p.scale = 0.0f;
  p.border_cut_probability = 1.0f;
  p.border_cut_max_fraction = 0.5f;
  std::mt19937_64 rng(3);
  std::set<std::pair<int, int>> cuts_seen;  // (side, depth)
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<float> out(144);
    augmentPatch(patch, p, false, rng, out.data());
    // The output is the patch cut on exactly one side (0 left, 1 right, 2 top, 3 bottom) from
    // exactly one depth: the pixels beyond the cut repeat the last row or column before it.
    int matches = 0;
    for (int side = 0; side < 4; ++side) {
      for (int depth = 1; depth <= 6; ++depth) {
        bool same = true;
        for (int y = 0; y < 12 && same; ++y) {
          for (int x = 0; x < 12 && same; ++x) {
            int sx = x, sy = y;
            if (side == 0) sx = std::max(x, depth);
            if (side == 1) sx = std::min(x, 11 - depth);
            if (side == 2) sy = std::max(y, depth);
            if (side == 3) sy = std::min(y, 11 - depth);
            same = out[y * 12 + x] == static_cast<float>(patch.at(sx, sy));
          }
        }
        if (same) ++matches, cuts_seen.insert({side, depth});
      }
    }
    ASSERT_EQ(matches, 1) << "trial " << trial;
  }
  EXPECT_EQ(cuts_seen.size(), 24u);  // every side, every depth 1..6
  // Corners: with the corner share at 1, every cut is on two adjacent sides, each with its depth.
  p.border_cut_corner_probability = 1.0f;
  for (int trial = 0; trial < 100; ++trial) {
    std::vector<float> out(144);
    augmentPatch(patch, p, false, rng, out.data());
    int matches = 0;
    for (int lr = 0; lr < 2; ++lr) {
      for (int tb = 2; tb < 4; ++tb) {
        for (int du = 1; du <= 6; ++du) {
          for (int dv = 1; dv <= 6; ++dv) {
            bool same = true;
            for (int y = 0; y < 12 && same; ++y) {
              for (int x = 0; x < 12 && same; ++x) {
                const int sx = lr == 0 ? std::max(x, du) : std::min(x, 11 - du);
                const int sy = tb == 2 ? std::max(y, dv) : std::min(y, 11 - dv);
                same = out[y * 12 + x] == static_cast<float>(patch.at(sx, sy));
              }
            }
            matches += same;
          }
        }
      }
    }
    ASSERT_EQ(matches, 1) << "trial " << trial;
  }
  // Probability 0: never cut.
  p.border_cut_probability = 0.0f;
  std::vector<float> out(144);
  augmentPatch(patch, p, false, rng, out.data());
  for (int i = 0; i < 144; ++i) ASSERT_EQ(out[i], static_cast<float>(patch.data()[i]));
}

TEST(CnnTrainer, EarlyStoppingKeepsTheBestEpoch) {
  TrainerParams p = quickParams();
  p.max_epochs = 40;
  p.patience_epochs = 2;
  const TrainResult r = train(boostNet(1), discDataset(12, 400, 1), p);
  ASSERT_LT(static_cast<int>(r.epochs.size()), 40);
  EXPECT_EQ(static_cast<int>(r.epochs.size()), r.best_epoch + 2);
  EXPECT_DOUBLE_EQ(r.validation.accuracy, r.epochs[r.best_epoch - 1].validation.accuracy);
}

TEST(CnnTrainer, RejectsDataThatDoesNotFitTheNet) {
  TrainerParams p = quickParams();
  EXPECT_THROW(train(boostNet(1), discDataset(13, 40, 1), p), Error);
  Dataset one_class = discDataset(12, 40, 1);
  for (Sample& s : one_class.samples) s.label = 0;
  EXPECT_THROW(train(boostNet(1), one_class, p), Error);
  EXPECT_THROW(train(readDarknetCfg(defaultModelDir() + "/ori_boost_net.cfg"),
                     discDataset(12, 40, 1), Dataset{12, 12, {"a", "b", "c"}, {}}, p),
               Error);
}

class CnnDataset : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = ::testing::TempDir() + "/cnn_dataset_" +
           ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::filesystem::remove_all(dir_);
  }
  std::string dir_;
};

template <typename F>
void expectErrorNaming(F&& f, const std::string& part) {
  try {
    f();
    ADD_FAILURE() << "no colorfree::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

TEST_F(CnnDataset, RoundTripsThroughFoldersAndManifest) {
  Dataset d = discDataset(12, 10, 5);
  d.samples[3].origin = {"", "kickoff_dim", 17, 100.5f, 50.0f, 30.0f, 30.0f, "ball d=2.3m"};
  writeDataset(d, dir_);
  const Dataset back = readDataset(dir_, 12, 12);
  EXPECT_EQ(back.class_names, (std::vector<std::string>{"disc", "none"}));  // sorted folder names
  ASSERT_EQ(back.samples.size(), 10u);
  const Dataset ordered = readDataset(dir_, 12, 12, {"none", "disc"});
  int found = 0;
  for (const Sample& s : ordered.samples) {
    if (s.origin.scenario == "kickoff_dim") {
      ++found;
      EXPECT_EQ(s.origin.frame, 17);
      EXPECT_FLOAT_EQ(s.origin.x_px, 100.5f);
      EXPECT_EQ(s.origin.truth, "ball d=2.3m");
      EXPECT_EQ(s.label, 1);
      EXPECT_EQ(s.patch.pixels(), d.samples[3].patch.pixels());
    }
  }
  EXPECT_EQ(found, 1);
  EXPECT_EQ(ordered.classCounts(), (std::vector<int>{5, 5}));
}

TEST_F(CnnDataset, BadFilesAreNamed) {
  writeDataset(discDataset(12, 6, 5), dir_);
  expectErrorNaming([&] { readDataset(dir_, 13, 12); }, "disc/000000.png");
  expectErrorNaming([&] { readDataset(dir_, 12, 12, {"none", "ghost"}); }, "ghost");
  std::ofstream(dir_ + "/disc/broken.png") << "not a png";
  expectErrorNaming([&] { readDataset(dir_, 12, 12); }, "disc/broken.png");
  std::filesystem::remove(dir_ + "/disc/broken.png");
  writeGrayPng(dir_ + "/disc/big.png", GrayImage(20, 12).view());
  expectErrorNaming([&] { readDataset(dir_, 12, 12); }, "disc/big.png");
  std::filesystem::remove(dir_ + "/disc/big.png");
  std::filesystem::rename(dir_ + "/disc/000000.png", dir_ + "/none/000009.png");
  expectErrorNaming([&] { readDataset(dir_, 12, 12); }, "disc/000000.png");
  std::filesystem::rename(dir_ + "/none/000009.png", dir_ + "/disc/000000.png");
  std::ofstream(dir_ + "/manifest.csv", std::ios::app) << "disc/000001.png,none,s,1,0,0,1,1,x\n";
  expectErrorNaming([&] { readDataset(dir_, 12, 12); }, "manifest.csv");
  expectErrorNaming([&] { readDataset(dir_ + "/nothing", 12, 12); }, "nothing");
}

}  // namespace
}  // namespace colorfree::cnn
