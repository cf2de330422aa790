#pragma once

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace colorfree::app {

/// What an experiment of the bench list reproduces; decides where its numbers go in the tables.
enum class ExperimentRole { kDetection, kOrientationStatic, kOrientationDynamic, kSweep, kScenario };
std::string roleName(ExperimentRole role);

/// One scenario of the bench list (scenes/bench.yaml) with what the bench needs to score it.
struct BenchExperiment {
  std::string id;  ///< unique in the list, e.g. "detection"
  ExperimentRole role = ExperimentRole::kScenario;
  std::string title;
  std::string scenario_path;  ///< resolved against the list's folder
  std::string scenario_name;
  std::uint64_t seed = 0;
  int frames_per_case = 0;  ///< after the list's frames / quick_frames override
  int cases = 0;
  double orientation_tolerance_deg = 22.5;
  /// A sweep's charted setting: its scenario's first `sweep:` path (the others are averaged over,
  /// e.g. the headings of an orientation sweep); empty for other roles.
  std::string swept_setting;
  std::vector<std::string> expectations;  ///< the scenario's `expect:` texts
  std::vector<double> case_costs;         ///< relative render cost per case (for balancing)
};

/// The bench list parsed and expanded: every experiment and the targets of the sweep charts.
struct BenchPlan {
  std::string list_path;
  bool quick = false;
  std::vector<BenchExperiment> experiments;
  std::map<std::string, double> targets;  ///< metric -> least acceptable rate in a sweep
  bool cnn_table = true;                  ///< time the shipped nets (the paper's Table 1)
  std::uint64_t fingerprint = 0;          ///< of the list, every scenario file, quick and the code
  nlohmann::json toJson() const;
  static BenchPlan fromJson(const nlohmann::json& j);
};

/// Loads the bench list strictly (unknown or missing keys name the file); loads every scenario it
/// names, so a broken scenario fails before anything renders.
BenchPlan loadBenchPlan(const std::string& list_path, bool quick);

/// One unit of work: a case of an experiment, or the CNN table.
struct WorkItem {
  int experiment = -1;  ///< index into plan.experiments; -1 = the CNN table
  int case_index = 0;
  double cost = 0;
};

/// Every work item in canonical order (experiments in list order, cases in order, CNN table last).
std::vector<WorkItem> allWorkItems(const BenchPlan& plan);
/// The items of shard `shard` of `shards`: a deterministic greedy balance by cost (largest first,
/// to the least loaded shard, lowest shard on ties); every item belongs to exactly one shard.
std::vector<WorkItem> shardItems(const BenchPlan& plan, int shard, int shards);

/// Stable 64-bit FNV-1a hash (the same on every machine and build).
std::uint64_t fnv1a(const std::string& text, std::uint64_t hash = 0xcbf29ce484222325ULL);

}  // namespace colorfree::app
