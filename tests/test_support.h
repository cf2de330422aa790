#pragma once

#include <string>

// Tolerances and paths shared by all tests, defined once.
namespace colorfree::test {

inline constexpr double kPixelTolerance = 1e-6;      // exact geometry in pixels
inline constexpr double kMetreTolerance = 1e-9;      // exact geometry in metres
inline constexpr double kRenderPixelTolerance = 1.0; // rendered vs projected, pixels
inline constexpr float kCnnTolerance = 1e-4f;        // two CNN engines on the same files

inline std::string sourceDir() { return COLORFREE_SOURCE_DIR; }

}  // namespace colorfree::test
