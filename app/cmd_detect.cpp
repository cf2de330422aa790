#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "colorfree/perception/camera_model.h"
#include "colorfree/perception/error.h"
#include "colorfree/perception/image.h"
#include "colorfree/perception/cnn/net.h"
#include "colorfree/perception/pipeline.h"
#include "colorfree/perception/robot_orientation.h"
#include "commands.h"

namespace colorfree::app {

namespace {

const char* typeName(IntersectionType t) {
  switch (t) {
    case IntersectionType::kL: return "L";
    case IntersectionType::kT: return "T";
    case IntersectionType::kX: return "X";
  }
  return "?";
}

nlohmann::json vec(const Eigen::Vector2d& v) { return {v.x(), v.y()}; }

nlohmann::json toJson(const Frame& frame, const PipelineStats& stats) {
  nlohmann::json j;
  j["width"] = frame.image.width;
  j["height"] = frame.image.height;
  const auto& regions = *frame.contrast_regions;
  j["high_contrast"]["windows_marked"] = regions.markedCount();
  j["high_contrast"]["window_px"] = regions.window_px;
  j["high_contrast"]["regions"] = nlohmann::json::array();
  for (const auto& r : regions.regions) {
    j["high_contrast"]["regions"].push_back(
        {{"box_px", {r.box.x0, r.box.y0, r.box.x1, r.box.y1}}, {"windows", r.window_count}});
  }
  const FieldLineResult& fl = *frame.field_lines;
  j["spots"] = fl.spots.size();
  j["lines"] = nlohmann::json::array();
  for (const auto& l : fl.features.lines) {
    j["lines"].push_back({{"start_px", vec(l.start_px)}, {"end_px", vec(l.end_px)},
                          {"start_in_robot_m", vec(l.start_in_robot)},
                          {"end_in_robot_m", vec(l.end_in_robot)}});
  }
  j["intersections"] = nlohmann::json::array();
  for (const auto& x : fl.features.intersections) {
    j["intersections"].push_back({{"type", typeName(x.type)}, {"position_px", vec(x.position_px)},
                                  {"position_in_robot_m", vec(x.position_in_robot)},
                                  {"direction1_in_robot", vec(x.direction1_in_robot)},
                                  {"direction2_in_robot", vec(x.direction2_in_robot)}});
  }
  j["centre_circle"] = nullptr;
  if (fl.features.centre_circle) {
    j["centre_circle"] = {{"centre_px", vec(fl.features.centre_circle->centre_px)},
                          {"centre_in_robot_m", vec(fl.features.centre_circle->centre_in_robot)}};
  }
  j["penalty_marks"] = nlohmann::json::array();
  for (const auto& m : fl.features.penalty_marks) {
    j["penalty_marks"].push_back(
        {{"centre_px", vec(m.centre_px)}, {"centre_in_robot_m", vec(m.centre_in_robot)}});
  }
  // Ball (issue 6): proposals and detections.
  if (frame.ball_proposals) {
    j["ball_proposals"] = nlohmann::json::array();
    for (const auto& p : *frame.ball_proposals) {
      j["ball_proposals"].push_back({{"centre_px", vec(p.centre_px)}, {"radius_px", p.radius_px}, {"response", p.response}});
    }
    j["balls"] = nlohmann::json::array();
    for (const auto& b : *frame.ball_percepts) {
      j["balls"].push_back({{"centre_px", vec(b.centre_px)}, {"radius_px", b.radius_px}, {"confidence", b.confidence},
                            {"position_in_robot_m", b.position_in_robot ? vec(*b.position_in_robot) : nlohmann::json(nullptr)}});
    }
  }
  for (int i = 0; i < kStageCount; ++i) {
    const auto& t = stats.timing(static_cast<Stage>(i));
    j["timing_ms"][stageName(static_cast<Stage>(i))] =
        t ? nlohmann::json{{"mean", t->meanMs()}, {"max", t->max_ms}} : nlohmann::json("absent");
  }
  return j;
}

void printText(const std::string& path, const Frame& frame, const PipelineStats& stats) {
  const FieldLineResult& fl = *frame.field_lines;
  std::printf("%s: %dx%d\n", path.c_str(), frame.image.width, frame.image.height);
  std::printf("high contrast: %d windows marked, %zu regions\n",
              frame.contrast_regions->markedCount(), frame.contrast_regions->regions.size());
  std::printf("line spots: %zu\n", fl.spots.size());
  std::printf("lines: %zu\n", fl.features.lines.size());
  for (const auto& l : fl.features.lines) {
    std::printf("  image (%.1f, %.1f)-(%.1f, %.1f) px  robot (%.3f, %.3f)-(%.3f, %.3f) m\n",
                l.start_px.x(), l.start_px.y(), l.end_px.x(), l.end_px.y(), l.start_in_robot.x(),
                l.start_in_robot.y(), l.end_in_robot.x(), l.end_in_robot.y());
  }
  if (!fl.rejected.empty()) std::printf("rejected line candidates: %zu\n", fl.rejected.size());
  for (const auto& r : fl.rejected) {
    std::printf("  %s: image (%.1f, %.1f)-(%.1f, %.1f) px  robot (%.3f, %.3f)-(%.3f, %.3f) m\n",
                lineRejectReasonName(r.reason), r.line.start_px.x(), r.line.start_px.y(), r.line.end_px.x(),
                r.line.end_px.y(), r.line.start_in_robot.x(), r.line.start_in_robot.y(),
                r.line.end_in_robot.x(), r.line.end_in_robot.y());
  }
  std::printf("intersections: %zu\n", fl.features.intersections.size());
  for (const auto& x : fl.features.intersections) {
    std::printf("  %s image (%.1f, %.1f) px  robot (%.3f, %.3f) m\n", typeName(x.type),
                x.position_px.x(), x.position_px.y(), x.position_in_robot.x(), x.position_in_robot.y());
  }
  if (fl.features.centre_circle) {
    const auto& c = *fl.features.centre_circle;
    std::printf("centre circle: image (%.1f, %.1f) px  robot (%.3f, %.3f) m\n", c.centre_px.x(),
                c.centre_px.y(), c.centre_in_robot.x(), c.centre_in_robot.y());
  } else {
    std::printf("centre circle: none\n");
  }
  std::printf("penalty marks: %zu\n", fl.features.penalty_marks.size());
  for (const auto& m : fl.features.penalty_marks) {
    std::printf("  image (%.1f, %.1f) px  robot (%.3f, %.3f) m\n", m.centre_px.x(), m.centre_px.y(),
                m.centre_in_robot.x(), m.centre_in_robot.y());
  }
  if (frame.ball_proposals) {
    std::printf("ball proposals: %zu\n", frame.ball_proposals->size());
    std::printf("balls: %zu\n", frame.ball_percepts->size());
    for (const auto& b : *frame.ball_percepts) {
      std::printf("  image (%.1f, %.1f) px  radius %.1f px  confidence %.3f", b.centre_px.x(), b.centre_px.y(),
                  b.radius_px, b.confidence);
      if (b.position_in_robot) std::printf("  robot (%.3f, %.3f) m", b.position_in_robot->x(), b.position_in_robot->y());
      std::printf("\n");
    }
  }
  std::printf("%s", stats.table().c_str());
}

RobotOrientationEstimator orientationEstimator(const PipelineConfig& config) {
  const std::string dir = config.model_dir.empty() ? cnn::defaultModelDir() : config.model_dir;
  auto net = [&](const char* stem) {
    return cnn::Classifier::load(dir + "/" + stem + ".cfg", dir + "/" + stem + ".weights");
  };
  return RobotOrientationEstimator(config.robot_orientation, config.field, net("ori_boost_net"),
                                   net("ori_net"));
}

// The orientation stage's inside for one robot: its silhouette points and each line's region with
// the nets' answers (what `--out` draws).
nlohmann::json orientationLinesJson(const RobotLines& lines) {
  nlohmann::json o;
  o["silhouette_points"] = lines.silhouette_px.size();
  o["silhouette_px"] = nlohmann::json::array();
  o["silhouette_in_robot_m"] = nlohmann::json::array();
  for (std::size_t k = 0; k < lines.silhouette_px.size(); ++k) {
    o["silhouette_px"].push_back(vec(lines.silhouette_px[k]));
    o["silhouette_in_robot_m"].push_back(vec(lines.silhouette_in_robot[k]));
  }
  o["regions"] = nlohmann::json::array();
  for (const auto& region : lines.regions) {
    const Eigen::Vector2d d = region.line_in_robot.direction();
    nlohmann::json r = {{"line_a_m", vec(region.line_in_robot.a)},
                        {"line_b_m", vec(region.line_in_robot.b)},
                        {"line_deg", std::atan2(d.y(), d.x()) * 180 / 3.14159265358979},
                        {"votes", region.line_in_robot.votes},
                        {"box_px", {region.box.x0, region.box.y0, region.box.x1, region.box.y1}},
                        {"usable", region.usable},
                        {"side_confidence", region.side_confidence}};
    if (region.side) {
      const char* names[] = {"front", "back", "side"};
      r["side"] = names[static_cast<int>(*region.side)];
      if (region.side_facing_known) r["side_facing"] = region.faces_left ? "left" : "right";
    }
    o["regions"].push_back(r);
  }
  return o;
}

nlohmann::json robotsJson(const Frame& frame, const PipelineConfig& config) {
  nlohmann::json j = nlohmann::json::array();
  const RobotOrientationEstimator ori = orientationEstimator(config);
  for (const auto& r : *frame.robot_percepts) {
    nlohmann::json o = {{"box_px", {r.box.x0, r.box.y0, r.box.x1, r.box.y1}},
                        {"feet_px", vec(r.feet_px)},
                        {"confidence", r.confidence}};
    if (r.position_in_robot) o["position_in_robot_m"] = vec(*r.position_in_robot);
    if (r.orientation_raw) {
      o["orientation_deg"] = r.orientation_raw->angle_rad * 180 / 3.14159265358979;
      o["facing_known"] = r.orientation_raw->facing_known;
    }
    o["orientation_lines"] =
        orientationLinesJson(ori.estimate(frame.image, frame.camera, r, frame.fieldFeatures()));
    j.push_back(o);
  }
  return j;
}

// Every robot proposal with RobotNet's confidence (the detector's input: why a robot was missed).
nlohmann::json robotProposalsJson(const Frame& frame) {
  nlohmann::json j = nlohmann::json::array();
  if (!frame.robot_proposals) return j;
  for (std::size_t i = 0; i < frame.robot_proposals->size(); ++i) {
    const auto& p = (*frame.robot_proposals)[i];
    nlohmann::json o = {{"box_px", {p.box.x0, p.box.y0, p.box.x1, p.box.y1}}, {"feet_px", vec(p.feet_px)}};
    if (frame.robot_net_confidences && i < frame.robot_net_confidences->size()) {
      o["robot_net_confidence"] = (*frame.robot_net_confidences)[i];
    }
    j.push_back(o);
  }
  return j;
}

void printRobots(const Frame& frame) {
  std::printf("robot proposals: %zu, robots: %zu\n", frame.robot_proposals->size(), frame.robot_percepts->size());
  for (const auto& r : *frame.robot_percepts) {
    std::printf("  box (%.0f, %.0f)-(%.0f, %.0f) px  feet (%.1f, %.1f) px  confidence %.2f", r.box.x0, r.box.y0,
                r.box.x1, r.box.y1, r.feet_px.x(), r.feet_px.y(), r.confidence);
    if (r.position_in_robot) std::printf("  robot (%.2f, %.2f) m", r.position_in_robot->x(), r.position_in_robot->y());
    if (r.orientation_raw) {
      std::printf("  orientation %.0f deg%s", r.orientation_raw->angle_rad * 180 / 3.14159265358979,
                  r.orientation_raw->facing_known ? "" : " (axis only)");
    }
    std::printf("\n");
  }
}

cv::Point pt(const Eigen::Vector2d& v) {
  return {static_cast<int>(std::lround(v.x() - 0.5)), static_cast<int>(std::lround(v.y() - 0.5))};
}

void drawAnnotated(const std::string& path, const Frame& frame, const PipelineConfig& config) {
  cv::Mat gray(frame.image.height, frame.image.width, CV_8UC1,
               const_cast<std::uint8_t*>(frame.image.data), static_cast<std::size_t>(frame.image.stride));
  cv::Mat img;
  cv::cvtColor(gray, img, cv::COLOR_GRAY2BGR);
  const IgnoreMask& ignore = *frame.ignore_mask;
  // Ignored pixels darkened and tinted.
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) {
      if (ignore.looked(x, y)) continue;
      auto& p = img.at<cv::Vec3b>(y, x);
      p = cv::Vec3b(static_cast<uchar>(p[0] / 2 + 60), static_cast<uchar>(p[1] / 2), static_cast<uchar>(p[2] / 2));
    }
  }
  for (int x = 1; x < img.cols; ++x) {
    cv::line(img, {x - 1, frame.field_boundary->boundary_y[x - 1]}, {x, frame.field_boundary->boundary_y[x]},
             {0, 255, 255}, 1);
  }
  const auto& regions = *frame.contrast_regions;
  const int s = regions.window_px;
  for (int r = 0; r < regions.rows; ++r) {
    for (int c = 0; c < regions.columns; ++c) {
      if (!regions.marked(c, r)) continue;
      const bool seed = regions.seeds[static_cast<std::size_t>(r) * regions.columns + c];
      cv::rectangle(img, {c * s, r * s}, {(c + 1) * s - 1, (r + 1) * s - 1},
                    seed ? cv::Scalar(255, 255, 0) : cv::Scalar(120, 120, 0), 1);
    }
  }
  const FieldLineResult& fl = *frame.field_lines;
  for (const auto& sp : fl.spots) {
    cv::circle(img, pt(sp.position_px), 1, sp.vertical_scan ? cv::Scalar(0, 0, 255) : cv::Scalar(255, 0, 0), -1);
  }
  for (const auto& r : fl.rejected) cv::line(img, pt(r.line.start_px), pt(r.line.end_px), {0, 0, 160}, 1);
  for (const auto& l : fl.features.lines) cv::line(img, pt(l.start_px), pt(l.end_px), {0, 220, 0}, 2);
  for (const auto& x : fl.features.intersections) {
    cv::circle(img, pt(x.position_px), 6, {0, 140, 255}, 2);
    cv::putText(img, typeName(x.type), pt(x.position_px) + cv::Point(8, -8), cv::FONT_HERSHEY_SIMPLEX,
                0.6, {0, 140, 255}, 2);
  }
  if (fl.features.centre_circle) {
    cv::drawMarker(img, pt(fl.features.centre_circle->centre_px), {255, 0, 255}, cv::MARKER_CROSS, 16, 2);
  }
  for (const auto& m : fl.features.penalty_marks) {
    cv::drawMarker(img, pt(m.centre_px), {255, 0, 255}, cv::MARKER_TILTED_CROSS, 14, 2);
  }
  if (frame.ball_proposals) {
    for (const auto& p : *frame.ball_proposals) {
      cv::circle(img, pt(p.centre_px), static_cast<int>(std::lround(p.radius_px)), {0, 120, 255}, 1);
    }
    for (const auto& b : *frame.ball_percepts) {
      cv::circle(img, pt(b.centre_px), static_cast<int>(std::lround(b.radius_px)) + 2, {0, 0, 255}, 2);
    }
  }
  if (frame.robot_proposals) {
    for (const auto& p : *frame.robot_proposals) {
      cv::rectangle(img, pt({p.box.x0, p.box.y0}), pt({p.box.x1, p.box.y1}), {255, 120, 0}, 1);
    }
  }
  if (frame.robot_percepts && !frame.robot_percepts->empty()) {
    // The orientation stage's inside: silhouette points (green), its lines (magenta) and their
    // regions (yellow: usable, with OriNet's class F/B/S, SL/SR when it saw the side's facing
    // left or right; grey: rejected).
    const RobotOrientationEstimator ori = orientationEstimator(config);
    for (const auto& r : *frame.robot_percepts) {
      const RobotLines lines = ori.estimate(frame.image, frame.camera, r, frame.fieldFeatures());
      for (const auto& q : lines.silhouette_px) cv::circle(img, pt(q), 0, {0, 255, 0}, -1);
      for (const auto& region : lines.regions) {
        const auto a = frame.camera.robotToPixel({region.line_in_robot.a.x(), region.line_in_robot.a.y(), 0});
        const auto b = frame.camera.robotToPixel({region.line_in_robot.b.x(), region.line_in_robot.b.y(), 0});
        if (a && b) cv::line(img, pt(*a), pt(*b), {255, 0, 255}, 1);
        const cv::Scalar colour = region.side ? cv::Scalar(0, 255, 255) : cv::Scalar(150, 150, 150);
        cv::rectangle(img, pt({region.box.x0, region.box.y0}), pt({region.box.x1, region.box.y1}), colour, 1);
        if (region.side) {
          const char* names[] = {"F", "B", "S"};
          std::string name = names[static_cast<int>(*region.side)];
          if (region.side_facing_known) name += region.faces_left ? "L" : "R";
          cv::putText(img, name, pt({region.box.x0, region.box.y1 + 12}),
                      cv::FONT_HERSHEY_SIMPLEX, 0.4, colour, 1);
        }
      }
    }
  }
  if (frame.robot_percepts) {
    for (const auto& r : *frame.robot_percepts) {
      cv::rectangle(img, pt({r.box.x0, r.box.y0}), pt({r.box.x1, r.box.y1}), {0, 0, 255}, 2);
      cv::drawMarker(img, pt(r.feet_px), {0, 0, 255}, cv::MARKER_DIAMOND, 8, 2);
      if (r.orientation_raw) {
        const double a = r.orientation_raw->angle_rad;
        cv::putText(img, std::to_string(static_cast<int>(std::lround(a * 180 / 3.14159265358979))) +
                             (r.orientation_raw->facing_known ? "" : " axis"),
                    pt({r.box.x0, r.box.y0 - 4}), cv::FONT_HERSHEY_SIMPLEX, 0.5, {0, 0, 255}, 1);
      }
    }
  }
  // Written to a temporary name first, so that a half-written file never looks complete.
  const std::string tmp = path + ".tmp.png";
  bool ok = false;
  try {
    ok = cv::imwrite(tmp, img);
  } catch (const cv::Exception&) {
    ok = false;
  }
  if (!ok) throw Error(path + ": cannot write annotated image");
  std::filesystem::rename(tmp, path);
}

}  // namespace

