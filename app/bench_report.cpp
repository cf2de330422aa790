#include "bench_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>

#include "colorfree/groundtruth/results.h"
#include "colorfree/groundtruth/scorer.h"

namespace colorfree::app {
namespace {

using json = nlohmann::json;

// The paper's figures (REFERENCE.md).
const std::map<std::string, std::pair<double, double>> kPaperStagesMs = {
    {"high_contrast", {1.478, 2.755}},   {"field_features", {1.300, 2.909}}, {"robot_proposals", {1.083, 2.692}},
    {"robot_detector", {0.939, 2.417}},  {"robot_orientation", {1.366, 4.537}},
    {"ball_proposals", {1.132, 2.506}},  {"ball_detector", {2.452, 6.959}}};
const std::map<std::string, std::string> kStageTitles = {
    {"high_contrast", "High contrast regions"}, {"field_features", "Field lines & features"},
    {"robot_proposals", "Robot proposals"},     {"robot_detector", "Robot detector"},
    {"robot_orientation", "Robot orientation"}, {"ball_proposals", "Ball proposals"},
    {"ball_detector", "Ball detector"}, {"ignore_regions", "Ignore regions"}};

// The rates charted against each swept setting: a detector's from its results.json counts per case
// (`section.counts.detected` of `section.counts.truths`, shown when `section.counts.ran` > 0), or,
// with `detected` empty, the filtered orientation's perceived share of the cases' robot-frames.
struct SweptRate {
  std::string metric, label, section, detected, truths, ran;
};
const std::vector<SweptRate> kSweptRates = {
    {"ball.detection_rate", "ball", "ball", "detected", "truths", "detector_frames"},
    {"robot.detection_rate", "robot", "robot", "detected", "truths", "detector_frames"},
    {"field_features.line_detection_rate", "field lines", "field_features", "lines_detected", "lines_in_view",
     "frames"},
    {"field_features.intersection_detection_rate", "L/T/X", "field_features", "intersections_detected",
     "intersections_in_view", "frames"},
    {"orientation.filtered.perceived", "orientation", "orientation", "", "", ""}};

// Per value of a sweep, beside the rates (not charted: not rates): summary key, label, decimals.
struct SweptExtra {
  std::string key;
  const char* label;
  int decimals;
};
const std::vector<SweptExtra> kSweptExtras = {{"orientation_false_positive", "ori false", 2},
                                              {"robot_false_positives_per_frame", "robot FP/f", 2},
                                              {"robot_position_error_m", "robot err m", 3},
                                              {"ball_position_error_m", "ball err m", 3}};

const json& at(const json& j, const std::string& path) {
  static const json kNull;
  const json* n = &j;
  std::size_t start = 0;
  while (true) {
    const std::size_t dot = path.find('.', start);
    const std::string key = path.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    if (!n->is_object() || !n->contains(key)) return kNull;
    n = &(*n)[key];
    if (dot == std::string::npos) return *n;
    start = dot + 1;
  }
}

// The filtered orientation's robot-frames of a result (a case's or the experiment's; 0 if none)
// and the count of them in class `share` ("perceived", "false_positive"), from its rate.
long orientationFrames(const json& r) {
  const json& n = at(r, "orientation.filtered.robot_frames");
  return n.is_number() ? n.get<long>() : 0L;
}
long orientationCount(const json& r, const std::string& share) {
  const json& f = at(r, "orientation.filtered." + share);
  return f.is_number() ? std::lround(f.get<double>() * static_cast<double>(orientationFrames(r))) : 0L;
}

std::string fmt(const json& v, int prec = 3, double scale = 1, const char* unit = "") {
  if (!v.is_number()) return "absent";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f%s", prec, v.get<double>() * scale, unit);
  return buf;
}

// A paper figure: "-" where the paper gives none.
std::string paperFmt(const json& v, int prec = 3) { return v.is_number() ? fmt(v, prec) : "-"; }

std::string esc(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&': o += "&amp;"; break;
      case '<': o += "&lt;"; break;
      case '>': o += "&gt;"; break;
      case '"': o += "&quot;"; break;
      default: o += c;
    }
  }
  return o;
}

const json* experimentWithRole(const BenchPlan& plan, const json& experiments, ExperimentRole role, std::string* id) {
  for (const auto& e : plan.experiments) {
    if (e.role == role && experiments.contains(e.id)) {
      if (id) *id = e.id;
      return &experiments.at(e.id);
    }
  }
  return nullptr;
}

json orientationSummary(const json& r, const std::string& id, double paper) {
  json o = {{"experiment", id},
            {"frames", r.at("frame_count")},
            {"tolerance_deg", at(r, "orientation.tolerance_deg")},
            {"robot_frames", at(r, "orientation.robot_frames")},
            {"raw", json::object()},
            {"filtered", json::object()},
            {"paper_perceived", paper}};
  for (const char* c : {"perceived", "semi_perceived", "not_perceived", "false_positive"}) {
    o["raw"][c] = at(r, std::string("orientation.") + c);
    o["filtered"][c] = at(r, std::string("orientation.filtered.") + c);
  }
  json per = json::array();
  for (const auto& bin : at(r, "orientation.per_heading")) {
    per.push_back({{"heading_deg", bin.at("heading_deg")},
                   {"robot_frames", bin.at("raw").at("robot_frames")},
                   {"raw", bin.at("raw")},
                   {"filtered", bin.at("filtered")}});
  }
  o["per_heading"] = per;
  return o;
}

