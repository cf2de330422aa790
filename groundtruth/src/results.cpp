#include "colorfree/groundtruth/results.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "colorfree/groundtruth/scorer.h"
#include "colorfree/perception/error.h"

namespace colorfree {

namespace {

void collect(const nlohmann::json& j, const std::string& prefix, std::set<std::string>& out) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it) {
      if (prefix.empty() && it.key() == "cases") continue;
      collect(it.value(), prefix.empty() ? it.key() : prefix + "." + it.key(), out);
    }
  } else if (!j.is_array()) {
    out.insert(prefix);
  }
}

std::string formatNumber(double v) {
  std::ostringstream s;
  s.precision(6);
  s << v;
  return s.str();
}

}  // namespace

Expectation parseExpectation(const std::string& text, const std::string& origin) {
  static const std::regex kPattern(
      R"(^\s*([A-Za-z_][A-Za-z0-9_.]*)\s*(>=|<=|==|>|<)\s*([-+]?[0-9]*\.?[0-9]+([eE][-+]?[0-9]+)?)\s*$)");
  std::smatch m;
  if (!std::regex_match(text, m, kPattern)) {
    throw Error(origin + ": expectation '" + text +
                "' is not of the form 'metric OP number' (OP one of >= <= > < ==)");
  }
  Expectation e;
  e.text = text;
  e.metric = m[1];
  e.op = m[2];
  e.bound = std::stod(m[3]);
  return e;
}

std::set<std::string> metricNames(const nlohmann::json& results) {
  std::set<std::string> out;
  collect(results, "", out);
  return out;
}

const std::set<std::string>& knownMetricNames() {
  static const std::set<std::string> kNames = [] {
    Scorer empty(ScoringParams{}, FieldDimensions{});
    return metricNames(empty.results(RunInfo{}));
  }();
  return kNames;
}

void validateExpectations(const std::vector<Expectation>& expectations, const std::string& origin) {
  const auto& known = knownMetricNames();
  for (const auto& e : expectations) {
    if (!known.count(e.metric)) {
      throw Error(origin + ": expectation '" + e.text + "' names an unknown metric '" + e.metric +
                  "' (e.g. ball.detection_rate, robot.proposal_recall, orientation.perceived, "
                  "field_features.pose_error_mm, timing_ms.ball_detector.mean)");
    }
  }
}

std::optional<double> metricValue(const nlohmann::json& results, const std::string& metric) {
  const nlohmann::json* node = &results;
  std::size_t start = 0;
  while (start <= metric.size()) {
    const std::size_t dot = metric.find('.', start);
    const std::string key =
        metric.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    if (!node->is_object() || !node->contains(key)) return std::nullopt;
    node = &(*node)[key];
    if (dot == std::string::npos) break;
    start = dot + 1;
  }
  if (!node->is_number()) return std::nullopt;
  return node->get<double>();
}

std::vector<ExpectationFailure> checkExpectations(const std::vector<Expectation>& expectations,
                                                  const nlohmann::json& results) {
  std::vector<ExpectationFailure> failures;
  for (const auto& e : expectations) {
    const auto v = metricValue(results, e.metric);
    bool ok = false;
    if (v) {
      if (e.op == ">=")
        ok = *v >= e.bound;
      else if (e.op == "<=")
        ok = *v <= e.bound;
      else if (e.op == ">")
        ok = *v > e.bound;
      else if (e.op == "<")
        ok = *v < e.bound;
      else
        ok = *v == e.bound;
    }
    if (!ok) failures.push_back({e, v});
  }
  return failures;
}

std::string ExpectationFailure::message(const std::string& scenario) const {
  return "scenario '" + scenario + "': expectation not met: " + expectation.metric + " = " +
         (value ? formatNumber(*value) : std::string("absent")) + ", expected " + expectation.op +
         " " + formatNumber(expectation.bound);
}

void writeFileAtomic(const std::string& path, const std::string& content) {
  const std::string tmp = path + ".partial";
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) throw Error(path + ": cannot write (temporary file " + tmp + ")");
    f << content;
    f.flush();
    if (!f) {
      std::remove(tmp.c_str());
      throw Error(path + ": write failed");
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::remove(tmp.c_str());
    throw Error(path + ": cannot rename the finished file into place: " + ec.message());
  }
}

}  // namespace colorfree
