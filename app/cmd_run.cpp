#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "colorfree/groundtruth/report.h"
#include "colorfree/groundtruth/results.h"
#include "colorfree/groundtruth/scorer.h"
#include "colorfree/groundtruth/scoring_params.h"
#include "colorfree/perception/field_dimensions.h"
#include "colorfree/sim/runner.h"
#include "colorfree/sim/scenario.h"
#include "colorfree/sim/world_renderer.h"
#include "code_version.h"
#include "commands.h"
#include "progress_bar.h"
#include "run_perception.h"

namespace colorfree::app {
namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

std::string caseFolder(int index) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "case_%03d", index);
  return buf;
}

std::string frameFile(int index) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "frame_%06d.png", index);
  return buf;
}

std::string show(const nlohmann::json& r, const std::string& metric, int prec = 3) {
  const auto v = metricValue(r, metric);
  if (!v) return "absent";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", prec, *v);
  return buf;
}

void printSummary(const nlohmann::json& r) {
  std::printf("%-34s %10s %10s   %10s %10s\n", "", "robot", "paper", "ball", "paper");
  std::printf("%-34s %10s %10s   %10s %10s\n", "proposals per frame",
              show(r, "robot.proposals_per_frame", 2).c_str(), "3.05",
              show(r, "ball.proposals_per_frame", 2).c_str(), "10.3");
  std::printf("%-34s %10s %10s   %10s %10s\n", "proposal recall",
              show(r, "robot.proposal_recall").c_str(), "0.972",
              show(r, "ball.proposal_recall").c_str(), "0.993");
  std::printf("%-34s %10s %10s   %10s %10s\n", "detection rate",
              show(r, "robot.detection_rate").c_str(), "0.949",
              show(r, "ball.detection_rate").c_str(), "0.971");
  std::printf("%-34s %10s %10s   %10s %10s\n", "false positives per frame",
              show(r, "robot.false_positives_per_frame").c_str(), "-",
              show(r, "ball.false_positives_per_frame").c_str(), "-");
  std::printf(
      "orientation perceived (raw / filtered): %s / %s  (paper 99.88 %% static, 95.52 %% "
      "dynamic)\n",
      show(r, "orientation.perceived").c_str(), show(r, "orientation.filtered.perceived").c_str());
  std::printf("pose error from field features: %s mm (paper 40.07 mm)\n",
              show(r, "field_features.pose_error_mm", 1).c_str());
}

}  // namespace