json sweepSummary(const BenchExperiment& e, const json& r, const std::map<std::string, double>& targets) {
  // The setting charted: the scenario's first swept path when numeric (any others are averaged
  // over), else the first numeric setting that takes more than one value.
  std::string setting;
  std::map<std::string, std::set<double>> values;
  for (const auto& c : r.at("cases")) {
    for (auto it = c.at("settings").begin(); it != c.at("settings").end(); ++it) {
      if (it.value().is_number()) values[it.key()].insert(it.value().get<double>());
    }
  }
  if (values.contains(e.swept_setting) && values.at(e.swept_setting).size() > 1) setting = e.swept_setting;
  for (const auto& c : r.at("cases")) {
    for (auto it = c.at("settings").begin(); it != c.at("settings").end() && setting.empty(); ++it) {
      if (values[it.key()].size() > 1) setting = it.key();
    }
  }
  json s = {{"experiment", e.id}, {"title", e.title}, {"setting", setting}, {"values", json::array()},
            {"rates", json::object()}, {"targets", targets}, {"below_target", json::object()}};
  if (setting.empty()) return s;
  for (double v : values[setting]) s["values"].push_back(v);
  for (const auto& sr : kSweptRates) {
    json rates = json::array();
    json below = json::array();
    const bool from_counts = !sr.detected.empty();
    const bool ran = from_counts ? at(r, sr.section + ".counts." + sr.ran).is_number() &&
                                       at(r, sr.section + ".counts." + sr.ran).get<double>() > 0
                                 : orientationFrames(r) > 0;
    for (double v : values[setting]) {
      long det = 0, tru = 0;
      for (const auto& c : r.at("cases")) {
        if (!c.at("settings").contains(setting) || c.at("settings").at(setting).get<double>() != v) continue;
        det += from_counts ? at(c, sr.section + ".counts." + sr.detected).get<long>() : orientationCount(c, "perceived");
        tru += from_counts ? at(c, sr.section + ".counts." + sr.truths).get<long>() : orientationFrames(c);
      }
      const json rate = ran && tru > 0 ? json(static_cast<double>(det) / tru) : json(nullptr);
      rates.push_back(rate);
      const auto t = targets.find(sr.metric);
      if (t != targets.end() && rate.is_number() && rate.get<double>() < t->second) below.push_back(v);
    }
    s["rates"][sr.metric] = rates;
    s["below_target"][sr.metric] = ran ? below : json(nullptr);
  }
  // Beside the rates: the filtered orientation's false share of the robot-frames, the robots' false
  // positives per frame and the detected robots' and balls' mean position errors on the ground
  // (metres; what a wrong camera pose costs, sweeps/camera_*_error.yaml).
  json robot_fp = json::array(), robot_error = json::array(), ball_error = json::array();
  json orientation_fp = json::array();
  for (double v : values[setting]) {
    long fp = 0, frames = 0, ori_fp = 0, ori_frames = 0;
    long errors[2] = {0, 0};
    double error_sums[2] = {0, 0};
    for (const auto& c : r.at("cases")) {
      if (!c.at("settings").contains(setting) || c.at("settings").at(setting).get<double>() != v) continue;
      const auto count = [&](const std::string& path) {
        const json& n = at(c, path);
        return n.is_number() ? n.get<long>() : 0L;
      };
      fp += count("robot.counts.false_positives");
      frames += count("robot.counts.detector_frames");
      ori_fp += orientationCount(c, "false_positive");
      ori_frames += orientationFrames(c);
      const char* objects[2] = {"robot", "ball"};
      for (int o = 0; o < 2; ++o) {
        const long n = count(std::string(objects[o]) + ".counts.position_errors");
        if (n <= 0) continue;
        errors[o] += n;
        error_sums[o] += at(c, std::string(objects[o]) + ".position_error_m").get<double>() * static_cast<double>(n);
      }
    }
    robot_fp.push_back(frames > 0 ? json(static_cast<double>(fp) / frames) : json(nullptr));
    orientation_fp.push_back(ori_frames > 0 ? json(static_cast<double>(ori_fp) / ori_frames) : json(nullptr));
    robot_error.push_back(errors[0] > 0 ? json(error_sums[0] / errors[0]) : json(nullptr));
    ball_error.push_back(errors[1] > 0 ? json(error_sums[1] / errors[1]) : json(nullptr));
  }
  s["orientation_false_positive"] = orientation_fp;
  s["robot_false_positives_per_frame"] = robot_fp;
  s["robot_position_error_m"] = robot_error;
  s["ball_position_error_m"] = ball_error;
  return s;
}

std::string num(double v, int prec) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", prec, v);
  return buf;
}

// A line chart of each detector's rate against the swept setting, with its target dashed.
std::string sweepChart(const json& s) {
  const auto& values = s.at("values");
  if (values.size() < 2) return "";
  const double w = 620, h = 270, l = 50, r = 190, t = 30, b = 42;
  double xmin = values.front().get<double>(), xmax = values.back().get<double>();
  auto X = [&](double x) { return l + (x - xmin) / (xmax - xmin) * (w - l - r); };
  auto Y = [&](double y) { return t + (1 - y) * (h - t - b); };
  std::ostringstream o;
  o << "<svg class=chart width=" << w << " height=" << h << " viewBox='0 0 " << w << " " << h << "'>";
  o << "<text x=" << l << " y=18 class=ct>" << esc(s.at("title").get<std::string>()) << ": rate against "
    << esc(s.at("setting").get<std::string>()) << "</text>";
  for (int k = 0; k <= 4; ++k) {
    o << "<line x1=" << l << " x2=" << w - r << " y1=" << Y(k / 4.0) << " y2=" << Y(k / 4.0) << " class=grid />";
    o << "<text x=" << l - 6 << " y=" << Y(k / 4.0) + 4 << " class=ax text-anchor=end>" << num(k / 4.0, 2) << "</text>";
  }
  for (const auto& v : values) {
    o << "<text x=" << X(v.get<double>()) << " y=" << h - b + 16 << " class=ax text-anchor=middle>"
      << num(v.get<double>(), 2) << "</text>";
  }
  o << "<text x=" << (l + w - r) / 2 << " y=" << h - 4 << " class=ax text-anchor=middle>"
    << esc(s.at("setting").get<std::string>()) << "</text>";
  const char* colours[] = {"#1f6fd1", "#d6453d", "#2e9d4a", "#8e44ad", "#d68a1f"};
  int row = 0;
  for (const auto& sr : kSweptRates) {
    const std::string colour = colours[row % 5];
    const json& rates = s.at("rates").at(sr.metric);
    std::string path;
    for (std::size_t i = 0; i < rates.size(); ++i) {
      if (!rates[i].is_number()) continue;
      const double x = X(values[i].get<double>()), y = Y(rates[i].get<double>());
      path += (path.empty() ? "M" : " L") + num(x, 1) + "," + num(y, 1);
      o << "<circle cx=" << x << " cy=" << y << " r=3 fill='" << colour << "' />";
    }
    if (!path.empty()) o << "<path d='" << path << "' stroke='" << colour << "' fill=none stroke-width=2 />";
    const auto tg = s.at("targets").find(sr.metric);
    std::string label = sr.label;
    if (tg != s.at("targets").end()) {
      o << "<line x1=" << l << " x2=" << w - r << " y1=" << Y(tg->get<double>()) << " y2=" << Y(tg->get<double>())
        << " stroke='" << colour << "' stroke-dasharray='5,4' stroke-width=1 />";
      label += " (target " + num(tg->get<double>(), 2) + ")";
    }
    o << "<rect x=" << w - r + 10 << " y=" << t + row * 18 << " width=12 height=12 fill='" << colour << "' />";
    o << "<text x=" << w - r + 26 << " y=" << t + row * 18 + 10 << " class=ax>" << esc(label)
      << (path.empty() ? " absent" : "") << "</text>";
    ++row;
  }
  o << "</svg>";
  return o.str();
}

