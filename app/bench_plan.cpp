#include "bench_plan.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "colorfree/groundtruth/results.h"
#include "colorfree/perception/error.h"
#include "colorfree/sim/scenario.h"
#include "code_version.h"

namespace colorfree::app {
namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

std::string readText(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot read");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

ExperimentRole parseRole(const std::string& text, const std::string& where) {
  if (text == "detection") return ExperimentRole::kDetection;
  if (text == "orientation_static") return ExperimentRole::kOrientationStatic;
  if (text == "orientation_dynamic") return ExperimentRole::kOrientationDynamic;
  if (text == "sweep") return ExperimentRole::kSweep;
  if (text == "scenario") return ExperimentRole::kScenario;
  throw Error(where + ": role '" + text +
              "' is not one of detection, orientation_static, orientation_dynamic, sweep, scenario");
}

std::string where(const std::string& path, const YAML::Node& node, const std::string& key) {
  return path + ":" + std::to_string(node.Mark().line + 1) + ": " + key;
}

void checkKeys(const YAML::Node& node, const std::set<std::string>& allowed, const std::string& path,
               const std::string& prefix) {
  if (!node.IsMap()) throw Error(where(path, node, prefix) + ": expected a mapping");
  for (const auto& kv : node) {
    const std::string key = kv.first.as<std::string>();
    if (!allowed.count(key)) throw Error(where(path, kv.first, prefix + key) + ": unknown key");
  }
}

template <typename T>
T get(const YAML::Node& node, const std::string& key, const std::string& path, const std::string& prefix) {
  if (!node[key]) throw Error(where(path, node, prefix + key) + ": missing required key");
  try {
    return node[key].as<T>();
  } catch (const YAML::Exception&) {
    throw Error(where(path, node[key], prefix + key) + ": value of the wrong type");
  }
}

}  // namespace

std::string roleName(ExperimentRole role) {
  switch (role) {
    case ExperimentRole::kDetection: return "detection";
    case ExperimentRole::kOrientationStatic: return "orientation_static";
    case ExperimentRole::kOrientationDynamic: return "orientation_dynamic";
    case ExperimentRole::kSweep: return "sweep";
    case ExperimentRole::kScenario: return "scenario";
  }
  return "scenario";
}

std::uint64_t fnv1a(const std::string& text, std::uint64_t hash) {
  for (unsigned char c : text) {
    hash ^= c;
    hash *= 0x100000001b3ULL;
  }
  return hash;
}

BenchPlan loadBenchPlan(const std::string& list_path, bool quick) {
  namespace fs = std::filesystem;
  const std::string text = readText(list_path);
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw Error(list_path + ":" + std::to_string(e.mark.line + 1) + ": malformed YAML: " + e.msg);
  }
  checkKeys(root, {"targets", "cnn_table", "experiments"}, list_path, "");
  BenchPlan plan;
  plan.list_path = list_path;
  plan.quick = quick;
  std::uint64_t hash = fnv1a(text);
  hash = fnv1a(quick ? "quick" : "full", hash);
  hash = fnv1a(codeVersion(), hash);
  if (root["targets"]) {
    checkKeys(root["targets"], {"ball.detection_rate", "robot.detection_rate", "field_features.line_detection_rate",
                                "field_features.intersection_detection_rate", "orientation.filtered.perceived"},
              list_path, "targets.");
    for (const auto& kv : root["targets"]) {
      const std::string key = kv.first.as<std::string>();
      const double v = get<double>(root["targets"], key, list_path, "targets.");
      if (!(v >= 0 && v <= 1)) throw Error(where(list_path, kv.second, "targets." + key) + ": must be in [0, 1]");
      plan.targets[key] = v;
    }
  }
  if (root["cnn_table"]) plan.cnn_table = get<bool>(root, "cnn_table", list_path, "");
  hash = fnv1a(plan.cnn_table ? "cnn" : "nocnn", hash);
  const YAML::Node list = root["experiments"];
  if (!list || !list.IsSequence() || list.size() == 0) {
    throw Error(list_path + ": experiments: missing or empty list");
  }
  const fs::path folder = fs::path(list_path).parent_path();
  std::set<std::string> ids;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const YAML::Node e = list[i];
    const std::string prefix = "experiments[" + std::to_string(i) + "].";
    checkKeys(e, {"id", "role", "title", "scenario", "frames", "quick_frames"}, list_path, prefix);
    BenchExperiment x;
    x.id = get<std::string>(e, "id", list_path, prefix);
    if (x.id.empty() || !ids.insert(x.id).second) {
      throw Error(where(list_path, e, prefix + "id") + ": '" + x.id + "' is empty or not unique");
    }
    x.role = parseRole(get<std::string>(e, "role", list_path, prefix), where(list_path, e, prefix + "role"));
    x.title = get<std::string>(e, "title", list_path, prefix);
    x.scenario_path = (folder / get<std::string>(e, "scenario", list_path, prefix)).lexically_normal().string();
    const sim::Scenario s = sim::Scenario::load(x.scenario_path);
    hash = fnv1a(readText(x.scenario_path), hash);
    x.scenario_name = s.name;
    x.seed = s.cases.front().settings.seed;
    x.cases = static_cast<int>(s.cases.size());
    x.frames_per_case = s.cases.front().settings.frames;
    const std::string frames_key = quick ? "quick_frames" : "frames";
    if (e[frames_key]) {
      x.frames_per_case = get<int>(e, frames_key, list_path, prefix);
      if (x.frames_per_case < 1 || x.frames_per_case > 100000) {
        throw Error(where(list_path, e[frames_key], prefix + frames_key) + ": must be in 1..100000");
      }
    }
    // Rounded to a milli-degree: the scenario keeps 22.5° as 0.3927 rad (as colorfree run does).
    x.orientation_tolerance_deg =
        std::round(s.cases.front().settings.orientation_tolerance_rad * kRadToDeg * 1e3) / 1e3;
    for (const auto& ex : s.expect) {
      // An expectation naming an unknown metric is an error before anything renders.
      const std::string origin = x.scenario_path + ":" + std::to_string(ex.line);
      validateExpectations({parseExpectation(ex.text, origin)}, origin);
      x.expectations.push_back(ex.text);
    }
    for (const auto& c : s.cases) {
      const auto& st = c.settings;
      const double pixels = static_cast<double>(st.width_px) * st.height_px / (640.0 * 480.0);
      x.case_costs.push_back(x.frames_per_case * std::max(1, st.effects.blur_subframes) * (0.3 + pixels));
    }
    if (x.role == ExperimentRole::kSweep && s.sweep.empty()) {
      throw Error(where(list_path, e, prefix + "role") + ": a sweep experiment needs a scenario with `sweep:` (" +
                  x.scenario_path + ")");
    }
    if (x.role == ExperimentRole::kSweep) x.swept_setting = s.sweep.front().path;
    plan.experiments.push_back(x);
  }
  plan.fingerprint = hash;
  return plan;
}

