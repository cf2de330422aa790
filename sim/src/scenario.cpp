#include "colorfree/sim/scenario.h"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <set>
#include <sstream>

#include "colorfree/perception/error.h"

namespace colorfree::sim {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

// Lighting preset names as the scenario file spells them (world.h's enum, in order).
const std::vector<std::pair<std::string, LightingPreset>>& presetNames() {
  static const std::vector<std::pair<std::string, LightingPreset>> kNames = {
      {"normal", LightingPreset::kNormal},           {"dim", LightingPreset::kDim},
      {"overexposed", LightingPreset::kOverexposed}, {"directional", LightingPreset::kDirectional},
      {"uneven", LightingPreset::kUneven},           {"flicker", LightingPreset::kFlicker}};
  return kNames;
}

std::string lineOf(const YAML::Mark& mark) {
  return mark.line >= 0 ? std::to_string(mark.line + 1) : std::string("?");
}

std::string scalarText(const YAML::Node& node) {
  if (node.IsScalar()) return node.Scalar();
  if (node.IsSequence()) return "a list";
  if (node.IsMap()) return "a mapping";
  return "nothing";
}

// Reads one YAML mapping strictly: every read key is remembered, finish() rejects the others.
// Errors read "file:line: key.path: problem".
class MapReader {
 public:
  MapReader(const YAML::Node& node, std::string path, const std::string& origin)
      : node_(node), path_(std::move(path)), origin_(origin) {
    if (!node_.IsMap())
      fail(node_.Mark(), path_, "expected a mapping of key: value, got " + scalarText(node_));
  }

  [[noreturn]] void fail(const YAML::Mark& mark, const std::string& key_path,
                         const std::string& what) const {
    throw Error(origin_ + ":" + lineOf(mark) + ": " + (key_path.empty() ? "" : key_path + ": ") +
                what);
  }

  std::string keyPath(const std::string& key) const {
    return path_.empty() ? key : path_ + "." + key;
  }

  bool has(const std::string& key) const { return static_cast<bool>(node_[key]); }

  YAML::Node required(const std::string& key) {
    const YAML::Node value = node_[key];
    if (!value) fail(node_.Mark(), keyPath(key), "missing required key");
    used_.insert(key);
    if (value.IsNull()) fail(value.Mark(), keyPath(key), "has no value");
    return value;
  }

  YAML::Node optional(const std::string& key) {
    const YAML::Node value = node_[key];
    if (value) used_.insert(key);
    return value;
  }

  double number(const YAML::Node& value, const std::string& key, double lo, double hi) const {
    if (!value.IsScalar())
      fail(value.Mark(), keyPath(key), "expected a number, got " + scalarText(value));
    double v = 0;
    try {
      v = value.as<double>();
    } catch (const YAML::Exception&) {
      fail(value.Mark(), keyPath(key), "expected a number, got '" + value.Scalar() + "'");
    }
    if (!std::isfinite(v) || v < lo || v > hi) {
      std::ostringstream msg;
      msg << "value " << value.Scalar() << " is out of range [" << lo << ", " << hi << "]";
      fail(value.Mark(), keyPath(key), msg.str());
    }
    return v;
  }

  double number(const std::string& key, double lo, double hi) {
    return number(required(key), key, lo, hi);
  }
  double number(const std::string& key, double lo, double hi, double fallback) {
    const YAML::Node value = optional(key);
    return value ? number(value, key, lo, hi) : fallback;
  }

  long long integer(const YAML::Node& value, const std::string& key, long long lo,
                    long long hi) const {
    if (!value.IsScalar())
      fail(value.Mark(), keyPath(key), "expected an integer, got " + scalarText(value));
    long long v = 0;
    try {
      v = value.as<long long>();
    } catch (const YAML::Exception&) {
      fail(value.Mark(), keyPath(key), "expected an integer, got '" + value.Scalar() + "'");
    }
    if (v < lo || v > hi) {
      fail(value.Mark(), keyPath(key),
           "value " + value.Scalar() + " is out of range [" + std::to_string(lo) + ", " +
               std::to_string(hi) + "]");
    }
    return v;
  }
  long long integer(const std::string& key, long long lo, long long hi) {
    return integer(required(key), key, lo, hi);
  }
  long long integer(const std::string& key, long long lo, long long hi, long long fallback) {
    const YAML::Node value = optional(key);
    return value ? integer(value, key, lo, hi) : fallback;
  }

