#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>

#include "colorfree/perception/error.h"
#include "commands.h"

int main(int argc, char** argv) {
  CLI::App app{"colorfree: colour-free NAO vision and its MuJoCo test bench"};
  app.require_subcommand(1);
  app.set_version_flag("--version", COLORFREE_VERSION);
  int exit_code = 0;
  (void)exit_code;
  colorfree::app::addRenderCommand(app, exit_code);
  colorfree::app::addTrainCommand(app, exit_code);
  colorfree::app::addRunCommand(app, exit_code);
  colorfree::app::addDetectCommand(app, exit_code);
  colorfree::app::addBenchCommand(app, exit_code);
  colorfree::app::addMergeCommand(app, exit_code);
  colorfree::app::addLearnCommand(app, exit_code);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const colorfree::Error& e) {
    std::fprintf(stderr, "colorfree: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "colorfree: internal error: %s\n", e.what());
    return 3;
  }
  return exit_code;
}
