#pragma once

#include <string>
#include <vector>

#include "colorfree/perception/image.h"

namespace colorfree::cnn {

/// Where a patch came from (all optional: a team's own patches may only have a file name).
struct SampleOrigin {
  std::string file;      ///< path relative to the dataset folder, e.g. "robot/000123.png"
  std::string scenario;  ///< scenario (or recording) name
  int frame = -1;        ///< frame index in the scenario, -1 = unknown
  float x_px = 0.0f;     ///< the box in the frame: top-left corner and size, pixels
  float y_px = 0.0f;
  float width_px = 0.0f;
  float height_px = 0.0f;
  std::string truth;  ///< free text: what the truth says is there (e.g. "ball d=2.31m")
};

/// One labelled grayscale patch at the net's input size (grey values, not normalised).
struct Sample {
  GrayImage patch;
  int label = 0;
  SampleOrigin origin;
};

/// Labelled patches of one size, with the class names in label order.
struct Dataset {
  int width = 0;
  int height = 0;
  std::vector<std::string> class_names;
  std::vector<Sample> samples;

  /// Samples per class, in label order.
  std::vector<int> classCounts() const;
};

/// The manifest's file name inside a dataset folder.
inline constexpr const char* kManifestName = "manifest.csv";

/// Reads a dataset folder: one sub-folder of PNG patches per class (class_names gives the label
/// order; empty = the sub-folders sorted by name), and optionally manifest.csv with the columns
/// file,label,scenario,frame,x_px,y_px,width_px,height_px,truth (truth may not contain commas).
/// Throws colorfree::Error naming the file for an unreadable image, a patch of another size
/// than width × height, a manifest row naming a missing file or a label that disagrees with the
/// folder, and a missing class folder.
Dataset readDataset(const std::string& dir, int width, int height,
                    const std::vector<std::string>& class_names = {});

/// Writes `data` as a dataset folder (PNG per sample, manifest.csv last, through a temporary
/// name). Samples without a file name are named <class>/<index>.png.
void writeDataset(const Dataset& data, const std::string& dir);

}  // namespace colorfree::cnn
