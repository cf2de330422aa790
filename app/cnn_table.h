#pragma once

#include <string>
#include <vector>

namespace colorfree::app {

/// One row of the paper's Table 1 for one of our nets, timed on this machine.
struct CnnTableRow {
  std::string name;
  int input_width = 0, input_height = 0, input_channels = 0;
  long long parameters = 0;
  int paper_parameters = 0;  ///< 0: a net the paper does not have (no paper figures)
  long long multiply_adds = 0;
  double us_per_patch_single = 0;   ///< median, one patch per call
  double us_per_patch_batch16 = 0;  ///< median, 16 patches per call
  double paper_time_ms = 0;
  bool trained = false;      ///< weights found beside the cfg
  std::string accuracy;      ///< "0.975 (1200)", "untrained" or "no held-out data"
  double paper_accuracy = 0;

  bool hasPaperFigures() const { return paper_parameters > 0; }
};

/// The table for the shipped nets in `models` (accuracy on `data_root`/<net stem> when given).
std::vector<CnnTableRow> cnnTable(const std::string& models, const std::string& data_root);

}  // namespace colorfree::app
