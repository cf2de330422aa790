#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>

#include "bench_plan.h"
#include "bench_report.h"
#include "cnn_table.h"
#include "colorfree/groundtruth/report.h"
#include "colorfree/groundtruth/results.h"
#include "colorfree/groundtruth/scorer.h"
#include "colorfree/groundtruth/scoring_params.h"
#include "colorfree/perception/cnn/shipped_nets.h"
#include "colorfree/perception/field_dimensions.h"
#include "colorfree/sim/runner.h"
#include "colorfree/sim/scenario.h"
#include "colorfree/sim/world_renderer.h"
#include "code_version.h"
#include "commands.h"
#include "run_perception.h"

namespace colorfree::app {
namespace {

using json = nlohmann::json;
namespace fs = std::filesystem;
constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;
constexpr const char* kShardFormat = "colorfree-bench-shard/1";

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

ScoringParams scoringFor(const BenchExperiment& e) {
  ScoringParams p = ScoringParams::loadDefault();
  p.orientation_tolerance_deg = e.orientation_tolerance_deg;
  return p;
}

std::string itemName(const BenchPlan& plan, const WorkItem& item) {
  if (item.experiment < 0) return "cnn_table";
  char buf[32];
  std::snprintf(buf, sizeof buf, "case_%03d", item.case_index);
  return plan.experiments[item.experiment].id + "/" + buf;
}

json cnnTableJson() {
  json rows = json::array();
  for (const CnnTableRow& r : cnnTable(cnn::defaultModelDir(), "")) {
    const bool paper = r.hasPaperFigures();
    const auto paperFigure = [paper](double v) { return paper ? json(v) : json(nullptr); };
    rows.push_back({{"net", r.name},
                    {"input", std::to_string(r.input_width) + "x" + std::to_string(r.input_height) + "x" +
                                  std::to_string(r.input_channels)},
                    {"parameters", r.parameters},
                    {"paper_parameters", paperFigure(r.paper_parameters)},
                    {"multiply_adds", r.multiply_adds},
                    {"us_per_patch_single", r.us_per_patch_single},
                    {"us_per_patch_batch16", r.us_per_patch_batch16},
                    {"paper_time_ms", paperFigure(r.paper_time_ms)},
                    {"trained", r.trained},
                    {"accuracy", r.accuracy},
                    {"paper_accuracy", paperFigure(r.paper_accuracy)}});
  }
  return rows;
}

// Renders and scores the items (cases grouped by experiment so that a World is reused), each case
// with a fresh scorer and pipeline so that its state does not depend on what ran before.
json runItems(const BenchPlan& plan, std::vector<WorkItem> items, const std::string& who) {
  std::stable_sort(items.begin(), items.end(), [](const WorkItem& a, const WorkItem& b) {
    return a.experiment != b.experiment ? a.experiment < b.experiment : a.case_index < b.case_index;
  });
  json out = json::array();
  const FieldDimensions dims = FieldDimensions::loadDefault();
  std::unique_ptr<sim::ScenarioRunner> runner;
  int runner_experiment = -2;
  int done = 0;
  for (const WorkItem& item : items) {
    const auto t0 = std::chrono::steady_clock::now();
    if (item.experiment < 0) {
      out.push_back({{"item", "cnn_table"}, {"cnn_table", cnnTableJson()}});
    } else {
      const BenchExperiment& e = plan.experiments[item.experiment];
      if (runner_experiment != item.experiment) {
        runner = std::make_unique<sim::ScenarioRunner>(sim::Scenario::load(e.scenario_path),
                                                       sim::worldRendererFactory());
        runner_experiment = item.experiment;
      }
      const ScoringParams params = scoringFor(e);
      Scorer scorer(params, dims);
      scorer.beginCase(caseInfo(runner->scenarioCase(item.case_index)));
      PerceptionRunner perception;
      runner->runCase(item.case_index, e.frames_per_case, true, [&](const sim::RenderedFrame& f) {
        scorer.addFrame(f.truth, perception.process(f, params), &f.image);
      });
      out.push_back({{"item", itemName(plan, item)},
                     {"experiment", e.id},
                     {"case", item.case_index},
                     {"state", scorer.caseStates()}});
    }
    ++done;
    std::fprintf(stderr, "%s: %d/%zu %s (%.1f s)\n", who.c_str(), done, items.size(), itemName(plan, item).c_str(),
                 secondsSince(t0));
    std::fflush(stderr);
  }
  return out;
}

json shardDocument(const BenchPlan& plan, int shard, int shards, const json& items, double wall_s) {
  return {{"format", kShardFormat}, {"plan", plan.toJson()}, {"shard", shard}, {"shards", shards},
          {"code_version", codeVersion()}, {"wall_s", wall_s}, {"items", items}};
}

json readJsonFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot read");
  try {
    return json::parse(in);
  } catch (const json::exception& e) {
    throw Error(path + ": not valid JSON (" + e.what() + ")");
  }
}

struct MergedBench {
  json results;
  std::string html;
  bool expectations_met = true;
};

// Merges shard documents into the bench results: checks that they come from one plan and one
// build and cover every item exactly once, then adds the case states in canonical order.
MergedBench mergeShards(const std::vector<json>& docs, const std::vector<std::string>& origins) {
  if (docs.empty()) throw Error("merge: no shard files");
  for (std::size_t i = 0; i < docs.size(); ++i) {
    if (docs[i].value("format", std::string()) != kShardFormat) {
      throw Error(origins[i] + ": not a colorfree bench shard file (format " + kShardFormat + ")");
    }
  }
  const BenchPlan plan = BenchPlan::fromJson(docs[0].at("plan"));
  const int shards = docs[0].at("shards").get<int>();
  std::set<int> seen_shards;
  std::map<std::string, json> by_item;
  double wall_s = 0;
  for (std::size_t i = 0; i < docs.size(); ++i) {
    const json& d = docs[i];
    if (d.at("plan").at("fingerprint").get<std::uint64_t>() != plan.fingerprint ||
        d.at("code_version") != docs[0].at("code_version")) {
      throw Error(origins[i] + ": from a different bench list, scenario files, --quick or build than " + origins[0]);
    }
    if (d.at("shards").get<int>() != shards || !seen_shards.insert(d.at("shard").get<int>()).second) {
      throw Error(origins[i] + ": shard " + d.at("shard").dump() + "/" + d.at("shards").dump() +
                  " repeats a shard or does not match the others' count " + std::to_string(shards));
    }
    wall_s = std::max(wall_s, d.value("wall_s", 0.0));
    for (const json& it : d.at("items")) {
      const std::string name = it.at("item").get<std::string>();
      if (!by_item.emplace(name, it).second) throw Error(origins[i] + ": item " + name + " appears twice");
    }
  }
  for (const WorkItem& w : allWorkItems(plan)) {
    if (!by_item.count(itemName(plan, w))) {
      throw Error("merge: item " + itemName(plan, w) + " is missing (shards given: " + std::to_string(seen_shards.size()) +
                  " of " + std::to_string(shards) + ")");
    }
  }

  MergedBench m;
  const FieldDimensions dims = FieldDimensions::loadDefault();
  json experiments = json::object();
  std::vector<std::string> sections;
  long frames = 0;
  for (int x = 0; x < static_cast<int>(plan.experiments.size()); ++x) {
    const BenchExperiment& e = plan.experiments[x];
    Scorer scorer(scoringFor(e), dims);
    for (int c = 0; c < e.cases; ++c) scorer.addCaseStates(by_item.at(itemName(plan, {x, c, 0})).at("state"));
    RunInfo run{e.scenario_name, e.seed, codeVersion()};
    json r = scorer.results(run);
    frames += scorer.frameCount();
    std::vector<Expectation> expectations;
    for (const auto& text : e.expectations) expectations.push_back(parseExpectation(text, e.scenario_path));
    const auto failures = checkExpectations(expectations, r);
    std::vector<ExpectationLine> lines;
    r["expectations"] = json::array();
    for (const auto& ex : expectations) {
      ExpectationLine line{ex.text, true, ""};
      const auto v = metricValue(r, ex.metric);
      line.detail = v ? "value " + std::to_string(*v) : "metric absent";
      for (const auto& f : failures) line.met = line.met && f.expectation.text != ex.text;
      m.expectations_met = m.expectations_met && line.met;
      r["expectations"].push_back({{"text", line.text}, {"met", line.met}});
      lines.push_back(line);
    }
    r["bench"] = {{"id", e.id}, {"role", roleName(e.role)}, {"title", e.title}, {"scenario_path", e.scenario_path}};
    sections.push_back("<section id='" + e.id + "'><h2>" + e.title + " <small>(" + e.id + ": " + e.scenario_path +
                       ")</small></h2>" + reportBody(renderReportHtml(r, scorer.gallery(), lines)) + "</section>");
    experiments[e.id] = r;
  }
  json results;
  results["format"] = "colorfree-bench/1";
  results["bench"] = {{"list", plan.list_path},
                      {"quick", plan.quick},
                      {"code_version", codeVersion()},
                      {"frames", frames},
                      {"targets", plan.targets},
                      {"wall_s", wall_s}};
  results["summary"] = benchSummary(plan, experiments);
  results["cnn_table"] = plan.cnn_table ? by_item.at("cnn_table").at("cnn_table") : json::array();
  results["experiments"] = experiments;
  m.results = results;
  m.html = renderBenchHtml(results, sections);
  return m;
}

void writeMerged(const MergedBench& m, const std::string& out) {
  fs::create_directories(out);
  // The report first, results.json last: results.json present means the run completed.
  writeFileAtomic(out + "/report.html", m.html);
  writeFileAtomic(out + "/results.json", m.results.dump(2) + "\n");
}

std::string shardFile(const std::string& dir, int shard, int shards) {
  return dir + "/shard_" + std::to_string(shard) + "_of_" + std::to_string(shards) + ".json";
}

// Runs shard `shard` of `shards` in this process and writes its shard file.
void runShard(const BenchPlan& plan, int shard, int shards, const std::string& path, const std::string& who) {
  const auto t0 = std::chrono::steady_clock::now();
  const json items = runItems(plan, shardItems(plan, shard, shards), who);
  writeFileAtomic(path, shardDocument(plan, shard, shards, items, secondsSince(t0)).dump() + "\n");
}

std::pair<int, int> parseShard(const std::string& text) {
  const auto slash = text.find('/');
  try {
    if (slash != std::string::npos) {
      std::size_t a = 0, b = 0;
      const int i = std::stoi(text.substr(0, slash), &a);
      const int n = std::stoi(text.substr(slash + 1), &b);
      if (a == slash && b == text.size() - slash - 1 && n >= 1 && i >= 0 && i < n) return {i, n};
    }
  } catch (const std::exception&) {
  }
  throw Error("--shard '" + text + "': expected i/n with 0 <= i < n (e.g. 0/4)");
}

}  // namespace

