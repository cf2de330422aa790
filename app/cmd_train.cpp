#include <chrono>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <sstream>
#include <string>

#include "colorfree/perception/cnn/classifier.h"
#include "colorfree/perception/cnn/dataset.h"
#include "colorfree/perception/cnn/net.h"
#include "colorfree/perception/cnn/shipped_nets.h"
#include "colorfree/perception/cnn/trainer.h"
#include "colorfree/perception/error.h"
#include "cnn_table.h"
#include "commands.h"

namespace colorfree::app {

namespace {

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

struct TrainOptions {
  std::string cfg, data, out, validation, init, classes;
  std::vector<std::string> no_flip;
  std::string optimizer = "adam";
  bool no_balance = false, no_augment = false, quiet = false;
  cnn::TrainerParams params;
};

void printConfusion(const cnn::Evaluation& e, const std::vector<std::string>& names) {
  std::printf("confusion (rows truth, columns predicted):\n%12s", "");
  for (const auto& n : names) std::printf(" %10s", n.c_str());
  std::printf("\n");
  for (std::size_t t = 0; t < names.size(); ++t) {
    std::printf("%12s", names[t].c_str());
    for (std::size_t p = 0; p < names.size(); ++p) std::printf(" %10d", e.confusion[t][p]);
    std::printf("\n");
  }
}

void runTrain(const TrainOptions& o, int& exit_code) {
  cnn::Net net = cnn::readDarknetCfg(o.cfg);
  const std::vector<std::string> classes = splitList(o.classes);
  const auto load_start = std::chrono::steady_clock::now();
  const cnn::Dataset data =
      cnn::readDataset(o.data, net.input().width, net.input().height, classes);
  cnn::TrainerParams p = o.params;
  if (o.optimizer == "adam") {
    p.optimizer = cnn::Optimizer::kAdam;
  } else if (o.optimizer == "sgd") {
    p.optimizer = cnn::Optimizer::kSgd;
  } else {
    throw Error("--optimizer must be adam or sgd, not '" + o.optimizer + "'");
  }
  p.balance_classes = !o.no_balance;
  p.augment = !o.no_augment;
  p.augmentation.flip_allowed.assign(data.class_names.size(), true);
  for (const std::string& c : o.no_flip) {
    const auto it = std::find(data.class_names.begin(), data.class_names.end(), c);
    if (it == data.class_names.end()) throw Error("--no-flip: no class '" + c + "' in " + o.data);
    p.augmentation.flip_allowed[it - data.class_names.begin()] = false;
  }
  if (o.init.empty()) {
    net.initialise(p.seed);
  } else {
    cnn::readDarknetWeights(net, o.init);
  }
  const double load_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - load_start).count();
  std::printf("%s: %zu parameters, %lld multiply-adds; %s: %zu patches in %.2f s, classes:",
              o.cfg.c_str(), net.parameterCount(), static_cast<long long>(net.multiplyAdds()),
              o.data.c_str(), data.samples.size(), load_seconds);
  const auto counts = data.classCounts();
  for (std::size_t c = 0; c < counts.size(); ++c)
    std::printf(" %s=%d", data.class_names[c].c_str(), counts[c]);
  std::printf("\n");
  const cnn::EpochCallback report = [&](const cnn::EpochReport& e) {
    if (o.quiet) return;
    std::printf("epoch %3d  train loss %.4f acc %.4f  validation loss %.4f acc %.4f  %.2f s%s\n",
                e.epoch, e.train_loss, e.train_accuracy, e.validation.loss, e.validation.accuracy,
                e.seconds, e.best ? "  *" : "");
    std::fflush(stdout);
  };
  cnn::TrainResult r;
  if (o.validation.empty()) {
    r = cnn::train(net, data, p, report);
  } else {
    const cnn::Dataset val =
        cnn::readDataset(o.validation, net.input().width, net.input().height, data.class_names);
    r = cnn::train(net, data, val, p, report);
  }
  cnn::writeDarknetWeights(r.net, o.out);
  std::printf(
      "best epoch %d of %zu: validation accuracy %.4f on %d samples (%d wrong); trained on %d in "
      "%.2f s\n",
      r.best_epoch, r.epochs.size(), r.validation.accuracy, r.validation.samples,
      static_cast<int>(r.validation.wrong.size()), r.train_samples, r.seconds);
  printConfusion(r.validation, data.class_names);
  std::printf("wrote %s\n", o.out.c_str());
  exit_code = 0;
}

double threadCpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// Median CPU time per patch of `classifier` in µs, for batches of `batch` (CPU time: on a shared
// machine wall time also counts other processes).
double timePerPatchUs(const cnn::Classifier& classifier, int batch) {
  std::vector<float> inputs(static_cast<std::size_t>(batch) * classifier.input().size());
  for (std::size_t i = 0; i < inputs.size(); ++i)
    inputs[i] = static_cast<float>((i * 37) % 101) / 50.0f - 1.0f;
  std::vector<float> probs(static_cast<std::size_t>(batch) * classifier.classes());
  std::vector<double> runs;
  for (int rep = 0; rep < 7; ++rep) {
    const int iterations = 4000 / batch + 1;
    const double t0 = threadCpuSeconds();
    for (int i = 0; i < iterations; ++i) classifier.run(inputs.data(), batch, probs.data());
    runs.push_back((threadCpuSeconds() - t0) * 1e6 / (static_cast<double>(iterations) * batch));
  }
  std::sort(runs.begin(), runs.end());
  return runs[runs.size() / 2];
}

std::string fixed3(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", v);
  return buf;
}

void runTable(const std::string& models, const std::string& data_root) {
  std::printf(
      "Table 1 for our nets (time: this machine, one core, median CPU time; paper: NAO V5)\n\n");
  std::printf(
      "| net | input | parameters (paper) | multiply-adds | µs/patch single | µs/patch batch 16 | "
      "paper ms | accuracy | paper accuracy |\n");
  std::printf("| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n");
  for (const CnnTableRow& r : cnnTable(models, data_root)) {
    const bool paper = r.hasPaperFigures();
    std::printf("| %s | %dx%dx%d | %lld (%s) | %lld | %.2f | %.2f | %s | %s | %s |\n", r.name.c_str(), r.input_width,
                r.input_height, r.input_channels, r.parameters,
                paper ? std::to_string(r.paper_parameters).c_str() : "-", r.multiply_adds, r.us_per_patch_single,
                r.us_per_patch_batch16, paper ? fixed3(r.paper_time_ms).c_str() : "-", r.accuracy.c_str(),
                paper ? fixed3(r.paper_accuracy).c_str() : "-");
  }
}

}  // namespace