  bool boolean(const std::string& key, bool fallback) {
    const YAML::Node value = optional(key);
    if (!value) return fallback;
    try {
      if (!value.IsScalar()) throw YAML::Exception(value.Mark(), "");
      return value.as<bool>();
    } catch (const YAML::Exception&) {
      fail(value.Mark(), keyPath(key), "expected true or false, got '" + scalarText(value) + "'");
    }
  }

  std::string string(const YAML::Node& value, const std::string& key) const {
    if (!value.IsScalar())
      fail(value.Mark(), keyPath(key), "expected a string, got " + scalarText(value));
    return value.Scalar();
  }
  std::string string(const std::string& key) { return string(required(key), key); }

  // One of `choices`; the error lists them.
  std::string choice(const YAML::Node& value, const std::string& key,
                     const std::vector<std::string>& choices) const {
    const std::string s = string(value, key);
    for (const auto& c : choices) {
      if (c == s) return s;
    }
    std::string list;
    for (const auto& c : choices) list += (list.empty() ? "" : ", ") + c;
    fail(value.Mark(), keyPath(key), "'" + s + "' is not one of: " + list);
  }

  void finish() const {
    for (const auto& kv : node_) {
      const std::string key = kv.first.Scalar();
      // A key a sweep added has no line of its own: its value (in the sweep list) has one.
      const YAML::Mark mark = kv.first.Mark().line >= 0 ? kv.first.Mark() : kv.second.Mark();
      if (!used_.count(key)) fail(mark, keyPath(key), "unknown key");
    }
  }

  const YAML::Node& node() const { return node_; }
  const std::string& origin() const { return origin_; }

