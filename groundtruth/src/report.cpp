#include "colorfree/groundtruth/report.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <sstream>

namespace colorfree {

namespace {

using json = nlohmann::json;

std::string esc(const std::string& s) {
  std::string o;
  for (char c : s) {
    switch (c) {
      case '&':
        o += "&amp;";
        break;
      case '<':
        o += "&lt;";
        break;
      case '>':
        o += "&gt;";
        break;
      case '"':
        o += "&quot;";
        break;
      default:
        o += c;
    }
  }
  return o;
}

std::string num(double v, int prec) {
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(prec);
  s << v;
  return s.str();
}

const json& at(const json& j, const std::string& path) {
  static const json kNull;
  const json* n = &j;
  std::size_t start = 0;
  while (true) {
    const std::size_t dot = path.find('.', start);
    const std::string key =
        path.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    if (!n->is_object() || !n->contains(key)) return kNull;
    n = &(*n)[key];
    if (dot == std::string::npos) return *n;
    start = dot + 1;
  }
}

// A metric cell: "absent" when the stage did not run, "n/a" when it ran but had nothing to count.
std::string cell(const json& v, bool stage_ran, int prec = 3, double scale = 1,
                 const std::string& unit = "") {
  if (v.is_number()) return num(v.get<double>() * scale, prec) + unit;
  return stage_ran ? "<span class=na>n/a</span>" : "<span class=absent>absent</span>";
}

bool ran(const json& r, const std::string& counter) {
  const json& v = at(r, counter);
  return v.is_number() && v.get<double>() > 0;
}

struct Series {
  std::string name;
  std::string colour;
  std::vector<std::pair<double, json>> points;
};

std::string lineChart(const std::string& title, const std::string& x_label,
                      const std::vector<Series>& series) {
  const double w = 520, h = 260, l = 50, r = 120, t = 30, b = 40;
  double xmin = 1e300, xmax = -1e300;
  for (const auto& s : series) {
    for (const auto& [x, y] : s.points) {
      xmin = std::min(xmin, x);
      xmax = std::max(xmax, x);
    }
  }
  if (xmin > xmax) return "";
  if (xmax == xmin) {
    xmin -= 1;
    xmax += 1;
  }
  auto X = [&](double x) { return l + (x - xmin) / (xmax - xmin) * (w - l - r); };
  auto Y = [&](double y) { return t + (1 - y) * (h - t - b); };
  std::ostringstream s;
  s << "<svg class=chart width=" << w << " height=" << h << " viewBox='0 0 " << w << " " << h
    << "'>";
  s << "<text x=" << l << " y=18 class=ct>" << esc(title) << "</text>";
  for (int k = 0; k <= 4; ++k) {
    const double y = k / 4.0;
    s << "<line x1=" << l << " x2=" << w - r << " y1=" << Y(y) << " y2=" << Y(y)
      << " class=grid />";
    s << "<text x=" << l - 6 << " y=" << Y(y) + 4 << " class=ax text-anchor=end>" << num(y, 2)
      << "</text>";
  }
  std::set<double> xs;
  for (const auto& se : series)
    for (const auto& pt : se.points) xs.insert(pt.first);
  const int stride = std::max<int>(1, static_cast<int>(xs.size()) / 10 + 1);
  int k = 0;
  for (double x : xs) {
    if (k++ % stride) continue;
    s << "<text x=" << X(x) << " y=" << h - b + 16 << " class=ax text-anchor=middle>" << num(x, 2)
      << "</text>";
  }
  s << "<text x=" << (l + w - r) / 2 << " y=" << h - 4 << " class=ax text-anchor=middle>"
    << esc(x_label) << "</text>";
  int row = 0;
  for (const auto& se : series) {
    std::string path;
    for (const auto& [x, y] : se.points) {
      if (!y.is_number()) continue;
      path += (path.empty() ? "M" : " L") + num(X(x), 1) + "," + num(Y(y.get<double>()), 1);
      s << "<circle cx=" << X(x) << " cy=" << Y(y.get<double>()) << " r=3 fill='" << se.colour
        << "' />";
    }
    if (!path.empty())
      s << "<path d='" << path << "' stroke='" << se.colour << "' fill=none stroke-width=2 />";
    s << "<rect x=" << w - r + 10 << " y=" << t + row * 18 << " width=12 height=12 fill='"
      << se.colour << "' />";
    s << "<text x=" << w - r + 26 << " y=" << t + row * 18 + 10 << " class=ax>" << esc(se.name)
      << (path.empty() ? " (absent)" : "") << "</text>";
    ++row;
  }
  s << "</svg>";
  return s.str();
}

const char* kClassNames[] = {"perceived", "semi_perceived", "not_perceived", "false_positive"};
const char* kClassColours[] = {"#2e9d4a", "#e6b422", "#9aa0a6", "#d6453d"};

std::string orientationChart(const json& per_heading, const std::string& which,
                             const std::string& title) {
  if (!per_heading.is_array() || per_heading.empty()) return "";
  const double bw = 34, gap = 8, l = 50, t = 30, h = 260, b = 40;
  const double w = l + per_heading.size() * (bw + gap) + 150;
  std::ostringstream s;
  s << "<svg class=chart width=" << w << " height=" << h << " viewBox='0 0 " << w << " " << h
    << "'>";
  s << "<text x=" << l << " y=18 class=ct>" << esc(title) << "</text>";
  auto Y = [&](double y) { return t + (1 - y) * (h - t - b); };
  for (int k = 0; k <= 4; ++k) {
    s << "<text x=" << l - 6 << " y=" << Y(k / 4.0) + 4 << " class=ax text-anchor=end>" << k * 25
      << "%</text>";
  }
  double x = l;
  for (const auto& bin : per_heading) {
    const json& c = bin[which];
    double acc = 0;
    for (int k = 0; k < 4; ++k) {
      const double v = c[kClassNames[k]].is_number() ? c[kClassNames[k]].get<double>() : 0;
      if (v > 0) {
        s << "<rect x=" << x << " y=" << Y(acc + v) << " width=" << bw
          << " height=" << Y(acc) - Y(acc + v) << " fill='" << kClassColours[k] << "'><title>"
          << kClassNames[k] << " " << num(100 * v, 1) << " %</title></rect>";
      }
      acc += v;
    }
    s << "<text x=" << x + bw / 2 << " y=" << h - b + 14 << " class=ax text-anchor=middle>"
      << num(bin["heading_deg"].get<double>(), 1) << "</text>";
    s << "<text x=" << x + bw / 2 << " y=" << h - b + 26
      << " class=ax text-anchor=middle>n=" << c["robot_frames"].get<long>() << "</text>";
    x += bw + gap;
  }
  s << "<text x=" << (l + x) / 2 << " y=" << h - 2
    << " class=ax text-anchor=middle>true heading, deg (0 = facing the camera)</text>";
  for (int k = 0; k < 4; ++k) {
    s << "<rect x=" << x + 10 << " y=" << t + k * 18 << " width=12 height=12 fill='"
      << kClassColours[k] << "' />";
    s << "<text x=" << x + 26 << " y=" << t + k * 18 + 10 << " class=ax>" << kClassNames[k]
      << "</text>";
  }
  s << "</svg>";
  return s.str();
}

}  // namespace

std::string renderReportHtml(const json& r, const std::vector<GalleryItem>& gallery,
                             const std::vector<ExpectationLine>& expectations) {
  std::ostringstream h;
  const std::string scenario = r.value("scenario", std::string());
  h << "<!DOCTYPE html><html><head><meta charset='utf-8'><title>colorfree: " << esc(scenario)
    << "</title><style>"
       "body{font:14px/1.4 sans-serif;margin:20px;max-width:1150px;color:#222}"
       "table{border-collapse:collapse;margin:8px 0 16px}td,th{border:1px solid #ccc;padding:3px "
       "8px;text-align:right}"
       "th{background:#f0f0f0}td:first-child,th:first-child{text-align:left}"
       ".paper{color:#555;background:#fafafa}.absent{color:#b00;font-style:italic}.na{color:#777}"
       ".ok{color:#080}.fail{color:#b00;font-weight:bold}.chart{border:1px solid #ddd;margin:4px}"
       ".ct{font:bold 13px sans-serif}.ax{font:11px sans-serif;fill:#333}.grid{stroke:#e4e4e4}"
       ".gal{display:flex;flex-wrap:wrap;gap:8px}.gal figure{margin:0;width:170px;font-size:11px}"
       ".gal figure.wide{width:490px}.gal img{border:1px solid "
       "#999;image-rendering:pixelated;max-width:100%}"
       "code{background:#f4f4f4}</style></head><body>";
  h << "<h1>colorfree run: " << esc(scenario) << "</h1>";
  h << "<p>seed " << r.value("seed", 0) << " &middot; " << r.value("frame_count", 0L)
    << " frames &middot; " << at(r, "cases").size() << " case(s) &middot; code "
    << esc(r.value("code_version", std::string())) << "</p>";

  if (!expectations.empty()) {
    h << "<h2>Expectations</h2><table><tr><th>expectation</th><th>result</th></tr>";
    for (const auto& e : expectations) {
      h << "<tr><td><code>" << esc(e.text) << "</code></td><td class=" << (e.met ? "ok" : "fail")
        << ">" << (e.met ? "met" : "NOT MET") << " " << esc(e.detail) << "</td></tr>";
    }
    h << "</table>";
  }

  // Table 2 of the paper.
  const bool rp = ran(r, "robot.counts.proposal_frames"),
             rd = ran(r, "robot.counts.detector_frames");
  const bool bp = ran(r, "ball.counts.proposal_frames"), bd = ran(r, "ball.counts.detector_frames");
  h << "<h2>Robots and ball (paper's Table 2)</h2><table><tr><th>metric</th><th>robot, ours</th>"
       "<th class=paper>robot, paper</th><th>ball, ours</th><th class=paper>ball, paper</th></tr>";
  auto row2 = [&](const std::string& name, const std::string& key, bool rs, bool bs,
                  const std::string& pr, const std::string& pb, int prec = 3) {
    h << "<tr><td>" << name << "</td><td>" << cell(at(r, "robot." + key), rs, prec)
      << "</td><td class=paper>" << pr << "</td><td>" << cell(at(r, "ball." + key), bs, prec)
      << "</td><td class=paper>" << pb << "</td></tr>";
  };
  row2("avg. proposals per frame", "proposals_per_frame", rp, bp, "3.05", "10.3", 2);
  row2("proposal recall", "proposal_recall", rp, bp, "0.972", "0.993");
  row2("overall accuracy (detection rate)", "detection_rate", rd, bd, "0.949",
       "0.971 (B-Human 0.697)");
  row2("false positives per frame", "false_positives_per_frame", rd, bd, "&ndash;", "&ndash;");
  row2("precision", "precision", rd, bd, "&ndash;", "&ndash;");
  row2("position error on the field, mean (m)", "position_error_m", rd, bd, "&ndash;", "&ndash;");
  row2("position error on the field, RMS (m)", "position_error_rms_m", rd, bd, "&ndash;",
       "&ndash;");
  h << "<tr><td>object-frames that should be detected</td><td>"
    << at(r, "robot.counts.should_detect") << "</td><td class=paper></td><td>"
    << at(r, "ball.counts.should_detect") << "</td><td class=paper>~600 frames</td></tr></table>";

  // Orientation.
  const json& o = at(r, "orientation");
  const bool orr = ran(r, "orientation.robot_frames");
  const double tol = o.value("tolerance_deg", 0.0);
  h << "<h2>Robot orientation (paper's Figs. 5 and 6)</h2><p>Tolerance " << num(tol, 2)
    << " deg; classes per observed robot and frame (a robot that should be detected but was not "
       "counts as "
       "not perceived). Paper: perceived 99.88 % static (tolerance 11.25 deg), 95.52 % dynamic "
       "(22.5 deg, "
       "12 cm/s), filtered estimates.</p>";
  h << "<table><tr><th>class</th><th>raw, ours</th><th>filtered, ours</th><th class=paper>paper, "
       "filtered</th></tr>";
  const std::string paper_perceived =
      tol <= 11.25 + 1e-6 ? "99.88 % (static)" : "95.52 % (dynamic)";
  for (int k = 0; k < 4; ++k) {
    h << "<tr><td>" << kClassNames[k] << "</td><td>" << cell(o[kClassNames[k]], orr, 2, 100, " %")
      << "</td><td>" << cell(o["filtered"][kClassNames[k]], orr, 2, 100, " %")
      << "</td><td class=paper>" << (k == 0 ? paper_perceived : "&ndash;") << "</td></tr>";
  }
  h << "<tr><td>robot-frames</td><td>" << o.value("robot_frames", 0L)
    << "</td><td></td><td class=paper></td></tr></table>";
  if (orr) {
    h << orientationChart(o["per_heading"], "raw", "Orientation classes per true heading, raw")
      << orientationChart(o["per_heading"], "filtered",
                          "Orientation classes per true heading, filtered");
  } else {
    h << "<p class=absent>The pipeline has no orientation stage: orientation absent.</p>";
  }

  // Field features.
  const bool ffr = ran(r, "field_features.counts.frames");
  const bool pfr = ran(r, "field_features.counts.pose_frames");
  h << "<h2>Field lines and features</h2><table><tr><th>metric</th><th>ours</th><th "
       "class=paper>paper</th></tr>";
  h << "<tr><td>pose error from features, mean (mm)</td><td>"
    << cell(at(r, "field_features.pose_error_mm"), pfr, 1)
    << "</td><td class=paper>40.07</td></tr>";
  h << "<tr><td>pose error, RMS (mm)</td><td>"
    << cell(at(r, "field_features.pose_error_rms_mm"), pfr, 1)
    << "</td><td class=paper>&ndash;</td></tr>";
  h << "<tr><td>frames with a pose fit</td><td>"
    << cell(at(r, "field_features.pose_fit_rate"), pfr, 3)
    << "</td><td class=paper>&ndash;</td></tr>";
  for (const auto& [name, key] : std::vector<std::pair<std::string, std::string>>{
           {"line detection rate", "line_detection_rate"},
           {"intersection (L/T/X) detection rate", "intersection_detection_rate"},
           {"centre circle detection rate", "centre_circle_detection_rate"},
           {"penalty mark detection rate", "penalty_mark_detection_rate"},
           {"false lines per frame", "false_lines_per_frame"},
           {"false intersections per frame", "false_intersections_per_frame"}}) {
    h << "<tr><td>" << name << "</td><td>" << cell(at(r, "field_features." + key), ffr, 3)
      << "</td><td class=paper>&ndash;</td></tr>";
  }
  h << "</table>";

  // Table 3.
  static const std::map<std::string, std::pair<std::string, std::pair<double, double>>>
      kPaperStages = {{"high_contrast", {"High contrast regions detector", {1.478, 2.755}}},
                      {"field_features", {"Field lines &amp; features detector", {1.300, 2.909}}},
                      {"robot_proposals", {"Robot proposals generator", {1.083, 2.692}}},
                      {"robot_detector", {"Robot detector", {0.939, 2.417}}},
                      {"robot_orientation", {"Robot orientation detector", {1.366, 4.537}}},
                      {"ball_proposals", {"Ball proposals generator", {1.132, 2.506}}},
                      {"ball_detector", {"Ball detector", {2.452, 6.959}}}};
  h << "<h2>Profiling (paper's Table 3; ours on this machine, paper's on a NAO "
       "V5)</h2><table><tr><th>module</th>"
       "<th>avg. ms, ours</th><th>max. ms, ours</th><th class=paper>avg. ms, paper</th><th "
       "class=paper>max. ms, paper</th></tr>";
  // The paper's rows in its order, then any other stage the pipeline timed.
  std::vector<std::string> stage_order = paperStageNames();
  for (auto it = at(r, "timing_ms").begin(); it != at(r, "timing_ms").end(); ++it) {
    if (std::find(stage_order.begin(), stage_order.end(), it.key()) == stage_order.end())
      stage_order.push_back(it.key());
  }
  for (const auto& key : stage_order) {
    const json& t = at(r, "timing_ms")[key];
    const auto p = kPaperStages.find(key);
    const bool present = t.is_object() && t["mean"].is_number();
    h << "<tr><td>"
      << (p != kPaperStages.end() ? p->second.first + " (<code>" + key + "</code>)"
                                  : "<code>" + esc(key) + "</code>")
      << "</td><td>" << cell(present ? t["mean"] : json(), present, 3) << "</td><td>"
      << cell(present ? t["max"] : json(), present, 3) << "</td><td class=paper>"
      << (p != kPaperStages.end() ? num(p->second.second.first, 3) : "&ndash;")
      << "</td><td class=paper>"
      << (p != kPaperStages.end() ? num(p->second.second.second, 3) : "&ndash;") << "</td></tr>";
  }
  h << "</table>";

  // Table 1.
  static const std::map<std::string, std::string> kPaperCnn = {
      {"RobotNet", "24&times;24&times;1, 884 params, 0.382 ms, 0.969"},
      {"BoostBallNet", "12&times;12&times;1, 125 params, 0.043 ms, 0.965"},
      {"BallNet", "26&times;26&times;1, 444 params, 0.343 ms, 0.984"},
      {"OriBoostNet", "12&times;12&times;1, 246 params, 0.059 ms, 0.962"},
      {"OriNet", "24&times;24&times;1, 657 params, 0.329 ms, 0.984"}};
  h << "<h2>CNN classifiers (paper's Table 1): accuracy on the samples that reached "
       "each</h2><table><tr><th>model</th>"
       "<th>accuracy, ours</th><th>samples</th><th>left out (on an object too hidden to demand)</th>"
       "<th class=paper>paper: input, parameters, time, "
       "accuracy</th></tr>";
  for (auto it = at(r, "cnn").begin(); it != at(r, "cnn").end(); ++it) {
    const auto p = kPaperCnn.find(it.key());
    const bool present = it.value().value("samples", 0L) > 0;
    h << "<tr><td>" << esc(it.key()) << "</td><td>" << cell(it.value()["accuracy"], present, 3)
      << "</td><td>" << it.value().value("samples", 0L) << "</td><td>"
      << it.value().value("ambiguous", 0L) << "</td><td class=paper>"
      << (p != kPaperCnn.end() ? p->second : "&ndash;") << "</td></tr>";
  }
  h << "</table>";

  // Charts against the swept settings and distance.
  h << "<h2>Detection rate against conditions</h2>";
  const json& cases = at(r, "cases");
  std::set<std::string> keys;
  for (const auto& c : cases) {
    for (auto it = c["settings"].begin(); it != c["settings"].end(); ++it) {
      if (it.value().is_number()) keys.insert(it.key());
    }
  }
  bool any_chart = false;
  for (const auto& key : keys) {
    std::set<double> values;
    for (const auto& c : cases) {
      if (c["settings"].contains(key)) values.insert(c["settings"][key].get<double>());
    }
    if (values.size() < 2) continue;
    // Cases that share a value of this setting are pooled by their counts.
    std::map<double, std::array<long, 8>> pooled;
    for (const auto& c : cases) {
      if (!c["settings"].contains(key)) continue;
      auto& a = pooled[c["settings"][key].get<double>()];
      a[0] += c["ball"]["counts"]["detected"].get<long>();
      a[1] += c["ball"]["counts"]["truths"].get<long>();
      a[2] += c["robot"]["counts"]["detected"].get<long>();
      a[3] += c["robot"]["counts"]["truths"].get<long>();
      const json& fc = c["field_features"]["counts"];
      a[4] += fc["lines_detected"].get<long>();
      a[5] += fc["lines_in_view"].get<long>();
      a[6] += fc["intersections_detected"].get<long>();
      a[7] += fc["intersections_in_view"].get<long>();
    }
    Series ball{"ball", "#1f6fd1", {}}, robot{"robot", "#d6453d", {}};
    Series lines{"field lines", "#2e9d4a", {}}, crossings{"L/T/X", "#8e44ad", {}};
    auto ratio = [](bool present, long num, long den) {
      return present && den > 0 ? json(static_cast<double>(num) / den) : json(nullptr);
    };
    for (const auto& [v, a] : pooled) {
      ball.points.push_back({v, ratio(bd, a[0], a[1])});
      robot.points.push_back({v, ratio(rd, a[2], a[3])});
      lines.points.push_back({v, ratio(ffr, a[4], a[5])});
      crossings.points.push_back({v, ratio(ffr, a[6], a[7])});
    }
    h << lineChart("Detection rate against " + key, key, {ball, robot, lines, crossings});
    any_chart = true;
  }
  // The detection rate per bin of the scorer's by_distance / by_visibility tables.
  const auto binChart = [&](const std::string& table, const std::string& unit,
                            const std::string& title, const std::string& axis) {
    Series ball{"ball", "#1f6fd1", {}}, robot{"robot", "#d6453d", {}};
    for (Series* s : {&ball, &robot}) {
      for (const auto& b : at(r, table + "." + s->name)) {
        s->points.push_back({(b["from_" + unit].get<double>() + b["to_" + unit].get<double>()) / 2,
                             b["detection_rate"]});
      }
    }
    if (ball.points.empty() && robot.points.empty()) return;
    h << lineChart(title, axis, {ball, robot});
    any_chart = true;
  };
  binChart("by_distance", "m", "Detection rate against distance (all frames)",
           "distance from the observer, m (bin centre)");
  binChart("by_visibility", "fraction", "Detection rate against the visible fraction (all frames)",
           "visible fraction of the demanded object (bin centre)");
  if (!any_chart) h << "<p class=na>No sweep and no detector output to chart.</p>";

  if (cases.size() > 1) {
    h << "<h2>Per case</h2><table><tr><th>case</th><th>settings</th><th>frames</th><th>ball "
         "det.</th><th>ball recall</th>"
         "<th>ball FP/frame</th><th>robot det.</th><th>robot recall</th><th>robot "
         "FP/frame</th><th>orient. perceived</th>"
         "<th>pose err. mm</th></tr>";
    for (const auto& c : cases) {
      std::string settings;
      for (auto it = c["settings"].begin(); it != c["settings"].end(); ++it) {
        settings += it.key() + "=" +
                    (it.value().is_number() ? num(it.value().get<double>(), 3)
                                            : it.value().get<std::string>()) +
                    " ";
      }
      h << "<tr><td>" << esc(c["name"].get<std::string>()) << "</td><td>" << esc(settings)
        << "</td><td>" << c["frames"] << "</td><td>" << cell(c["ball"]["detection_rate"], bd)
        << "</td><td>" << cell(c["ball"]["proposal_recall"], bp) << "</td><td>"
        << cell(c["ball"]["false_positives_per_frame"], bd) << "</td><td>"
        << cell(c["robot"]["detection_rate"], rd) << "</td><td>"
        << cell(c["robot"]["proposal_recall"], rp) << "</td><td>"
        << cell(c["robot"]["false_positives_per_frame"], rd) << "</td><td>"
        << cell(c["orientation"]["perceived"], orr, 3) << "</td><td>"
        << cell(c["field_features"]["pose_error_mm"], pfr, 1) << "</td></tr>";
    }
    h << "</table>";
  }

  h << "<h2>Rules and thresholds</h2><p><b>Should be detected.</b> "
    << esc(r.value("should_detect_rule", std::string())) << "</p><p><b>Matching.</b> "
    << esc(r.value("matching_rule", std::string()))
    << "</p><p><b>Absent</b> means the pipeline has no such stage yet; it is never shown as 0 or "
       "as perfect. "
       "<b>n/a</b> means the stage ran but there was nothing to "
       "count.</p><table><tr><th>parameter</th><th>value</th></tr>";
  for (auto it = at(r, "scoring").begin(); it != at(r, "scoring").end(); ++it) {
    h << "<tr><td><code>" << esc(it.key()) << "</code></td><td>" << it.value().dump()
      << "</td></tr>";
  }
  h << "</table>";

  h << "<h2>Gallery</h2><p>Green: truth. Red: percepts. Yellow: proposals near a missed "
       "object.</p>";
  static const std::vector<std::pair<std::string, std::string>> kKinds = {
      {"worst_frame", "Worst frames"},
      {"missed_ball", "Missed balls (most visible first)"},
      {"false_ball", "False balls (most confident first)"},
      {"missed_robot", "Missed robots (most visible first)"},
      {"false_robot", "False robots (most confident first)"},
      {"orientation", "Orientation false positives"},
      {"missed_intersection", "Missed L/T/X intersections (first seen)"},
      {"false_intersection", "False L/T/X intersections (first seen)"}};
  bool any = false;
  for (const auto& [kind, title] : kKinds) {
    std::vector<const GalleryItem*> items;
    for (const auto& g : gallery)
      if (g.kind == kind) items.push_back(&g);
    if (items.empty()) continue;
    any = true;
    h << "<h3>" << title << "</h3><div class=gal>";
    for (const auto* g : items) {
      h << "<figure" << (kind == "worst_frame" ? " class=wide" : "")
        << "><img src='data:image/png;base64," << g->png_base64 << "'><figcaption>"
        << esc(g->caption) << "</figcaption></figure>";
    }
    h << "</div>";
  }
  if (!any) h << "<p class=na>Nothing missed and nothing false (or no detector ran).</p>";
  h << "</body></html>\n";
  return h.str();
}

}  // namespace colorfree
