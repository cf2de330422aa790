#pragma once

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

// Tolerances and paths shared by all tests, defined once.
namespace colorfree::test {

inline constexpr double kPixelTolerance = 1e-6;      // exact geometry in pixels
inline constexpr double kMetreTolerance = 1e-9;      // exact geometry in metres
inline constexpr double kRenderPixelTolerance = 1.0; // rendered vs projected, pixels
inline constexpr float kCnnTolerance = 1e-4f;        // two CNN engines on the same files

inline std::string sourceDir() { return COLORFREE_SOURCE_DIR; }

/// Every scenario file shipped under scenes/ (recursively, sorted; scenes/bench.yaml is the
/// bench's list of scenarios, not a scenario).
inline std::vector<std::filesystem::path> shippedScenarioFiles() {
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(sourceDir() + "/scenes")) {
    if (entry.path().extension() == ".yaml" && entry.path().filename() != "bench.yaml") {
      files.push_back(entry.path());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

}  // namespace colorfree::test