 private:
  YAML::Node node_;
  std::string path_;
  const std::string& origin_;
  std::set<std::string> used_;
};

MotionSpec parseMotion(MapReader& parent, const std::string& key, std::uint64_t seed_phase) {
  MotionSpec motion;
  const YAML::Node node = parent.optional(key);
  // A robot's gait phase defaults to a value spread by its index so robots do not step in unison.
  motion.phase = static_cast<double>(seed_phase % 1000) / 1000.0;
  if (!node) return motion;
  const std::string path = parent.keyPath(key);
  if (node.IsScalar()) {
    if (parent.choice(node, key, {"stand"}) == "stand") motion.kind = MotionSpec::Kind::kStand;
    return motion;
  }
  MapReader r(node, path, parent.origin());
  const std::string type = r.choice(r.required("type"), "type", {"stand", "walk", "turn"});
  if (type == "walk") {
    motion.kind = MotionSpec::Kind::kWalk;
    motion.speed_mps = r.number("speed_mps", 0, 0.6);
    motion.direction_rad = r.number("direction_deg", -180, 180, 0) * kDegToRad;
  } else if (type == "turn") {
    motion.kind = MotionSpec::Kind::kTurn;
    motion.turn_rate_radps = r.number("rate_degps", -180, 180) * kDegToRad;
  }
  motion.phase = r.number("phase", 0, 1, motion.phase);
  if (motion.phase >= 1) motion.phase = 0;
  r.finish();
  return motion;
}

// Position of a robot or the ball: x_m/y_m on the field, or distance_m/bearing_deg from the
// observer (bearing relative to the observer's heading).
void parsePosition(MapReader& r, const FieldPose& observer, const FieldDimensions& field,
                   double& x_m, double& y_m) {
  const bool absolute = r.has("x_m") || r.has("y_m");
  const bool relative = r.has("distance_m") || r.has("bearing_deg");
  if (absolute && relative) {
    r.fail(r.node().Mark(), r.keyPath("distance_m"),
           "give either x_m/y_m or distance_m/bearing_deg, not both");
  }
  const double half_x = field.carpetHalfLength();
  const double half_y = field.carpetHalfWidth();
  if (relative) {
    const double distance = r.number("distance_m", 0, 2 * half_x);
    const double bearing = r.number("bearing_deg", -360, 360, 0) * kDegToRad;
    x_m = observer.x_m + distance * std::cos(observer.heading_rad + bearing);
    y_m = observer.y_m + distance * std::sin(observer.heading_rad + bearing);
    if (std::abs(x_m) > half_x || std::abs(y_m) > half_y) {
      r.fail(
          r.node()["distance_m"].Mark(), r.keyPath("distance_m"),
          "puts it off the carpet at (" + std::to_string(x_m) + ", " + std::to_string(y_m) + ")");
    }
  } else {
    x_m = r.number("x_m", -half_x, half_x);
    y_m = r.number("y_m", -half_y, half_y);
  }
}

HeadSpec parseHead(MapReader& parent) {
  HeadSpec head;
  const YAML::Node node = parent.optional("head");
  if (!node) return head;
  MapReader r(node, parent.keyPath("head"), parent.origin());
  // NAO joint ranges (REFERENCE.md): HeadYaw ±119.5°, HeadPitch −38.5..29.5°.
  head.yaw_rad = r.number("yaw_deg", -119.5, 119.5, 0) * kDegToRad;
  head.pitch_rad = r.number("pitch_deg", -38.5, 29.5, 0) * kDegToRad;
  head.yaw_amplitude_rad = r.number("yaw_amplitude_deg", 0, 119.5, 0) * kDegToRad;
  head.yaw_period_s = r.number("yaw_period_s", 0.1, 60, 2);
  head.pitch_amplitude_rad = r.number("pitch_amplitude_deg", 0, 34, 0) * kDegToRad;
  head.pitch_period_s = r.number("pitch_period_s", 0.1, 60, 2);
  const double yaw_max = 119.5 * kDegToRad + 1e-9;
  if (std::abs(head.yaw_rad) + head.yaw_amplitude_rad > yaw_max) {
    r.fail(node["yaw_amplitude_deg"].Mark(), r.keyPath("yaw_amplitude_deg"),
           "yaw_deg ± yaw_amplitude_deg leaves the head yaw range ±119.5°");
  }
  if (head.pitch_rad - head.pitch_amplitude_rad < -38.5 * kDegToRad - 1e-9 ||
      head.pitch_rad + head.pitch_amplitude_rad > 29.5 * kDegToRad + 1e-9) {
    r.fail(node["pitch_amplitude_deg"].Mark(), r.keyPath("pitch_amplitude_deg"),
           "pitch_deg ± pitch_amplitude_deg leaves the head pitch range -38.5..29.5°");
  }
  r.finish();
  return head;
}

CaseSettings parseCase(const YAML::Node& root, const std::string& origin,
                       const FieldDimensions& field) {
  CaseSettings s;
  s.ball_radius_m = field.ballRadius();
  MapReader r(root, "", origin);
  r.required("name");
  r.optional("sweep");
  r.optional("expect");

  const std::string camera = r.choice(r.required("camera"), "camera", {"top", "bottom"});
  s.camera = camera == "top" ? NaoCamera::kTop : NaoCamera::kBottom;
  s.width_px = s.camera == NaoCamera::kTop ? 640 : 320;
  s.height_px = s.camera == NaoCamera::kTop ? 480 : 240;
  if (const YAML::Node res = r.optional("resolution")) {
    const std::string key = "resolution";
    if (!res.IsSequence() || res.size() != 2) {
      r.fail(res.Mark(), key, "expected [width_px, height_px], got " + scalarText(res));
    }
    s.width_px = static_cast<int>(r.integer(res[0], key + "[0]", 16, 1280));
    s.height_px = static_cast<int>(r.integer(res[1], key + "[1]", 12, 960));
  }
  s.frames = static_cast<int>(r.integer("frames", 1, 100000));
  s.frame_rate_hz = r.number("frame_rate_hz", 0.1, 1000);
  s.seed = static_cast<std::uint64_t>(r.integer("seed", 0, std::numeric_limits<long long>::max()));
  std::string nao = "v5";
  if (const YAML::Node v = r.optional("nao")) nao = r.choice(v, "nao", {"v5", "v6"});
  s.camera_horizontal_fov_deg = nao == "v6" ? 56.3 : 60.9;
  s.shadows = r.boolean("shadows", true);
  s.multisamples = static_cast<int>(r.integer("multisamples", 0, 16, 4));

  {
    MapReader o(r.required("observer"), "observer", origin);
    s.observer.pose.x_m = o.number("x_m", -field.carpetHalfLength(), field.carpetHalfLength());
    s.observer.pose.y_m = o.number("y_m", -field.carpetHalfWidth(), field.carpetHalfWidth());
    s.observer.pose.heading_rad = o.number("heading_deg", -360, 360) * kDegToRad;
    s.observer.head = parseHead(o);
    s.observer.jersey_gray = o.number("jersey_gray", 0, 1, 0.5);
    s.observer.motion = parseMotion(o, "motion", 0);
    o.finish();
  }

  if (const YAML::Node robots = r.optional("robots")) {
    if (!robots.IsSequence()) r.fail(robots.Mark(), "robots", "expected a list of robots");
    if (robots.size() > static_cast<std::size_t>(kMaxRobots)) {
      r.fail(robots.Mark(), "robots",
             std::to_string(robots.size()) + " robots; at most " + std::to_string(kMaxRobots) +
                 " besides the observer");
    }
    for (std::size_t i = 0; i < robots.size(); ++i) {
      MapReader rr(robots[i], "robots[" + std::to_string(i) + "]", origin);
      RobotSpec robot;
      parsePosition(rr, s.observer.pose, field, robot.pose.x_m, robot.pose.y_m);
      robot.pose.heading_rad = rr.number("heading_deg", -360, 360) * kDegToRad;
      robot.jersey_gray = rr.number("jersey_gray", 0, 1, 0.5);
      robot.motion = parseMotion(rr, "motion", 137 * (i + 1) + s.seed);
      rr.finish();
      s.robots.push_back(robot);
    }
  }

  if (const YAML::Node ball = r.optional("ball"); ball && !ball.IsNull()) {
    MapReader b(ball, "ball", origin);
    BallSpec spec;
    parsePosition(b, s.observer.pose, field, spec.x_m, spec.y_m);
    spec.velocity_x_mps = b.number("velocity_x_mps", -10, 10, 0);
    spec.velocity_y_mps = b.number("velocity_y_mps", -10, 10, 0);
    spec.deceleration_mps2 = b.number("deceleration_mps2", 0, 20, spec.deceleration_mps2);
    b.finish();
    s.ball = spec;
  }

  {
    MapReader l(r.required("lighting"), "lighting", origin);
    std::vector<std::string> names;
    for (const auto& [name, preset] : presetNames()) names.push_back(name);
    const std::string preset = l.choice(l.required("preset"), "preset", names);
    for (const auto& [name, p] : presetNames()) {
      if (name == preset) s.lighting.preset = p;
    }
    // The world takes 0..10 times a preset's light; scale × (1 + flicker) stays inside.
    s.lighting.scale = l.number("scale", 0, 6, 1.0);
    s.lighting.flicker_amplitude = l.number("flicker_amplitude", 0, 0.6, 0.0);
    s.lighting.flicker_frequency_hz = l.number("flicker_frequency_hz", 0, 500, 0.0);
    l.finish();
  }

  if (const YAML::Node effects = r.optional("effects")) {
    MapReader e(effects, "effects", origin);
    EffectsSpec& x = s.effects;
    x.gain = e.number("gain", 0, 64, x.gain);
    x.noise_sigma = e.number("noise_sigma", 0, 128, x.noise_sigma);
    x.shot_noise = e.number("shot_noise", 0, 16, x.shot_noise);
    x.exposure_s = e.number("exposure_ms", 0, 200, x.exposure_s * 1e3) / 1e3;
    x.blur_subframes = static_cast<int>(e.integer("blur_subframes", 1, 64, x.blur_subframes));
    x.rolling_shutter = e.boolean("rolling_shutter", x.rolling_shutter);
    x.readout_s = e.number("readout_ms", 0, 200, x.readout_s * 1e3) / 1e3;
    x.rolling_shutter_bands =
        static_cast<int>(e.integer("rolling_shutter_bands", 1, 240, x.rolling_shutter_bands));
    x.defocus_px = e.number("defocus_px", 0, 20, x.defocus_px);
    x.veiling_glare = e.number("veiling_glare", 0, 0.9, x.veiling_glare);
    e.finish();
    if (x.blur_subframes > 1 && x.exposure_s <= 0) {
      e.fail(effects.Mark(), "effects.blur_subframes", "motion blur needs exposure_ms > 0");
    }
  }

  if (const YAML::Node error = r.optional("camera_error")) {
    MapReader c(error, "camera_error", origin);
    CameraErrorSpec& x = s.camera_error;
    x.pitch_rad = c.number("pitch_deg", -20, 20, 0) * kDegToRad;
    x.roll_rad = c.number("roll_deg", -20, 20, 0) * kDegToRad;
    x.yaw_rad = c.number("yaw_deg", -20, 20, 0) * kDegToRad;
    x.height_m = c.number("height_m", -0.2, 0.2, 0);
    c.finish();
  }

  if (const YAML::Node scoring = r.optional("scoring")) {
    MapReader sc(scoring, "scoring", origin);
    s.orientation_tolerance_rad =
        sc.number("orientation_tolerance_deg", 0, 90, s.orientation_tolerance_rad / kDegToRad) *
        kDegToRad;
    sc.finish();
  }

  r.finish();
  return s;
}

struct PathStep {
  std::string key;
  int index = -1;  // >= 0: a list element after the key
};

// "robots[0].heading_deg" → {robots,0} {heading_deg}
std::vector<PathStep> parsePath(const std::string& path, const std::string& where) {
  std::vector<PathStep> steps;
  std::size_t i = 0;
  auto bad = [&]() { throw Error(where + ": malformed setting path '" + path + "'"); };
  while (i < path.size()) {
    PathStep step;
    while (i < path.size() && path[i] != '.' && path[i] != '[') step.key += path[i++];
    if (step.key.empty()) bad();
    if (i < path.size() && path[i] == '[') {
      const std::size_t close = path.find(']', i);
      if (close == std::string::npos || close == i + 1) bad();
      const std::string digits = path.substr(i + 1, close - i - 1);
      for (char c : digits) {
        if (c < '0' || c > '9') bad();
      }
      step.index = std::stoi(digits);
      i = close + 1;
    }
    steps.push_back(step);
    if (i < path.size()) {
      if (path[i] != '.') bad();
      ++i;
      if (i == path.size()) bad();
    }
  }
  if (steps.empty() || steps.back().index >= 0) bad();
  return steps;
}

// Sets the setting at `path` in `root` to `value` (a node of the same document, so that errors
// about it still name its line). Every step but the last must exist.
void applySetting(YAML::Node root, const std::string& path, const YAML::Node& value,
                  const std::string& where) {
  const std::vector<PathStep> steps = parsePath(path, where);
  YAML::Node node = root;
  for (std::size_t s = 0; s < steps.size(); ++s) {
    const PathStep& step = steps[s];
    const bool last = s + 1 == steps.size();
    if (!node.IsMap()) throw Error(where + ": '" + path + "' does not address a setting");
    if (last) {
      node[step.key] = value;
      return;
    }
    const YAML::Node next = static_cast<const YAML::Node&>(node)[step.key];
    if (!next && step.index >= 0) {
      throw Error(where + ": '" + path + "': the scenario has no '" + step.key + "'");
    }
    // A section the file leaves out (e.g. effects) is created for the swept key.
    if (!next) node[step.key] = YAML::Node(YAML::NodeType::Map);
    YAML::Node child;
    child.reset(node[step.key]);
    if (step.index >= 0) {
      if (!child.IsSequence() || step.index >= static_cast<int>(child.size())) {
        throw Error(where + ": '" + path + "': '" + step.key + "' has no element " +
                    std::to_string(step.index));
      }
      YAML::Node element;
      element.reset(child[step.index]);
      child.reset(element);
    }
    node.reset(child);
  }
}

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open scenario file");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw Error(path + ": cannot read scenario file");
  return text.str();
}

