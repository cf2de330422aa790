#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "colorfree/perception/error.h"

namespace colorfree {

/// A scenario's expectation, e.g. "ball.detection_rate >= 0.97".
struct Expectation {
  std::string text;    ///< as written
  std::string metric;  ///< dotted path into results.json
  std::string op;      ///< >=, <=, >, <, ==
  double bound = 0;
};

/// An expectation that was not met; `value` is empty when the metric is absent (null).
struct ExpectationFailure {
  Expectation expectation;
  std::optional<double> value;
  std::string message(const std::string& scenario) const;
};

/// Parses "metric op number"; throws colorfree::Error naming `origin` on bad syntax.
Expectation parseExpectation(const std::string& text, const std::string& origin);

/// Every dotted path to a leaf of a results object (arrays and "cases" left out).
std::set<std::string> metricNames(const nlohmann::json& results);
/// The metric names every results.json has (from an empty run).
const std::set<std::string>& knownMetricNames();
/// Throws colorfree::Error naming `origin` and the metric when an expectation names a metric
/// results.json does not have. Called before anything runs.
void validateExpectations(const std::vector<Expectation>& expectations, const std::string& origin);
/// The expectations `results` does not meet (an absent metric fails).
std::vector<ExpectationFailure> checkExpectations(const std::vector<Expectation>& expectations,
                                                  const nlohmann::json& results);
/// Looks up a dotted path; empty when missing or null.
std::optional<double> metricValue(const nlohmann::json& results, const std::string& metric);

/// Writes `content` to a temporary name beside `path`, then renames it over `path`, so an
/// interrupted run never leaves a file that looks complete. Throws colorfree::Error on failure.
void writeFileAtomic(const std::string& path, const std::string& content);

}  // namespace colorfree
