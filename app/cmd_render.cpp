#include <unistd.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <string>

#include "colorfree/perception/error.h"
#include "colorfree/sim/render_output.h"
#include "colorfree/sim/scenario.h"
#include "colorfree/sim/world_renderer.h"
#include "commands.h"

namespace colorfree::app {
namespace {

// A one-line progress bar on stderr, redrawn in place.
class ProgressBar {
 public:
  explicit ProgressBar(bool enabled)
      : enabled_(enabled), start_(std::chrono::steady_clock::now()) {}
  void update(int done, int total, const std::string& label) {
    if (!enabled_) return;
    constexpr int kWidth = 30;
    const int filled = total > 0 ? done * kWidth / total : kWidth;
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const double rate = seconds > 0 ? done / seconds : 0;
    const double eta = rate > 0 ? (total - done) / rate : 0;
    std::fprintf(stderr, "\r[%s%s] %d/%d frames  %s  %.1f fps  %.0f s left ",
                 std::string(static_cast<std::size_t>(filled), '#').c_str(),
                 std::string(static_cast<std::size_t>(kWidth - filled), ' ').c_str(), done, total,
                 label.c_str(), rate, eta);
    if (done == total) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  }

 private:
  bool enabled_;
  std::chrono::steady_clock::time_point start_;
};

// Ctrl-C stops after the frame being rendered; the partial output is then removed.
std::atomic<bool> g_interrupted{false};
extern "C" void onInterrupt(int) { g_interrupted = true; }

}  // namespace

void addRenderCommand(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand(
      "render", "Render a scenario's frames (PNG) and truth (truth.jsonl) into a folder");
  struct Args {
    std::string scenario;
    std::string out;
    int case_index = -1;
    int frames = 0;
    bool object_maps = false;
    bool quiet = false;
  };
  auto args = std::make_shared<Args>();
  cmd->add_option("scenario", args->scenario, "Scenario file (docs/scenarios.md)")->required();
  cmd->add_option("--out", args->out, "Output folder (replaced only when the render completes)")
      ->required();
  cmd->add_option("--case", args->case_index, "Render only this case (0-based)");
  cmd->add_option("--frames", args->frames, "Frames per case instead of the scenario's count");
  cmd->add_flag("--object-maps", args->object_maps, "Also write 16-bit object-map PNGs");
  cmd->add_flag("--quiet", args->quiet, "No progress bar");
  cmd->callback([args, &exit_code]() {
    sim::Scenario scenario = sim::Scenario::load(args->scenario);
    sim::RenderDirOptions options;
    options.out_dir = args->out;
    if (args->case_index >= 0) options.case_index = args->case_index;
    if (args->frames != 0) options.frames = args->frames;
    options.object_maps = args->object_maps;
    sim::ScenarioRunner runner(std::move(scenario), sim::worldRendererFactory());
    ProgressBar bar(!args->quiet && ::isatty(STDERR_FILENO));
    g_interrupted = false;
    std::signal(SIGINT, onInterrupt);
    std::signal(SIGTERM, onInterrupt);
    const int written = sim::renderToDirectory(
        runner, options, [&](int done, int total, const sim::RenderedFrame& f) {
          bar.update(done, total, runner.scenarioCase(f.case_index).name());
          if (g_interrupted) {
            throw Error("render of " + args->scenario + " interrupted; " + args->out +
                        " was not written");
          }
        });
    std::signal(SIGINT, SIG_DFL);
    std::signal(SIGTERM, SIG_DFL);
    std::printf("%s: %d frames of %s written to %s\n", runner.scenario().name.c_str(), written,
                args->scenario.c_str(), args->out.c_str());
    exit_code = 0;
  });
}

}  // namespace colorfree::app