nlohmann::json BenchPlan::toJson() const {
  nlohmann::json j;
  j["list"] = list_path;
  j["quick"] = quick;
  j["fingerprint"] = fingerprint;
  j["targets"] = targets;
  j["cnn_table"] = cnn_table;
  j["experiments"] = nlohmann::json::array();
  for (const auto& e : experiments) {
    j["experiments"].push_back({{"id", e.id},
                                {"role", roleName(e.role)},
                                {"title", e.title},
                                {"scenario_path", e.scenario_path},
                                {"scenario", e.scenario_name},
                                {"seed", e.seed},
                                {"frames_per_case", e.frames_per_case},
                                {"cases", e.cases},
                                {"orientation_tolerance_deg", e.orientation_tolerance_deg},
                                {"swept_setting", e.swept_setting},
                                {"expectations", e.expectations},
                                {"case_costs", e.case_costs}});
  }
  return j;
}

BenchPlan BenchPlan::fromJson(const nlohmann::json& j) {
  BenchPlan p;
  try {
    p.list_path = j.at("list").get<std::string>();
    p.quick = j.at("quick").get<bool>();
    p.fingerprint = j.at("fingerprint").get<std::uint64_t>();
    p.targets = j.at("targets").get<std::map<std::string, double>>();
    p.cnn_table = j.at("cnn_table").get<bool>();
    for (const auto& e : j.at("experiments")) {
      BenchExperiment x;
      x.id = e.at("id").get<std::string>();
      x.role = parseRole(e.at("role").get<std::string>(), "plan");
      x.title = e.at("title").get<std::string>();
      x.scenario_path = e.at("scenario_path").get<std::string>();
      x.scenario_name = e.at("scenario").get<std::string>();
      x.seed = e.at("seed").get<std::uint64_t>();
      x.frames_per_case = e.at("frames_per_case").get<int>();
      x.cases = e.at("cases").get<int>();
      x.orientation_tolerance_deg = e.at("orientation_tolerance_deg").get<double>();
      x.swept_setting = e.at("swept_setting").get<std::string>();
      x.expectations = e.at("expectations").get<std::vector<std::string>>();
      x.case_costs = e.at("case_costs").get<std::vector<double>>();
      p.experiments.push_back(x);
    }
  } catch (const nlohmann::json::exception& e) {
    throw Error(std::string("bench plan: ") + e.what());
  }
  return p;
}

std::vector<WorkItem> allWorkItems(const BenchPlan& plan) {
  std::vector<WorkItem> items;
  for (int e = 0; e < static_cast<int>(plan.experiments.size()); ++e) {
    for (int c = 0; c < plan.experiments[e].cases; ++c) items.push_back({e, c, plan.experiments[e].case_costs[c]});
  }
  // The CNN table times each net for a few seconds: about the cost of 30 frames.
  if (plan.cnn_table) items.push_back({-1, 0, 30});
  return items;
}

std::vector<WorkItem> shardItems(const BenchPlan& plan, int shard, int shards) {
  if (shards < 1 || shard < 0 || shard >= shards) {
    throw Error("--shard " + std::to_string(shard) + "/" + std::to_string(shards) + ": need 0 <= i < n");
  }
  const std::vector<WorkItem> items = allWorkItems(plan);
  std::vector<int> order(items.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = static_cast<int>(i);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return items[a].cost > items[b].cost; });
  std::vector<double> load(static_cast<std::size_t>(shards), 0.0);
  std::vector<int> owner(items.size(), 0);
  for (int i : order) {
    const int s = static_cast<int>(std::min_element(load.begin(), load.end()) - load.begin());
    owner[i] = s;
    load[s] += items[i].cost;
  }
  std::vector<WorkItem> mine;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (owner[i] == shard) mine.push_back(items[i]);
  }
  return mine;
}

}  // namespace colorfree::app