YAML::Node loadYaml(const std::string& text, const std::string& origin) {
  try {
    YAML::Node root = YAML::Load(text);
    if (!root.IsMap()) {
      throw Error(origin + ":" + lineOf(root.Mark()) +
                  ": expected a scenario (a mapping of key: value), got " + scalarText(root));
    }
    return root;
  } catch (const YAML::ParserException& e) {
    throw Error(origin + ":" + lineOf(e.mark) + ": malformed YAML: " + e.msg);
  }
}

}  // namespace

std::string motionKindName(MotionSpec::Kind kind) {
  switch (kind) {
    case MotionSpec::Kind::kStand:
      return "standing";
    case MotionSpec::Kind::kWalk:
      return "walking";
    case MotionSpec::Kind::kTurn:
      return "turning";
  }
  return "standing";
}

bool Expectation::holds(double value) const {
  if (!std::isfinite(value)) return false;
  switch (comparison) {
    case Comparison::kGreaterEqual:
      return value >= bound;
    case Comparison::kLessEqual:
      return value <= bound;
    case Comparison::kGreater:
      return value > bound;
    case Comparison::kLess:
      return value < bound;
    case Comparison::kEqual:
      return value == bound;
  }
  return false;
}

std::string comparisonSymbol(Expectation::Comparison comparison) {
  switch (comparison) {
    case Expectation::Comparison::kGreaterEqual:
      return ">=";
    case Expectation::Comparison::kLessEqual:
      return "<=";
    case Expectation::Comparison::kGreater:
      return ">";
    case Expectation::Comparison::kLess:
      return "<";
    case Expectation::Comparison::kEqual:
      return "==";
  }
  return "?";
}