std::string belowText(const json& s, const std::string& metric) {
  const json& below = at(s, "below_target")[metric];
  if (!s.at("targets").contains(metric)) return "no target";
  if (below.is_null()) return "absent";
  std::ostringstream t;
  t << (below.empty() ? "never below " : "below ") << num(s.at("targets").at(metric).get<double>(), 2);
  if (!below.empty()) t << " at";
  for (const auto& v : below) t << ' ' << num(v.get<double>(), 3);
  return t.str();
}

// The detection set per lighting preset (its cases sweep `lighting.preset`): each detector's rate
// and the pose error from field features (mean over the frames with a fit), from the per-case counts.
json byLightingPreset(const json& d) {
  struct Sums {
    double ball_det = 0, ball_should = 0, robot_det = 0, robot_should = 0, lines_det = 0, lines_in_view = 0;
    double pose_error_sum_mm = 0, fits = 0, pose_frames = 0;
  };
  std::map<std::string, Sums> by;
  std::vector<std::string> order;
  for (const auto& c : d.at("cases")) {
    if (!c.at("settings").contains("lighting.preset")) continue;
    const std::string name = c.at("settings").at("lighting.preset").get<std::string>();
    if (!by.count(name)) order.push_back(name);
    Sums& s = by[name];
    auto num = [&](const std::string& path) {
      const json& v = at(c, path);
      return v.is_number() ? v.get<double>() : 0.0;
    };
    s.ball_det += num("ball.counts.detected");
    s.ball_should += num("ball.counts.truths");
    s.robot_det += num("robot.counts.detected");
    s.robot_should += num("robot.counts.truths");
    s.lines_det += num("field_features.counts.lines_detected");
    s.lines_in_view += num("field_features.counts.lines_in_view");
    const double fits = num("field_features.counts.pose_fits");
    if (fits > 0) s.pose_error_sum_mm += num("field_features.pose_error_mm") * fits;
    s.fits += fits;
    s.pose_frames += num("field_features.counts.pose_frames");
  }
  json rows = json::array();
  auto rate = [](double a, double b) { return b > 0 ? json(a / b) : json(nullptr); };
  for (const auto& name : order) {
    const Sums& s = by.at(name);
    rows.push_back({{"preset", name},
                    {"ball_detection_rate", rate(s.ball_det, s.ball_should)},
                    {"robot_detection_rate", rate(s.robot_det, s.robot_should)},
                    {"line_detection_rate", rate(s.lines_det, s.lines_in_view)},
                    {"pose_error_mm", rate(s.pose_error_sum_mm, s.fits)},
                    {"pose_fit_rate", rate(s.fits, s.pose_frames)}});
  }
  return rows;
}

// Table 1's accuracy: each net on the samples of the detection set that reached it (held out from
// training), else what the shipped table says (untrained, or no held-out data).
std::string cnnAccuracy(const json& results, const json& row) {
  const json& net = at(results, "summary.cnn_accuracy.nets." + row.at("net").get<std::string>());
  if (at(net, "accuracy").is_number()) {
    return fmt(net.at("accuracy"), 3) + " (" + std::to_string(net.at("samples").get<long>()) + ")";
  }
  return row.at("accuracy").get<std::string>();
}

}  // namespace

// The metrics of each detector in a "scenario" experiment (the hard sets), and its expectations.
const std::vector<std::string> kScenarioMetrics = {"proposal_recall", "proposals_per_frame", "detection_rate",
                                                   "false_positives_per_frame"};

json scenarioSummary(const BenchExperiment& e, const json& r) {
  json o = {{"experiment", e.id}, {"title", e.title}, {"frames", r.at("frame_count")}};
  for (const std::string object : {"ball", "robot"}) {
    json m = {{"should_detect", at(r, object + ".counts.should_detect")}};
    for (const auto& k : kScenarioMetrics) m[k] = at(r, object + "." + k);
    o[object] = m;
  }
  // The orientation's row: its filtered estimate's perceived and false shares of the robot-frames.
  o["orientation"] = {{"should_detect", at(r, "orientation.filtered.robot_frames")},
                      {"proposal_recall", nullptr},
                      {"proposals_per_frame", nullptr},
                      {"detection_rate", at(r, "orientation.filtered.perceived")},
                      {"false_positives_per_frame", at(r, "orientation.filtered.false_positive")}};
  json unmet = json::array();
  long total = 0;
  bool orientation = false;
  for (const auto& x : r.value("expectations", json::array())) {
    ++total;
    if (!x.at("met").get<bool>()) unmet.push_back(x.at("text"));
    orientation = orientation || x.at("text").get<std::string>().rfind("orientation.", 0) == 0;
  }
  o["expectations"] = total;
  o["unmet"] = unmet;
  o["demands_orientation"] = orientation;
  return o;
}