std::vector<CnnTableRow> cnnTable(const std::string& models, const std::string& data_root) {
  std::vector<CnnTableRow> rows;
  for (const cnn::ShippedNet& s : cnn::kShippedNets) {
    const std::string cfg = models + "/" + s.stem + ".cfg",
                      weights = models + "/" + s.stem + ".weights";
    cnn::Net net = cnn::readDarknetCfg(cfg);
    const bool trained = std::filesystem::exists(weights);
    if (trained) {
      cnn::readDarknetWeights(net, weights);
    } else {
      net.initialise(1);
    }
    const cnn::Classifier classifier(net);
    std::string accuracy = trained ? "no held-out data" : "untrained";
    const std::string held_out = data_root + "/" + s.stem;
    if (trained && !data_root.empty() && std::filesystem::is_directory(held_out)) {
      const cnn::Dataset d =
          cnn::readDataset(held_out, net.input().width, net.input().height, s.classNames());
      const cnn::Evaluation e = cnn::evaluate(net, d);
      char buf[64];
      std::snprintf(buf, sizeof(buf), "%.3f (%d)", e.accuracy, e.samples);
      accuracy = buf;
    }
    CnnTableRow r;
    r.name = s.name;
    r.input_width = net.input().width;
    r.input_height = net.input().height;
    r.input_channels = net.input().channels;
    r.parameters = static_cast<long long>(net.parameterCount());
    r.paper_parameters = s.paper_parameters;
    r.multiply_adds = static_cast<long long>(net.multiplyAdds());
    r.us_per_patch_single = timePerPatchUs(classifier, 1);
    r.us_per_patch_batch16 = timePerPatchUs(classifier, 16);
    r.paper_time_ms = s.paper_time_ms;
    r.trained = trained;
    r.accuracy = accuracy;
    r.paper_accuracy = s.paper_accuracy;
    rows.push_back(r);
  }
  return rows;
}

void addTrainCommand(CLI::App& app, int& exit_code) {
  auto o = std::make_shared<TrainOptions>();
  CLI::App* cmd =
      app.add_subcommand("train", "Train a tiny CNN (Darknet cfg) on a folder of labelled patches");
  cmd->add_option("--cfg", o->cfg, "Darknet cfg of the net")->required();
  cmd->add_option("--data", o->data,
                  "dataset folder: one sub-folder of PNG patches per class, optional manifest.csv")
      ->required();
  cmd->add_option("--out", o->out, "weights file to write (Darknet format)")->required();
  cmd->add_option("--classes", o->classes,
                  "class folders in label order, comma-separated (default: sorted)");
  cmd->add_option("--validation", o->validation,
                  "held-out dataset folder (default: a split of --data)");
  cmd->add_option("--init", o->init, "start from these weights instead of a seeded initialisation");
  cmd->add_option("--optimizer", o->optimizer, "adam or sgd")->capture_default_str();
  cmd->add_option("--lr", o->params.learning_rate, "learning rate")->capture_default_str();
  cmd->add_option("--momentum", o->params.momentum, "SGD momentum / Adam beta1")
      ->capture_default_str();
  cmd->add_option("--weight-decay", o->params.weight_decay, "L2 on weights")->capture_default_str();
  cmd->add_option("--batch", o->params.batch_size, "samples per step")->capture_default_str();
  cmd->add_option("--epochs", o->params.max_epochs, "most epochs")->capture_default_str();
  cmd->add_option("--patience", o->params.patience_epochs,
                  "epochs without improvement before stopping")
      ->capture_default_str();
  cmd->add_option("--validation-fraction", o->params.validation_fraction, "held out per class")
      ->capture_default_str();
  cmd->add_option("--seed", o->params.seed, "seed of initialisation, split, order and augmentation")
      ->capture_default_str();
  cmd->add_option("--no-flip", o->no_flip, "classes that must not be mirrored");
  cmd->add_flag("--no-balance", o->no_balance, "do not weight the loss by inverse class frequency");
  cmd->add_flag("--no-augment", o->no_augment, "no augmentation");
  cmd->add_flag("--quiet", o->quiet, "no per-epoch lines");
  cmd->callback([o, &exit_code] { runTrain(*o, exit_code); });

  auto models = std::make_shared<std::string>(cnn::defaultModelDir());
  auto data_root = std::make_shared<std::string>();
  CLI::App* table = app.add_subcommand(
      "cnn-table", "Print the paper's Table 1 for our nets, timed on this machine");
  table->add_option("--models", *models, "folder of the nets' cfg and weights")
      ->capture_default_str();
  table->add_option("--data", *data_root,
                    "folder with one held-out dataset folder per net (robot_net/, ...)");
  table->callback([models, data_root, &exit_code] {
    runTable(*models, *data_root);
    exit_code = 0;
  });
}

}  // namespace colorfree::app
