#pragma once
// The per-stage summary of bench_perception and bench_perception_rendered: after Google
// Benchmark's own table, per stage the median, mean and max over the frames (the paper's profiling
// table reports mean and max) of each frame's CPU time. Benchmarks are named "Stage/frame"; with
// --benchmark_repetitions=N a frame counts with its fastest repetition (the machine is shared).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

namespace colorfree::bench {

class StageSummaryReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      if (r.run_type != Run::RT_Iteration || r.iterations == 0) continue;
      const std::string name = r.run_name.function_name;
      // CPU time of the one thread, in the run's unit (µs) → ms.
      const double ms = r.GetAdjustedCPUTime() * 1e-3;
      auto [it, added] = per_frame_ms_.emplace(name, ms);
      if (!added) it->second = std::min(it->second, ms);
    }
    ConsoleReporter::ReportRuns(runs);
  }
  void printSummary(const char* what) const {
    std::map<std::string, std::vector<double>> times_ms;
    for (const auto& [name, ms] : per_frame_ms_) times_ms[name.substr(0, name.find('/'))].push_back(ms);
    std::printf("\nCPU time per 640x480 frame over %s (ms):\n", what);
    std::printf("%-16s %9s %9s %9s\n", "stage", "median", "mean", "max");
    for (auto [stage, t] : times_ms) {
      std::sort(t.begin(), t.end());
      double sum = 0;
      for (double v : t) sum += v;
      const double median = t.size() % 2 ? t[t.size() / 2] : (t[t.size() / 2 - 1] + t[t.size() / 2]) / 2;
      std::printf("%-16s %9.4f %9.4f %9.4f\n", stage.c_str(), median, sum / t.size(), t.back());
    }
  }

 private:
  std::map<std::string, double> per_frame_ms_;
};

}  // namespace colorfree::bench