// The detectors a hard set's table shows: those with something to demand there, the orientation
// where the scenario has expectations of it; at least one row per experiment (the robot's), so its
// unmet expectations always show.
std::vector<std::string> scenarioRowObjects(const json& sc) {
  std::vector<std::string> shown;
  for (const std::string object : {"ball", "robot"}) {
    const json& m = sc.at(object);
    if (m.at("detection_rate").is_number() || m.at("proposal_recall").is_number()) shown.push_back(object);
  }
  if (shown.empty()) shown.push_back("robot");
  if (sc.value("demands_orientation", false) && sc.at("orientation").at("detection_rate").is_number()) {
    shown.push_back("orientation");
  }
  return shown;
}

std::string unmetText(const json& sc) {
  std::string unmet;
  for (const auto& u : sc.at("unmet")) unmet += (unmet.empty() ? "" : "; ") + u.get<std::string>();
  return unmet;
}

// The detection set's detection rate per bin of the demanded objects' visible fraction, ball and
// robot side by side: [{from_fraction, to_fraction, robot: {truths, detection_rate}, ball: ...}].
json byVisibleFraction(const json& d) {
  std::map<double, json> rows;
  for (const char* obj : {"robot", "ball"}) {
    for (const auto& b : at(d, std::string("by_visibility.") + obj)) {
      json& row = rows[b.at("from_fraction").get<double>()];
      row["from_fraction"] = b.at("from_fraction");
      row["to_fraction"] = b.at("to_fraction");
      row[obj] = {{"truths", b.at("truths")}, {"detection_rate", b.at("detection_rate")}};
    }
  }
  json out = json::array();
  for (auto& [from, row] : rows) {
    for (const char* obj : {"robot", "ball"}) {
      if (!row.contains(obj)) row[obj] = {{"truths", 0}, {"detection_rate", nullptr}};
    }
    out.push_back(row);
  }
  return out;
}

json benchSummary(const BenchPlan& plan, const json& experiments) {
  json s;
  std::string id;
  if (const json* d = experimentWithRole(plan, experiments, ExperimentRole::kDetection, &id)) {
    json t = {{"experiment", id}, {"frames", d->at("frame_count")}, {"cases", d->at("cases").size()}};
    for (const char* obj : {"robot", "ball"}) {
      for (const char* m : {"proposals_per_frame", "proposal_recall", "detection_rate", "false_positives_per_frame"}) {
        t[obj][m] = at(*d, std::string(obj) + "." + m);
      }
    }
    t["paper"] = {{"robot", {{"proposals_per_frame", 3.05}, {"proposal_recall", 0.972}, {"detection_rate", 0.949}}},
                  {"ball", {{"proposals_per_frame", 10.3}, {"proposal_recall", 0.993}, {"detection_rate", 0.971}}}};
    t["by_visible_fraction"] = byVisibleFraction(*d);
    s["table2"] = t;
    s["field_features"] = {{"experiment", id},
                           {"pose_error_mm", at(*d, "field_features.pose_error_mm")},
                           {"pose_error_rms_mm", at(*d, "field_features.pose_error_rms_mm")},
                           {"pose_fit_rate", at(*d, "field_features.pose_fit_rate")},
                           {"line_detection_rate", at(*d, "field_features.line_detection_rate")},
                           {"intersection_detection_rate", at(*d, "field_features.intersection_detection_rate")},
                           {"paper_pose_error_mm", 40.07},
                           {"by_lighting_preset", byLightingPreset(*d)}};
    json prof = json::array();
    std::vector<std::string> order = paperStageNames();
    for (auto it = at(*d, "timing_ms").begin(); it != at(*d, "timing_ms").end(); ++it) {
      if (std::find(order.begin(), order.end(), it.key()) == order.end()) order.push_back(it.key());
    }
    for (const auto& st : order) {
      const auto p = kPaperStagesMs.find(st);
      prof.push_back({{"stage", st},
                      {"mean_ms", at(*d, "timing_ms." + st + ".mean")},
                      {"max_ms", at(*d, "timing_ms." + st + ".max")},
                      {"paper_mean_ms", p != kPaperStagesMs.end() ? json(p->second.first) : json(nullptr)},
                      {"paper_max_ms", p != kPaperStagesMs.end() ? json(p->second.second) : json(nullptr)}});
    }
    s["table3"] = {{"experiment", id}, {"stages", prof}};
    s["cnn_accuracy"] = {{"experiment", id}, {"nets", at(*d, "cnn")}};
  }
  if (const json* o = experimentWithRole(plan, experiments, ExperimentRole::kOrientationStatic, &id)) {
    s["orientation_static"] = orientationSummary(*o, id, 0.9988);
  }
  if (const json* o = experimentWithRole(plan, experiments, ExperimentRole::kOrientationDynamic, &id)) {
    s["orientation_dynamic"] = orientationSummary(*o, id, 0.9552);
  }
  json sweeps = json::array();
  for (const auto& e : plan.experiments) {
    if (e.role == ExperimentRole::kSweep && experiments.contains(e.id)) {
      sweeps.push_back(sweepSummary(e, experiments.at(e.id), plan.targets));
    }
  }
  s["sweeps"] = sweeps;
  json scenarios = json::array();
  for (const auto& e : plan.experiments) {
    if (e.role == ExperimentRole::kScenario && experiments.contains(e.id)) {
      scenarios.push_back(scenarioSummary(e, experiments.at(e.id)));
    }
  }
  s["scenarios"] = scenarios;
  return s;
}

