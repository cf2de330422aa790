#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "bench_plan.h"

namespace colorfree::app {

/// The paper's tables from the experiments' results (each a colorfree run results object keyed by
/// experiment id): Table 2, the orientation figures, the pose error, Table 3, the sweeps with
/// where each detector falls below its target. Absent stages are null, never 0.
nlohmann::json benchSummary(const BenchPlan& plan, const nlohmann::json& experiments);

/// Prints the tables of a bench results.json with the paper's figure beside each of ours.
void printBenchTables(const nlohmann::json& results);

/// One page: the bench tables and sweep charts, then each experiment's own report section.
std::string renderBenchHtml(const nlohmann::json& results, const std::vector<std::string>& experiment_sections);

/// The inside of <body> of a page made by renderReportHtml, headings moved down one level.
std::string reportBody(const std::string& html);

}  // namespace colorfree::app
