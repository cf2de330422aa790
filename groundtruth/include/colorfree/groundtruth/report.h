#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "colorfree/groundtruth/scorer.h"

namespace colorfree {

/// What the report says about expectations.
struct ExpectationLine {
  std::string text;
  bool met = false;
  std::string detail;
};

/// One self-contained HTML page: the paper's tables with the paper's numbers beside ours, inline
/// SVG charts (orientation classes per true heading, detection rate against each swept setting
/// and against distance), the rules and thresholds, and the gallery (base64 PNG crops).
std::string renderReportHtml(const nlohmann::json& results, const std::vector<GalleryItem>& gallery,
                             const std::vector<ExpectationLine>& expectations);

}  // namespace colorfree