void printBenchTables(const json& results) {
  const json& s = results.at("summary");
  const json& b = results.at("bench");
  std::printf("colorfree bench: %s%s, %ld frames, code %s\n", b.at("list").get<std::string>().c_str(),
              b.at("quick").get<bool>() ? " (--quick)" : "", b.at("frames").get<long>(),
              b.at("code_version").get<std::string>().c_str());
  std::printf("(\"absent\": the branch has no such detector yet; ours on MuJoCo renders, the paper's on a real NAO V5)\n");
  if (s.contains("table2")) {
    const json& t = s.at("table2");
    std::printf("\nTable 2: detection set (%s: %ld frames, %ld cases)\n", t.at("experiment").get<std::string>().c_str(),
                t.at("frames").get<long>(), t.at("cases").get<long>());
    std::printf("  %-28s %9s %9s %9s %9s\n", "", "robot", "paper", "ball", "paper");
    const std::vector<std::pair<std::string, std::string>> rows = {{"proposals per frame", "proposals_per_frame"},
                                                                   {"proposal recall", "proposal_recall"},
                                                                   {"detection rate", "detection_rate"},
                                                                   {"false positives per frame", "false_positives_per_frame"}};
    for (const auto& [label, key] : rows) {
      const int prec = key == "proposals_per_frame" ? 2 : 3;
      std::printf("  %-28s %9s %9s %9s %9s\n", label.c_str(), fmt(t.at("robot").at(key), prec).c_str(),
                  paperFmt(at(t, "paper.robot." + key), prec == 2 ? 2 : 3).c_str(), fmt(t.at("ball").at(key), prec).c_str(),
                  paperFmt(at(t, "paper.ball." + key), prec == 2 ? 1 : 3).c_str());
    }
    if (t.contains("by_visible_fraction") && !t.at("by_visible_fraction").empty()) {
      // (No demanded object in a bin: "-", not "absent", which means no such detector.)
      const auto rate = [](const json& o) {
        return o.at("truths").get<long>() > 0 ? fmt(o.at("detection_rate")) : std::string("-");
      };
      std::printf("  %-28s %9s %9s %9s %9s\n", "per visible fraction", "robot", "n", "ball", "n");
      for (const auto& r : t.at("by_visible_fraction")) {
        const std::string bin = fmt(r.at("from_fraction"), 1) + "-" + fmt(r.at("to_fraction"), 1);
        std::printf("  %-28s %9s %9ld %9s %9ld\n", bin.c_str(), rate(r.at("robot")).c_str(),
                    r.at("robot").at("truths").get<long>(), rate(r.at("ball")).c_str(),
                    r.at("ball").at("truths").get<long>());
      }
    }
  }
  for (const char* which : {"orientation_static", "orientation_dynamic"}) {
    if (!s.contains(which)) continue;
    const json& o = s.at(which);
    std::printf("\nOrientation, %s (%s: tolerance %s deg, %ld robot-frames): classes per true heading\n",
                std::string(which).substr(12).c_str(), o.at("experiment").get<std::string>().c_str(),
                fmt(o.at("tolerance_deg"), 2).c_str(), o.at("robot_frames").get<long>());
    std::printf("  %-9s %6s | %-27s | %-27s\n", "heading", "n", "raw  P / S / N / F %", "filtered  P / S / N / F %");
    auto classes = [](const json& c) {
      char buf[96];
      std::snprintf(buf, sizeof buf, "%5s %5s %5s %5s", fmt(c.at("perceived"), 0, 100).c_str(),
                    fmt(c.at("semi_perceived"), 0, 100).c_str(), fmt(c.at("not_perceived"), 0, 100).c_str(),
                    fmt(c.at("false_positive"), 0, 100).c_str());
      return std::string(buf);
    };
    for (const auto& bin : o.at("per_heading")) {
      std::printf("  %-9s %6ld | %-27s | %-27s\n", fmt(bin.at("heading_deg"), 1).c_str(), bin.at("robot_frames").get<long>(),
                  classes(bin.at("raw")).c_str(), classes(bin.at("filtered")).c_str());
    }
    std::printf("  %-9s %6ld | %-27s | %-27s\n", "all", o.at("robot_frames").get<long>(), classes(o.at("raw")).c_str(),
                classes(o.at("filtered")).c_str());
    std::printf("  perceived: raw %s, filtered %s; paper %s (filtered)\n", fmt(o.at("raw").at("perceived"), 2, 100, " %").c_str(),
                fmt(o.at("filtered").at("perceived"), 2, 100, " %").c_str(),
                fmt(o.at("paper_perceived"), 2, 100, " %").c_str());
  }
  if (s.contains("field_features")) {
    const json& f = s.at("field_features");
    std::printf("\nField features (%s): pose error %s mm (RMS %s mm, fit in %s of frames); paper %s mm\n",
                f.at("experiment").get<std::string>().c_str(), fmt(f.at("pose_error_mm"), 1).c_str(),
                fmt(f.at("pose_error_rms_mm"), 1).c_str(), fmt(f.at("pose_fit_rate"), 3).c_str(),
                fmt(f.at("paper_pose_error_mm"), 2).c_str());
    std::printf("  line detection rate %s, L/T/X detection rate %s\n", fmt(f.at("line_detection_rate")).c_str(),
                fmt(f.at("intersection_detection_rate")).c_str());
    if (f.contains("by_lighting_preset") && !f.at("by_lighting_preset").empty()) {
      std::printf("  per lighting preset:  %12s %14s %14s %12s %10s\n", "ball det.", "robot det.", "line det.",
                  "pose err mm", "fit rate");
      for (const auto& r : f.at("by_lighting_preset")) {
        std::printf("  %-20s %12s %14s %14s %12s %10s\n", r.at("preset").get<std::string>().c_str(),
                    fmt(r.at("ball_detection_rate")).c_str(), fmt(r.at("robot_detection_rate")).c_str(),
                    fmt(r.at("line_detection_rate")).c_str(), fmt(r.at("pose_error_mm"), 1).c_str(),
                    fmt(r.at("pose_fit_rate")).c_str());
      }
    }
  }
  if (s.contains("table3")) {
    std::printf("\nTable 3: profiling, ms per frame (ours: this machine while rendering; paper: NAO V5)\n");
    std::printf("  %-26s %9s %9s %11s %10s\n", "module", "mean", "max", "paper mean", "paper max");
    for (const auto& st : s.at("table3").at("stages")) {
      const std::string key = st.at("stage").get<std::string>();
      const auto title = kStageTitles.find(key);
      std::printf("  %-26s %9s %9s %11s %10s\n", (title != kStageTitles.end() ? title->second : key).c_str(),
                  fmt(st.at("mean_ms")).c_str(), fmt(st.at("max_ms")).c_str(), paperFmt(st.at("paper_mean_ms")).c_str(),
                  paperFmt(st.at("paper_max_ms")).c_str());
    }
  }
  if (results.contains("cnn_table") && !results.at("cnn_table").empty()) {
    std::printf("\nTable 1: CNN classifiers (time: this machine, one core, median; accuracy: on the detection set's\n"
                "samples that reach each net, their count in brackets; samples on a ball or robot too hidden to\n"
                "demand, which training leaves out too, are left out)\n");
    std::printf("  %-13s %-8s %15s %10s %10s %9s %-17s %6s\n", "net", "input", "params (paper)", "us single",
                "us batch16", "paper ms", "accuracy", "paper");
    for (const auto& r : results.at("cnn_table")) {
      const std::string params =
          std::to_string(r.at("parameters").get<long>()) + " (" + paperFmt(r.at("paper_parameters"), 0) + ")";
      std::printf("  %-13s %-8s %15s %10.2f %10.2f %9s %-17s %6s\n", r.at("net").get<std::string>().c_str(),
                  r.at("input").get<std::string>().c_str(), params.c_str(), r.at("us_per_patch_single").get<double>(),
                  r.at("us_per_patch_batch16").get<double>(), paperFmt(r.at("paper_time_ms")).c_str(),
                  cnnAccuracy(results, r).c_str(), paperFmt(r.at("paper_accuracy")).c_str());
    }
  }
  if (s.contains("scenarios") && !s.at("scenarios").empty()) {
    std::printf("\nHard sets (each scenario's own expectations are the issues' targets)\n");
    std::printf("  %-18s %6s %-6s %8s %9s %7s %9s %10s  %s\n", "experiment", "frames", "object", "demanded",
                "recall", "props/f", "detection", "FP/frame", "expectations unmet");
    for (const auto& sc : s.at("scenarios")) {
      bool first = true;
      for (const std::string& object : scenarioRowObjects(sc)) {
        const json& m = sc.at(object);
        std::string unmet;
        if (first) {
          unmet = unmetText(sc);
          if (unmet.empty()) unmet = "none (of " + std::to_string(sc.at("expectations").get<long>()) + ")";
        }
        std::printf("  %-18s %6s %-6s %8s %9s %7s %9s %10s  %s\n",
                    first ? sc.at("experiment").get<std::string>().c_str() : "",
                    first ? std::to_string(sc.at("frames").get<long>()).c_str() : "",
                    object == "orientation" ? "orient" : object.c_str(),
                    m.at("should_detect").is_number() ? std::to_string(m.at("should_detect").get<long>()).c_str()
                                                      : "-",
                    object == "orientation" ? "-" : fmt(m.at("proposal_recall")).c_str(),
                    object == "orientation" ? "-" : fmt(m.at("proposals_per_frame"), 1).c_str(),
                    fmt(m.at("detection_rate")).c_str(), fmt(m.at("false_positives_per_frame")).c_str(),
                    unmet.c_str());
        first = false;
      }
    }
  }
  if (s.contains("sweeps") && !s.at("sweeps").empty()) {
    std::printf("\nSweeps: rate per setting value, detection and the filtered orientation perceived (targets:");
    for (auto it = b.at("targets").begin(); it != b.at("targets").end(); ++it) {
      std::printf(" %s %s", it.key().c_str(), fmt(it.value(), 2).c_str());
    }
    std::printf(")\n");
    for (const auto& sw : s.at("sweeps")) {
      std::printf("  %s (%s):\n    %-12s", sw.at("experiment").get<std::string>().c_str(),
                  sw.at("setting").get<std::string>().c_str(), "value");
      for (const auto& v : sw.at("values")) std::printf(" %7s", fmt(v, 2).c_str());
      std::printf("\n");
      for (const auto& sr : kSweptRates) {
        std::printf("    %-12s", sr.label.c_str());
        for (const auto& v : sw.at("rates").at(sr.metric)) std::printf(" %7s", fmt(v, 2).c_str());
        std::printf("   %s\n", belowText(sw, sr.metric).c_str());
      }
      for (const auto& [key, label, decimals] : kSweptExtras) {
        if (!sw.contains(key)) continue;
        std::printf("    %-12s", label);
        for (const auto& v : sw.at(key)) std::printf(" %7s", fmt(v, decimals).c_str());
        std::printf("\n");
      }
    }
  }
}