void addBenchCommand(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand(
      "bench", "Run the paper's experiments (scenes/bench.yaml): tables beside the paper's, results.json and "
               "report.html");
  struct Args {
    std::string out = "out/bench";
    std::string list;
    int jobs = 2;
    std::string shard;
    bool quick = false;
    bool check = false;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("--out", args->out, "Output folder (results.json, report.html; shards: DIR/shard_i_of_n.json)")
      ->capture_default_str();
  cmd->add_option("--list", args->list, "Bench list (default: scenes/bench.yaml of the source tree)");
  cmd->add_option("--jobs", args->jobs, "Worker processes, each with its own World and GL context")
      ->capture_default_str();
  cmd->add_option("--shard", args->shard, "Run only shard i of n (i/n, 0-based) and write a partial results file");
  cmd->add_flag("--quick", args->quick, "Few frames per case (a smoke test of the whole bench)");
  cmd->add_flag("--check", args->check, "Exit 1 when a scenario's expectation is not met");
  cmd->callback([args, &exit_code]() {
    const std::string list = args->list.empty() ? std::string(COLORFREE_SOURCE_DIR) + "/scenes/bench.yaml" : args->list;
    if (args->jobs < 1 || args->jobs > 64) throw Error("--jobs must be in 1..64");
    const BenchPlan plan = loadBenchPlan(list, args->quick);
    fs::create_directories(args->out);
    const auto t0 = std::chrono::steady_clock::now();
    if (!args->shard.empty()) {
      const auto [i, n] = parseShard(args->shard);
      const std::string path = shardFile(args->out, i, n);
      fs::remove(path);
      runShard(plan, i, n, path, "shard " + args->shard);
      std::printf("shard %d/%d written to %s (%.0f s); merge all shards with: colorfree merge DIR... --out DIR\n", i,
                  n, path.c_str(), secondsSince(t0));
      exit_code = 0;
      return;
    }
    // A stale result must not pass for this run's if this run stops half-way.
    fs::remove(args->out + "/results.json");
    fs::remove(args->out + "/report.html");
    std::vector<json> docs;
    std::vector<std::string> origins;
    const int jobs = std::min<int>(args->jobs, static_cast<int>(allWorkItems(plan).size()));
    if (jobs == 1) {
      const json items = runItems(plan, allWorkItems(plan), "bench");
      docs.push_back(shardDocument(plan, 0, 1, items, secondsSince(t0)));
      origins.push_back("bench");
    } else {
      // Worker processes (forked before any GL context exists), one shard each.
      const std::string work = args->out + "/.work";
      fs::create_directories(work);
      std::vector<pid_t> pids;
      for (int k = 0; k < jobs; ++k) {
        std::fflush(nullptr);
        const pid_t pid = ::fork();
        if (pid < 0) throw Error("bench: cannot start a worker process");
        if (pid == 0) {
          // A worker ends with the bench that started it.
          ::prctl(PR_SET_PDEATHSIG, SIGTERM);
          int rc = 0;
          try {
            runShard(plan, k, jobs, shardFile(work, k, jobs), "worker " + std::to_string(k));
          } catch (const std::exception& e) {
            std::fprintf(stderr, "colorfree: worker %d: %s\n", k, e.what());
            rc = 2;
          }
          std::fflush(nullptr);
          ::_exit(rc);
        }
        pids.push_back(pid);
      }
      bool ok = true;
      for (pid_t pid : pids) {
        int status = 0;
        ::waitpid(pid, &status, 0);
        ok = ok && WIFEXITED(status) && WEXITSTATUS(status) == 0;
      }
      if (!ok) throw Error("bench: a worker failed (see above); no results written");
      for (int k = 0; k < jobs; ++k) {
        docs.push_back(readJsonFile(shardFile(work, k, jobs)));
        origins.push_back(shardFile(work, k, jobs));
      }
      fs::remove_all(work);
    }
    MergedBench m = mergeShards(docs, origins);
    m.results["bench"]["wall_s"] = secondsSince(t0);
    writeMerged(m, args->out);
    printBenchTables(m.results);
    std::printf("\nresults: %s/results.json, report: %s/report.html (%.0f s, %d jobs)\n", args->out.c_str(),
                args->out.c_str(), secondsSince(t0), jobs);
    exit_code = args->check && !m.expectations_met ? 1 : 0;
  });
}

void addMergeCommand(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand("merge", "Merge the shard files of `colorfree bench --shard i/n` into one results.json "
                                          "and report.html");
  auto inputs = std::make_shared<std::vector<std::string>>();
  auto out = std::make_shared<std::string>();
  cmd->add_option("inputs", *inputs, "Folders holding shard_i_of_n.json files, or the files")->required();
  cmd->add_option("--out", *out, "Output folder for results.json and report.html")->required();
  cmd->callback([inputs, out, &exit_code]() {
    std::vector<std::string> files;
    for (const auto& in : *inputs) {
      if (fs::is_directory(in)) {
        std::vector<std::string> found;
        for (const auto& f : fs::directory_iterator(in)) {
          const std::string name = f.path().filename().string();
          if (name.rfind("shard_", 0) == 0 && f.path().extension() == ".json") found.push_back(f.path().string());
        }
        std::sort(found.begin(), found.end());
        files.insert(files.end(), found.begin(), found.end());
      } else if (fs::exists(in)) {
        files.push_back(in);
      } else {
        throw Error(in + ": no such file or folder");
      }
    }
    std::vector<json> docs;
    for (const auto& f : files) docs.push_back(readJsonFile(f));
    const MergedBench m = mergeShards(docs, files);
    writeMerged(m, *out);
    printBenchTables(m.results);
    std::printf("\nmerged %zu shard file(s): %s/results.json, %s/report.html\n", files.size(), out->c_str(),
                out->c_str());
    exit_code = 0;
  });
}

}  // namespace colorfree::app
