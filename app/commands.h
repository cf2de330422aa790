#pragma once

#include <CLI/CLI.hpp>

namespace colorfree::app {

// Each command adds its subcommand to `app`; its callback sets `exit_code` (0 success, 1 an
// expectation not met) and throws colorfree::Error on bad input (exit 2). main.cpp lists them in
// the order --help shows them.

// `render` (a scenario's frames and truth into a folder).
void addRenderCommand(CLI::App& app, int& exit_code);

// `train` (a tiny CNN on a folder of patches) and `cnn-table` (the paper's Table 1 for our nets).
void addTrainCommand(CLI::App& app, int& exit_code);

// `run` (render, detect and score a scenario: results.json and report.html).
void addRunCommand(CLI::App& app, int& exit_code);
void addDetectCommand(CLI::App& app, int& exit_code);
// `learn` (active learning of a kind's nets in the simulator).
void addLearnCommand(CLI::App& app, int& exit_code);

// `bench` (the paper's experiments, sharded or in worker processes) and `merge` (shard files).
void addBenchCommand(CLI::App& app, int& exit_code);
void addMergeCommand(CLI::App& app, int& exit_code);

}  // namespace colorfree::app