Expectation parseExpectation(const std::string& text, const std::string& origin) {
  Expectation e;
  e.text = text;
  const std::string bad = origin + ": expectation '" + text + "' ";
  std::size_t i = 0;
  auto skipSpace = [&]() {
    while (i < text.size() && (text[i] == ' ' || text[i] == '\t')) ++i;
  };
  skipSpace();
  const std::size_t start = i;
  while (i < text.size() && (std::isalnum(static_cast<unsigned char>(text[i])) || text[i] == '_' ||
                             text[i] == '.' || text[i] == '[' || text[i] == ']')) {
    ++i;
  }
  e.metric = text.substr(start, i - start);
  if (e.metric.empty() || e.metric.front() == '.' || e.metric.back() == '.') {
    throw Error(bad + "does not start with a metric name (as in 'ball.detection_rate >= 0.97')");
  }
  skipSpace();
  static const std::vector<std::pair<std::string, Expectation::Comparison>> kOps = {
      {">=", Expectation::Comparison::kGreaterEqual},
      {"<=", Expectation::Comparison::kLessEqual},
      {"==", Expectation::Comparison::kEqual},
      {">", Expectation::Comparison::kGreater},
      {"<", Expectation::Comparison::kLess}};
  bool found = false;
  for (const auto& [op, cmp] : kOps) {
    if (text.compare(i, op.size(), op) == 0) {
      e.comparison = cmp;
      i += op.size();
      found = true;
      break;
    }
  }
  if (!found) throw Error(bad + "has no comparison (>=, <=, >, <, ==) after the metric");
  skipSpace();
  const std::string rest = text.substr(i);
  std::size_t used = 0;
  try {
    e.bound = std::stod(rest, &used);
  } catch (const std::exception&) {
    throw Error(bad + "has no number after the comparison");
  }
  std::size_t j = used;
  while (j < rest.size() && (rest[j] == ' ' || rest[j] == '\t')) ++j;
  if (j != rest.size())
    throw Error(bad + "has extra text '" + rest.substr(j) + "' after the bound");
  if (!std::isfinite(e.bound)) throw Error(bad + "has a bound that is not a finite number");
  return e;
}