std::string reportBody(const std::string& html) {
  const auto start = html.find("<body>");
  const auto end = html.rfind("</body>");
  std::string body = start == std::string::npos || end == std::string::npos ? html : html.substr(start + 6, end - start - 6);
  // The experiment's page title becomes a sub-heading of the bench page.
  for (const auto& [from, to] : std::vector<std::pair<std::string, std::string>>{
           {"<h3>", "<h4>"}, {"</h3>", "</h4>"}, {"<h2>", "<h3>"}, {"</h2>", "</h3>"}, {"<h1>", "<h3>"}, {"</h1>", "</h3>"}}) {
    for (auto p = body.find(from); p != std::string::npos; p = body.find(from, p + to.size())) body.replace(p, from.size(), to);
  }
  return body;
}

std::string renderBenchHtml(const json& results, const std::vector<std::string>& experiment_sections) {
  const json& s = results.at("summary");
  const json& b = results.at("bench");
  std::ostringstream h;
  h << "<!DOCTYPE html><html><head><meta charset='utf-8'><title>colorfree bench</title><style>"
       "body{font:14px/1.4 sans-serif;margin:20px;max-width:1150px;color:#222}"
       "table{border-collapse:collapse;margin:8px 0 16px}td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}"
       "th{background:#f0f0f0}td:first-child,th:first-child{text-align:left}"
       ".paper{color:#555;background:#fafafa}.absent{color:#b00;font-style:italic}.na{color:#777}"
       ".ok{color:#080}.fail{color:#b00;font-weight:bold}.chart{border:1px solid #ddd;margin:4px}"
       ".ct{font:bold 13px sans-serif}.ax{font:11px sans-serif;fill:#333}.grid{stroke:#e4e4e4}"
       ".gal{display:flex;flex-wrap:wrap;gap:8px}.gal figure{margin:0;width:170px;font-size:11px}"
       ".gal figure.wide{width:490px}.gal img{border:1px solid #999;image-rendering:pixelated;max-width:100%}"
       "section{border-top:3px solid #888;margin-top:30px}code{background:#f4f4f4}</style></head><body>";
  h << "<h1>colorfree bench</h1><p>" << esc(b.at("list").get<std::string>()) << (b.at("quick").get<bool>() ? " (--quick)" : "")
    << " &middot; " << b.at("frames") << " frames &middot; code " << esc(b.at("code_version").get<std::string>())
    << ". Ours on MuJoCo renders; the paper's on a real NAO V5. <span class=absent>absent</span> = the code has no "
       "such detector yet (never shown as 0).</p>";
  auto cell = [](const json& v, int prec = 3, double scale = 1, const char* unit = "") {
    return v.is_number() ? fmt(v, prec, scale, unit) : std::string("<span class=absent>absent</span>");
  };
  h << "<h2>Contents</h2><ul><li><a href='#summary'>The paper's tables, ours beside</a></li><li><a href='#sweeps'>Sweeps</a></li>";
  for (auto it = results.at("experiments").begin(); it != results.at("experiments").end(); ++it) {
    h << "<li><a href='#" << esc(it.key()) << "'>" << esc(it.key()) << "</a>: "
      << esc(at(it.value(), "bench.title").get<std::string>()) << "</li>";
  }
  h << "</ul><h2 id=summary>Table 2: detection set</h2>";
  if (s.contains("table2")) {
    const json& t = s.at("table2");
    h << "<p>" << esc(t.at("experiment").get<std::string>()) << ": " << t.at("frames") << " frames, " << t.at("cases")
      << " cases.</p><table><tr><th>metric</th><th>robot, ours</th><th class=paper>robot, paper</th><th>ball, ours</th>"
         "<th class=paper>ball, paper</th></tr>";
    for (const auto& [label, key] : std::vector<std::pair<std::string, std::string>>{
             {"avg. proposals per frame", "proposals_per_frame"}, {"proposal recall", "proposal_recall"},
             {"overall detection rate", "detection_rate"}, {"false positives per frame", "false_positives_per_frame"}}) {
      h << "<tr><td>" << label << "</td><td>" << cell(t.at("robot").at(key)) << "</td><td class=paper>"
        << (at(t, "paper.robot." + key).is_number() ? fmt(at(t, "paper.robot." + key)) : "&ndash;") << "</td><td>"
        << cell(t.at("ball").at(key)) << "</td><td class=paper>"
        << (at(t, "paper.ball." + key).is_number() ? fmt(at(t, "paper.ball." + key)) : "&ndash;") << "</td></tr>";
    }
    h << "</table>";
    if (t.contains("by_visible_fraction") && !t.at("by_visible_fraction").empty()) {
      const auto rate = [&](const json& o) {
        return o.at("truths").get<long>() > 0 ? cell(o.at("detection_rate"))
                                              : std::string("&ndash;");
      };
      h << "<h3>Detection rate per visible fraction (detection set; objects partly hidden by "
           "others or by the image border)</h3><table><tr><th>visible fraction</th>"
           "<th>robot detection</th><th>robot-frames</th><th>ball detection</th>"
           "<th>ball-frames</th></tr>";
      for (const auto& r : t.at("by_visible_fraction")) {
        h << "<tr><td>" << fmt(r.at("from_fraction"), 1) << "&ndash;" << fmt(r.at("to_fraction"), 1)
          << "</td><td>" << rate(r.at("robot")) << "</td><td>" << r.at("robot").at("truths")
          << "</td><td>" << rate(r.at("ball")) << "</td><td>" << r.at("ball").at("truths")
          << "</td></tr>";
      }
      h << "</table>";
    }
  }
  h << "<h2>Orientation (paper's Figs. 5 and 6)</h2><table><tr><th>experiment</th><th>tolerance deg</th>"
       "<th>robot-frames</th><th>perceived, raw</th><th>perceived, filtered</th><th class=paper>paper (filtered)</th></tr>";
  for (const char* which : {"orientation_static", "orientation_dynamic"}) {
    if (!s.contains(which)) continue;
    const json& o = s.at(which);
    h << "<tr><td>" << which << "</td><td>" << fmt(o.at("tolerance_deg"), 2) << "</td><td>" << o.at("robot_frames")
      << "</td><td>" << cell(o.at("raw").at("perceived"), 2, 100, " %") << "</td><td>"
      << cell(o.at("filtered").at("perceived"), 2, 100, " %") << "</td><td class=paper>"
      << fmt(o.at("paper_perceived"), 2, 100, " %") << "</td></tr>";
  }
  h << "</table><p>The charts of classes per true heading are in each orientation experiment's section below.</p>";
  if (s.contains("field_features")) {
    const json& f = s.at("field_features");
    h << "<h2>Field features</h2><table><tr><th>metric</th><th>ours</th><th class=paper>paper</th></tr><tr><td>pose "
         "error from field features, mean (mm)</td><td>"
      << cell(f.at("pose_error_mm"), 1) << "</td><td class=paper>40.07</td></tr><tr><td>RMS (mm)</td><td>"
      << cell(f.at("pose_error_rms_mm"), 1) << "</td><td class=paper>&ndash;</td></tr><tr><td>frames with a fit</td><td>"
      << cell(f.at("pose_fit_rate")) << "</td><td class=paper>&ndash;</td></tr></table>";
    if (f.contains("by_lighting_preset") && !f.at("by_lighting_preset").empty()) {
      h << "<h3>Per lighting preset (detection set)</h3><table><tr><th>preset</th><th>ball detection</th><th>robot "
           "detection</th><th>line detection</th><th>pose error mm</th><th>frames with a fit</th></tr>";
      for (const auto& r : f.at("by_lighting_preset")) {
        h << "<tr><td>" << esc(r.at("preset").get<std::string>()) << "</td><td>" << cell(r.at("ball_detection_rate"))
          << "</td><td>" << cell(r.at("robot_detection_rate")) << "</td><td>" << cell(r.at("line_detection_rate"))
          << "</td><td>" << cell(r.at("pose_error_mm"), 1) << "</td><td>" << cell(r.at("pose_fit_rate")) << "</td></tr>";
      }
      h << "</table>";
    }
  }
  if (s.contains("table3")) {
    h << "<h2>Table 3: profiling</h2><p>Ours: this machine, while rendering in parallel; paper: NAO V5.</p><table><tr>"
         "<th>module</th><th>mean ms</th><th>max ms</th><th class=paper>paper mean</th><th class=paper>paper max</th></tr>";
    for (const auto& st : s.at("table3").at("stages")) {
      const std::string key = st.at("stage").get<std::string>();
      const auto title = kStageTitles.find(key);
      h << "<tr><td>" << esc(title != kStageTitles.end() ? title->second : key) << "</td><td>" << cell(st.at("mean_ms"))
        << "</td><td>" << cell(st.at("max_ms")) << "</td><td class=paper>"
        << (st.at("paper_mean_ms").is_number() ? fmt(st.at("paper_mean_ms")) : "&ndash;") << "</td><td class=paper>"
        << (st.at("paper_max_ms").is_number() ? fmt(st.at("paper_max_ms")) : "&ndash;") << "</td></tr>";
    }
    h << "</table>";
  }
  h << "<h2>Table 1: CNN classifiers</h2><table><tr><th>net</th><th>input</th><th>parameters</th><th class=paper>paper "
       "parameters</th><th>&micro;s/patch single</th><th>&micro;s/patch batch 16</th><th class=paper>paper ms</th>"
       "<th>accuracy</th><th class=paper>paper accuracy</th></tr>";
  for (const auto& r : results.at("cnn_table")) {
    h << "<tr><td>" << esc(r.at("net").get<std::string>()) << "</td><td>" << esc(r.at("input").get<std::string>())
      << "</td><td>" << r.at("parameters") << "</td><td class=paper>" << paperFmt(r.at("paper_parameters"), 0)
      << "</td><td>" << fmt(r.at("us_per_patch_single"), 2) << "</td><td>" << fmt(r.at("us_per_patch_batch16"), 2)
      << "</td><td class=paper>" << paperFmt(r.at("paper_time_ms")) << "</td><td>" << esc(cnnAccuracy(results, r))
      << "</td><td class=paper>" << paperFmt(r.at("paper_accuracy")) << "</td></tr>";
  }
  h << "</table>";
  if (s.contains("scenarios") && !s.at("scenarios").empty()) {
    h << "<h2>Hard sets</h2><table><tr><th>experiment</th><th>frames</th><th>object</th><th>demanded</th>"
         "<th>proposal recall</th><th>proposals per frame</th><th>detection rate</th><th>false positives per "
         "frame</th><th>expectations not met</th></tr>";
    for (const auto& sc : s.at("scenarios")) {
      const std::string unmet = unmetText(sc);
      for (const std::string& object : scenarioRowObjects(sc)) {
        const json& m = sc.at(object);
        h << "<tr><td><a href='#" << esc(sc.at("experiment").get<std::string>()) << "'>"
          << esc(sc.at("experiment").get<std::string>()) << "</a></td><td>" << sc.at("frames").get<long>()
          << "</td><td>" << (object == "orientation" ? "orientation (filtered: shares of robot-frames)" : object)
          << "</td><td>" << cell(m.at("should_detect"), 0) << "</td><td>"
          << (object == "orientation" ? "-" : cell(m.at("proposal_recall"))) << "</td><td>"
          << (object == "orientation" ? "-" : cell(m.at("proposals_per_frame"), 1)) << "</td><td>"
          << cell(m.at("detection_rate")) << "</td><td>" << cell(m.at("false_positives_per_frame"))
          << "</td><td>" << esc(unmet.empty() ? "none" : unmet) << "</td></tr>";
      }
    }
    h << "</table>";
  }
  h << "<h2 id=sweeps>Sweeps: where each detector falls below its target</h2>";
  for (const auto& sw : s.at("sweeps")) {
    h << sweepChart(sw) << "<ul>";
    for (const auto& sr : kSweptRates) {
      h << "<li>" << esc(sr.label) << ": " << esc(belowText(sw, sr.metric)) << "</li>";
    }
    for (const auto& [key, label, decimals] : kSweptExtras) {
      if (!sw.contains(key)) continue;
      h << "<li>" << esc(label) << ":";
      for (std::size_t i = 0; i < sw.at(key).size(); ++i) {
        h << (i ? ", " : " ") << fmt(sw.at("values")[i], 2) << " &rarr; " << fmt(sw.at(key)[i], decimals);
      }
      h << "</li>";
    }
    h << "</ul>";
  }
  for (const auto& sec : experiment_sections) h << sec;
  h << "</body></html>\n";
  return h.str();
}

}  // namespace colorfree::app