void addRunCommand(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand(
      "run",
      "Render a scenario, run the perception on every frame, score it against the truth and "
      "write results.json and report.html");
  struct Args {
    std::string scenario;
    std::string out;
    std::string scoring;
    int case_index = -1;
    int frames = 0;
    bool save_frames = false;
    bool quiet = false;
    std::vector<std::string> expect;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("scenario", args->scenario, "Scenario file (docs/scenarios.md)")->required();
  cmd->add_option("--out", args->out, "Output folder for results.json and report.html")->required();
  cmd->add_option("--scoring", args->scoring,
                  "Scoring parameters (default groundtruth/params/scoring.yaml)");
  cmd->add_option("--case", args->case_index, "Run only this case (0-based)");
  cmd->add_option("--frames", args->frames, "Frames per case instead of the scenario's count");
  cmd->add_flag("--save-frames", args->save_frames,
                "Also write every frame as PNG under DIR/frames, with its camera file (.camera.yaml)");
  cmd->add_flag("--quiet", args->quiet, "No progress bar");
  cmd->add_option("--expect", args->expect,
                   "Check this expectation (\"metric >= value\") instead of the scenario's own; "
                   "repeatable (CI's regression floors on a scenario whose targets are not met yet)");
  cmd->callback([args, &exit_code]() {
    sim::Scenario scenario = sim::Scenario::load(args->scenario);
    // Expectations are checked against the metric names before anything renders.
    std::vector<Expectation> expectations;
    if (args->expect.empty()) {
      for (const auto& e : scenario.expect) {
        const std::string origin = args->scenario + ":" + std::to_string(e.line);
        expectations.push_back(parseExpectation(e.text, origin));
        validateExpectations({expectations.back()}, origin);
      }
    } else {
      for (const auto& text : args->expect) {
        expectations.push_back(parseExpectation(text, "--expect"));
        validateExpectations({expectations.back()}, "--expect");
      }
    }
    if (args->case_index >= static_cast<int>(scenario.cases.size())) {
      throw Error(args->scenario + ": no case " + std::to_string(args->case_index) +
                  " (the scenario has " + std::to_string(scenario.cases.size()) + ")");
    }
    if (args->frames < 0) throw Error("--frames must be positive");
    ScoringParams params =
        args->scoring.empty() ? ScoringParams::loadDefault() : ScoringParams::load(args->scoring);
    // Rounded to a milli-degree: the scenario keeps 22.5° as 0.3927 rad (22.50005°).
    params.orientation_tolerance_deg =
        std::round(scenario.cases.front().settings.orientation_tolerance_rad * kRadToDeg * 1e3) /
        1e3;

    namespace fs = std::filesystem;
    fs::create_directories(args->out);
    const std::string results_path = args->out + "/results.json";
    const std::string report_path = args->out + "/report.html";
    // A stale result must not pass for this run's if this run stops half-way.
    fs::remove(results_path);
    fs::remove(report_path);

    std::vector<int> cases;
    for (int c = 0; c < static_cast<int>(scenario.cases.size()); ++c) {
      if (args->case_index < 0 || args->case_index == c) cases.push_back(c);
    }
    int total = 0;
    for (int c : cases)
      total += args->frames > 0 ? args->frames : scenario.cases[c].settings.frames;

    Scorer scorer(params, FieldDimensions::loadDefault());
    PerceptionRunner perception;
    sim::ScenarioRunner runner(scenario, sim::worldRendererFactory());
    RunProgressBar bar(!args->quiet && ::isatty(STDERR_FILENO));
    int done = 0;
    bar.update(0, total, "");
    for (int c : cases) {
      const sim::ScenarioCase& sc = runner.scenarioCase(c);
      const CaseInfo info = caseInfo(sc);
      scorer.beginCase(info);
      perception.beginCase();
      const std::string frame_dir = args->out + "/frames/" + caseFolder(c);
      if (args->save_frames) fs::create_directories(frame_dir);
      runner.runCase(
          c, args->frames > 0 ? args->frames : -1, true, [&](const sim::RenderedFrame& f) {
            const FramePercepts percepts = perception.process(f, params);
            scorer.addFrame(f.truth, percepts, &f.image);
            if (args->save_frames) {
              const std::string file = frame_dir + "/" + frameFile(f.frame_index);
              writeGrayPng(file, f.image.view());
              // The camera file beside it, for `colorfree detect FRAME --camera FRAME.camera.yaml`.
              f.perception_camera.save(file.substr(0, file.size() - 4) + ".camera.yaml");
            }
            bar.update(++done, total, info.name);
          });
    }

    RunInfo run;
    run.scenario = scenario.name;
    run.seed = scenario.cases.front().settings.seed;
    run.code_version = codeVersion();
    nlohmann::json results = scorer.results(run);
    const auto failures = checkExpectations(expectations, results);
    std::vector<ExpectationLine> lines;
    for (const auto& e : expectations) {
      ExpectationLine line{e.text, true, ""};
      const auto v = metricValue(results, e.metric);
      line.detail = v ? "value " + std::to_string(*v) : "metric absent";
      for (const auto& f : failures) line.met = line.met && f.expectation.text != e.text;
      lines.push_back(line);
    }
    results["expectations"] = nlohmann::json::array();
    for (const auto& l : lines)
      results["expectations"].push_back({{"text", l.text}, {"met", l.met}});
    // The report first, results.json last: results.json present means the run completed.
    writeFileAtomic(report_path, renderReportHtml(results, scorer.gallery(), lines));
    writeFileAtomic(results_path, results.dump(2) + "\n");

    std::printf("%s: %d frames scored, results in %s\n", scenario.name.c_str(), scorer.frameCount(),
                results_path.c_str());
    printSummary(results);
    for (const auto& f : failures)
      std::fprintf(stderr, "colorfree: %s\n", f.message(scenario.name).c_str());
    exit_code = failures.empty() ? 0 : 1;
  });
}

}  // namespace colorfree::app