std::string ScenarioCase::name() const {
  char buf[32];
  std::snprintf(buf, sizeof buf, "case_%03d", index);
  return buf;
}

Scenario Scenario::load(const std::string& path) { return parse(readFile(path), path); }

Scenario Scenario::parse(const std::string& text, const std::string& origin) {
  const FieldDimensions field = FieldDimensions::loadDefault();
  YAML::Node root = loadYaml(text, origin);
  Scenario scenario;
  scenario.path = origin;

  {
    MapReader r(root, "", origin);
    scenario.name = r.string("name");
    if (scenario.name.empty()) r.fail(root["name"].Mark(), "name", "is empty");

    if (const YAML::Node sweep = r.optional("sweep")) {
      if (!sweep.IsSequence()) r.fail(sweep.Mark(), "sweep", "expected a list of {path, values}");
      std::set<std::string> seen;
      for (std::size_t i = 0; i < sweep.size(); ++i) {
        const std::string key = "sweep[" + std::to_string(i) + "]";
        MapReader s(sweep[i], key, origin);
        SweepAxis axis;
        axis.line = sweep[i].Mark().line + 1;
        const YAML::Node path_node = s.required("path");
        axis.path = s.string(path_node, "path");
        const std::string where = origin + ":" + lineOf(path_node.Mark()) + ": " + key + ".path";
        parsePath(axis.path, where);
        if (!seen.insert(axis.path).second) {
          s.fail(path_node.Mark(), key + ".path", "'" + axis.path + "' is swept twice");
        }
        const YAML::Node values = s.required("values");
        if (!values.IsSequence() || values.size() == 0) {
          s.fail(values.Mark(), key + ".values", "expected a non-empty list of values");
        }
        for (std::size_t v = 0; v < values.size(); ++v) {
          if (!values[v].IsScalar()) {
            s.fail(values[v].Mark(), key + ".values[" + std::to_string(v) + "]",
                   "expected a single value, got " + scalarText(values[v]));
          }
          axis.values.push_back(values[v].Scalar());
        }
        s.finish();
        scenario.sweep.push_back(axis);
      }
    }

    if (const YAML::Node expect = r.optional("expect")) {
      if (!expect.IsSequence()) {
        r.fail(expect.Mark(), "expect",
               "expected a list of strings like 'ball.detection_rate >= 0.97'");
      }
      for (std::size_t i = 0; i < expect.size(); ++i) {
        const std::string key = "expect[" + std::to_string(i) + "]";
        const std::string where = origin + ":" + lineOf(expect[i].Mark()) + ": " + key;
        if (!expect[i].IsScalar())
          throw Error(where + ": expected a string, got " + scalarText(expect[i]));
        Expectation e = parseExpectation(expect[i].Scalar(), where);
        e.line = expect[i].Mark().line + 1;
        scenario.expect.push_back(e);
      }
    }
  }

  long long count = 1;
  for (const SweepAxis& axis : scenario.sweep) {
    count *= static_cast<long long>(axis.values.size());
    if (count > kMaxScenarioCases) {
      throw Error(origin + ":" + std::to_string(axis.line) + ": sweep: expands to more than " +
                  std::to_string(kMaxScenarioCases) + " cases");
    }
  }

  for (int k = 0; k < static_cast<int>(count); ++k) {
    // A fresh tree per case, so the values of one case never leak into the next.
    YAML::Node tree = loadYaml(text, origin);
    ScenarioCase c;
    c.index = k;
    int rest = k;
    std::vector<std::size_t> choice(scenario.sweep.size());
    for (int a = static_cast<int>(scenario.sweep.size()) - 1; a >= 0; --a) {
      const int n = static_cast<int>(scenario.sweep[a].values.size());
      choice[a] = static_cast<std::size_t>(rest % n);
      rest /= n;
    }
    std::string case_desc;
    for (std::size_t a = 0; a < scenario.sweep.size(); ++a) {
      const SweepAxis& axis = scenario.sweep[a];
      const YAML::Node value = tree["sweep"][a]["values"][choice[a]];
      applySetting(tree, axis.path, value,
                   origin + ":" + std::to_string(axis.line) + ": sweep[" + std::to_string(a) + "]");
      c.values.push_back({axis.path, axis.values[choice[a]]});
      case_desc += (case_desc.empty() ? "" : ", ") + axis.path + " = " + axis.values[choice[a]];
    }
    try {
      c.settings = parseCase(tree, origin, field);
    } catch (const Error& e) {
      if (scenario.sweep.empty()) throw;
      throw Error(std::string(e.what()) + " (in " + c.name() + ": " + case_desc + ")");
    }
    scenario.cases.push_back(std::move(c));
  }
  return scenario;
}

}  // namespace colorfree::sim