void addDetectCommand(CLI::App& app, int& exit_code) {
  auto* cmd = app.add_subcommand(
      "detect", "Run the colour-free perception on one camera frame (PNG or raw YUV422) and show what it found");
  struct Options {
    std::string image, camera, yuyv, out, params;
    bool json = false;
    bool no_body = false;
    bool rejected = false;
    int repeat = 1;
  };
  auto opt = std::make_shared<Options>();
  cmd->add_option("IMAGE", opt->image, "PNG (any 8-bit image; colour is converted to luma) or raw YUYV frame")
      ->required();
  cmd->add_option("--camera", opt->camera, "camera file (docs/camera_file.md)")->required();
  cmd->add_option("--yuyv", opt->yuyv, "IMAGE is a raw YUV422 (YUYV) frame of this size, e.g. 640x480");
  cmd->add_option("--out", opt->out, "write the image annotated with what was found (PNG)");
  cmd->add_option("--params", opt->params, "directory of parameter files (default: the shipped ones)");
  cmd->add_flag("--json", opt->json, "print the result as JSON");
  cmd->add_flag("--rejected", opt->rejected, "also list rejected line candidates with the reason");
  cmd->add_flag("--no-body", opt->no_body, "do not mask the observer's body (e.g. a top camera frame)");
  cmd->add_option("--repeat", opt->repeat,
                  "run the perception this many times on the frame: the timing table's mean and max are over the "
                  "runs (the first pays for cold caches)")
      ->check(CLI::Range(1, 100000));
  cmd->callback([opt, &exit_code] {
    GrayImage image;
    if (!opt->yuyv.empty()) {
      int w = 0, h = 0;
      char x = 0;
      if (std::sscanf(opt->yuyv.c_str(), "%d%c%d", &w, &x, &h) != 3 || x != 'x') {
        throw Error("--yuyv: expected WIDTHxHEIGHT, got '" + opt->yuyv + "'");
      }
      image = readYuyvFile(opt->image, w, h);
    } else {
      image = readGrayImage(opt->image);
    }
    const CameraModel camera = CameraModel::load(opt->camera);
    if (image.width() != camera.width() || image.height() != camera.height()) {
      throw Error(opt->image + ": image is " + std::to_string(image.width()) + "x" +
                  std::to_string(image.height()) + " but " + opt->camera + " describes " +
                  std::to_string(camera.width()) + "x" + std::to_string(camera.height()));
    }
    PipelineConfig config = opt->params.empty() ? PipelineConfig::loadDefault() : PipelineConfig::load(opt->params);
    config.use_body_contour = !opt->no_body;
    config.keep_rejected = opt->rejected;
    const Pipeline pipeline(config);
    PipelineStats stats;
    // Every run starts from a fresh frame (the stages' results are the same each time: no stage keeps
    // state); the last one is printed.
    for (int i = 1; i < opt->repeat; ++i) {
      Frame scratch(image.view(), camera);
      pipeline.process(scratch, &stats);
    }
    Frame frame(image.view(), camera);
    pipeline.process(frame, &stats);
    if (opt->json) {
      nlohmann::json j = toJson(frame, stats);
      j["robots"] = robotsJson(frame, config);
      j["robot_proposals"] = robotProposalsJson(frame);
      std::printf("%s\n", j.dump(2).c_str());
    } else {
      printText(opt->image, frame, stats);
      printRobots(frame);
    }
    if (!opt->out.empty()) drawAnnotated(opt->out, frame, config);
    exit_code = 0;
  });
}

}  // namespace colorfree::app
