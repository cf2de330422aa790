// Development probe (not in CTest): renders the frames of a scenario and prints, per frame, every
// true robot in view (ground pixel, distance, visible fraction, cut by a border, demanded or not),
// every robot proposal (match, RobotNet's confidence) and, for a demanded robot that no proposal
// matches, the feet points and rejected candidates near it with their reasons, so a miss can be
// traced to the proposer's step that lost it. With a PNG folder, each frame is drawn: true boxes
// (green: demanded, grey: not), proposals (blue), percepts (red), feet points (yellow), rejected
// candidates (magenta).
//   robot_probe SCENARIO [frames_per_case] [case] [png_dir] [misses_only]
// With RP_EXACT=1 it also prints every feet point, rejection, proposal and percept of the frame
// at full precision (to check that a speed-up changes nothing). With RP_SHIFT=1, per demanded
// robot, RobotNet's score on the proposer-shaped box about its true feet moved by -0.2 to 0.2 of
// its height (README robot21: RobotNet does not tell where the feet are), then moved sideways by
// -0.2 to 0.2 of its width (XSHIFT; README robot28).
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <string>

#include "colorfree/groundtruth/field_markings.h"
#include "colorfree/groundtruth/matching.h"
#include "colorfree/groundtruth/scoring_params.h"
#include "colorfree/groundtruth/truth_in_image.h"
#include "colorfree/perception/cnn/classifier.h"
#include "colorfree/perception/error.h"
#include "colorfree/perception/field_dimensions.h"
#include "colorfree/perception/pipeline.h"
#include "colorfree/sim/runner.h"
#include "colorfree/sim/scenario.h"
#include "colorfree/sim/world_renderer.h"

using namespace colorfree;

namespace {

cv::Point pt(const Eigen::Vector2d& p) { return {int(std::lround(p.x())), int(std::lround(p.y()))}; }
void box(cv::Mat& img, const PixelBox& b, cv::Scalar c, int t = 1) {
  cv::rectangle(img, cv::Point(int(b.x0), int(b.y0)), cv::Point(int(b.x1), int(b.y1)), c, t);
}

int probe(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr,
                 "usage: robot_probe SCENARIO [frames_per_case] [case] [png_dir] [misses_only]\n");
    return 2;
  }
  const int frames = argc > 2 ? std::atoi(argv[2]) : -1;
  const int only_case = argc > 3 ? std::atoi(argv[3]) : -1;
  const std::string png_dir = argc > 4 ? argv[4] : "";
  const bool misses_only = argc > 5 && std::atoi(argv[5]) != 0;
  if (!png_dir.empty()) std::filesystem::create_directories(png_dir);
  const FieldDimensions dims = FieldDimensions::loadDefault();
  const FieldMarkings markings = FieldMarkings::fromDimensions(dims);
  const ScoringParams scoring = ScoringParams::loadDefault();
  PipelineConfig config = PipelineConfig::loadDefault();
  // Quick parameter trials: RP_NAME=value overrides the file (RP_FREEZE, RP_FILL, RP_RUN, ...).
  const auto env = [](const char* k, auto& v) {
    if (const char* e = std::getenv(k)) v = static_cast<std::decay_t<decltype(v)>>(std::atof(e));
  };
  RobotProposerParams& rpp = config.robot_proposer;
  env("RP_DECAY", rpp.carpet_dark_decay);
  env("RP_BAND", rpp.lit_band_beside_width_factor);
  env("RP_BANDH", rpp.lit_band_height_fraction);
  env("RP_UPDATE", rpp.carpet_update_weight);
  env("RP_JUMP", rpp.min_jump_gray);
  env("RP_RATIO", rpp.jump_ratio);
  env("RP_GAP", rpp.max_gap_px);
  env("RP_GAPH", rpp.max_gap_height_fraction);
  env("RP_FEETDARK", rpp.feet_dark_height_fraction);
  env("RP_RUN", rpp.min_run_height_fraction);
  env("RP_FILL", rpp.min_fill_fraction);
  env("RP_MINW", rpp.min_width_fraction);
  env("RP_JOINH", rpp.join_height_fraction);
  env("RP_JOINGAP", rpp.join_gap_width_fraction);
  env("RP_IOU", rpp.max_overlap_iou);
  env("RP_OWN", rpp.own_body_height_fraction);
  env("RP_MAX", rpp.max_proposals);
  env("RP_HELD", rpp.max_held_back);
  env("RD_CONF", config.robot_detector.min_confidence);
  env("RD_HELD", config.robot_detector.min_held_back_confidence);
  env("RD_WIDE", config.robot_detector.min_wide_group_confidence);
  env("RD_SHIFT", config.robot_detector.wide_group_shift_width_fraction);
  env("RD_SHIFTMIN", config.robot_detector.wide_group_min_shift_confidence);
  env("RD_BEHIND", config.robot_detector.min_behind_robot_confidence);
  env("RD_TRACK", config.robot_detector.track_prior_odds);
  env("RD_TRACKHITS", config.robot_detector.track_prior_min_hits);
  env("RD_TRACKDIST", config.robot_detector.track_prior_distance_m);
  env("RD_VETO", config.robot_detector.behind_net_veto_confidence);
  env("RD_BEHINDPART", config.robot_detector.behind_lower_part_fraction);
  env("RD_MIRLO", config.robot_detector.mirror_min_confidence);
  env("RD_MIRHI", config.robot_detector.mirror_max_confidence);
  env("RD_AREA", config.robot_detector.area_min_patch_widths);
  env("RD_SHINFILL", config.robot_detector.shin_min_fill_fraction);
  env("RD_SHINGAP", config.robot_detector.shin_gap_height_fraction);
  env("RD_SHINMIN", config.robot_detector.shin_min_height_fraction);
  env("RD_SHINSPAN", config.robot_detector.shin_min_span_width_fraction);
  env("RD_FEETCONF", config.robot_detector.feet_min_confidence);
  env("RD_FEETSTEP", config.robot_detector.feet_step_height_fraction);
  env("RD_FEETN", config.robot_detector.feet_max_steps);
  env("RD_INSIDE", config.robot_detector.max_inside_fraction);
  env("RD_IOU", config.robot_detector.max_overlap_iou);
  env("RD_BALLR", config.robot_detector.ball_feet_radii);
  env("RD_BALLC", config.robot_detector.ball_feet_max_confidence);
  env("RP_BESIDE", rpp.beside_width_factor);
  env("RP_LINE", rpp.line_stripe_factor);
  env("RP_LINEB", rpp.line_beside_width_factor);
  env("RP_KNEE", rpp.knee_gap_height_fraction);
  env("RP_NOISE", rpp.noise_jump_factor);
  env("RP_SMOOTH", rpp.smooth_min_noise_gray);
  env("RP_SMOOTHW", rpp.smooth_width_px);
  env("RP_KNEELIT", rpp.knee_min_lit_height_fraction);
  env("RP_KNEEX", rpp.max_knee_proposals);
  env("RP_BOXW", rpp.box_width_factor);
  env("RP_SHORT", rpp.short_object_height_fraction);
  env("RP_SHORTMIN", rpp.short_object_min_height_fraction);
  env("HC_LIGHT", config.high_contrast.light_contrast_fraction);
  // RP_MODELS=DIR: the nets from DIR (a retrained RobotNet) instead of perception/models.
  if (const char* models = std::getenv("RP_MODELS")) config.model_dir = models;
  // RP_EXACT=1: also every feet point, rejection, proposal and percept at full precision.
  const bool exact_dump = std::getenv("RP_EXACT") != nullptr && std::atoi(std::getenv("RP_EXACT")) != 0;
  const Pipeline pipeline(config);
  // RP_SHIFT=1: RobotNet (loaded only then) on the true feet's box moved up and down.
  std::optional<cnn::Classifier> shift_net;
  if (std::getenv("RP_SHIFT") != nullptr) {
    const std::string dir = config.model_dir.empty() ? cnn::defaultModelDir() : config.model_dir;
    shift_net = cnn::Classifier::load(dir + "/robot_net.cfg", dir + "/robot_net.weights");
  }
  const RobotProposer proposer(config.robot_proposer, config.field);
  sim::ScenarioRunner runner(sim::Scenario::load(argv[1]), sim::worldRendererFactory());
  int truths = 0, prop_hits = 0, hits = 0, fps = 0, frames_seen = 0;
  long proposals = 0;
  for (int c = 0; c < runner.caseCount(); ++c) {
    if (only_case >= 0 && c != only_case) continue;
    RobotTracks tracks;
    runner.runCase(c, frames, true, [&](const sim::RenderedFrame& f) {
      const FrameTruth truth = computeFrameTruth(f.truth, markings, dims, scoring);
      Frame frame(f.image.view(), f.perception_camera);
      frame.time_s = f.truth.time_s;  // as colorfree run: the tracks expire by it
      pipeline.process(frame, nullptr, &tracks);
      // The perception's camera for the proposer; the true one for matching, as the scorer does.
      const CameraModel& cam = f.truth.camera.model;
      const RobotProposals rp = proposer.run(frame.image, f.perception_camera, *frame.ignore_mask,
                                             *frame.contrast_regions, true);
      ++frames_seen;
      const auto& props = *frame.robot_proposals;
      proposals += static_cast<long>(props.size());
      const auto& percepts = *frame.robot_percepts;
      const Eigen::Isometry3d r2f = robotToField(truth.observer);
      auto feetInField = [&](const Eigen::Vector2d& px) -> std::optional<Eigen::Vector2d> {
        const auto g = cam.pixelToGround(px);
        if (!g) return std::nullopt;
        return Eigen::Vector2d((r2f * Eigen::Vector3d(g->x(), g->y(), 0)).head<2>());
      };
      std::printf("case %d %s frame %d: %zu proposals, %zu percepts\n", c,
                  runner.scenarioCase(c).name().c_str(), f.frame_index, props.size(),
                  percepts.size());
      bool frame_miss = false;
      std::vector<PixelBox> missed_boxes;
      const double W = cam.width(), H = cam.height();
      for (const RobotInImage& r : truth.robots) {
        if (!r.in_view) continue;
        const bool cut = r.box.x0 <= 0.5 || r.box.y0 <= 0.5 || r.box.x1 >= W - 0.5 ||
                         r.box.y1 >= H - 0.5;
        std::string cuts;
        if (r.box.x0 <= 0.5) cuts += "L";
        if (r.box.x1 >= W - 0.5) cuts += "R";
        if (r.box.y0 <= 0.5) cuts += "T";
        if (r.box.y1 >= H - 0.5) cuts += "B";
        bool ph = false, dh = false;
        for (const auto& p : props) ph = ph || robotMatchCost(r, p.box, feetInField(p.feet_px), scoring);
        for (const auto& p : percepts) dh = dh || robotMatchCost(r, p.box, feetInField(p.feet_px), scoring);
        std::printf(
            "  R%d ground=(%.0f,%.0f) box=(%.0f,%.0f)-(%.0f,%.0f) d=%.2f vis=%.2f %s%s%s%s\n",
            r.index, r.ground_px.x(), r.ground_px.y(), r.box.x0, r.box.y0, r.box.x1, r.box.y1,
            r.distance_m, r.visible_fraction, cut ? "cut:" : "", cuts.c_str(),
            r.should_detect ? " DEMANDED" : "",
            r.should_detect ? (!ph   ? (dh ? " ok (no proposal: a box moved by RobotFeetNet)"
                                           : " >>> PROPOSAL MISS")
                               : !dh ? " >>> NET MISS"
                                     : " ok")
                            : "");
        if (!r.should_detect) continue;
        if (shift_net) {
          const auto& fc = f.perception_camera;
          const double shifts[] = {-0.2, -0.15, -0.1, -0.05, 0, 0.05, 0.1, 0.15, 0.2};
          // The proposer's box for feet at `g` of a robot `h` px tall.
          const auto proposerBox = [&](const Eigen::Vector2d& g, double h) {
            const double w =
                rpp.box_width_factor * h * config.field.robot_width_m / config.field.robot_height_m;
            const double y1 = g.y() + rpp.box_below_feet_fraction * h;
            const double y0 = y1 - rpp.box_height_factor * h;
            return cnn::PatchBox{float(g.x() - w / 2), float(y0), float(w), float(y1 - y0)};
          };
          const auto print = [&](const char* what, double size_px,
                                 const std::vector<cnn::PatchBox>& pbs) {
            std::vector<float> pr;
            shift_net->classify(frame.image, pbs, pr);
            std::printf("     %s=%.0f", what, size_px);
            for (std::size_t k = 0; k < pbs.size(); ++k) std::printf(" %.2f", pr[2 * k + 1]);
            std::printf("\n");
          };
          const auto h0 = fc.robotHeightPx(r.ground_px, config.field.robot_height_m);
          if (h0) {
            std::vector<cnn::PatchBox> pbs;
            for (double s : shifts) {
              const Eigen::Vector2d g(r.ground_px.x(), r.ground_px.y() + s * *h0);
              const auto h = fc.robotHeightPx(g, config.field.robot_height_m);
              pbs.push_back(h ? proposerBox(g, *h) : cnn::PatchBox{0, 0, 1, 1});
            }
            print("SHIFT h", *h0, pbs);
            const cnn::PatchBox centre = proposerBox(r.ground_px, *h0);
            pbs.clear();
            for (double s : shifts) {
              cnn::PatchBox moved = centre;
              moved.x_px += static_cast<float>(s * centre.width_px);
              pbs.push_back(moved);
            }
            print("XSHIFT w", centre.width_px, pbs);
          }
        }
        ++truths;
        prop_hits += ph;
        hits += dh;
        if (!dh) frame_miss = true;
        if (ph) continue;
        missed_boxes.push_back(r.box);
        for (const auto& fp : rp.feet_points_px) {
          if (fp.x() >= r.box.x0 && fp.x() <= r.box.x1 && fp.y() >= r.box.y0 &&
              fp.y() <= r.box.y1 + 10) {
            std::printf("     feet point (%.0f,%.0f)\n", fp.x(), fp.y());
          }
        }
        for (const auto& rj : rp.rejected) {
          if (rj.feet_px.x() >= r.box.x0 && rj.feet_px.x() <= r.box.x1 &&
              rj.feet_px.y() >= r.box.y0 && rj.feet_px.y() <= r.box.y1 + 10) {
            std::printf("     rejected (%.0f,%.0f) %s\n", rj.feet_px.x(), rj.feet_px.y(),
                        robotRejectReasonName(rj.reason));
          }
        }
      }
      for (std::size_t i = 0; i < props.size(); ++i) {
        const auto& p = props[i];
        bool m = false;
        for (const RobotInImage& r : truth.robots) m = m || robotMatchCost(r, p.box, feetInField(p.feet_px), scoring);
        const int fx = std::clamp(static_cast<int>(p.feet_px.x()), 0, frame.ignore_mask->width - 1);
        std::printf(
            "   prop %zu feet=(%.0f,%.0f) box=(%.0f,%.0f)-(%.0f,%.0f) boundary=%d net=%.3f%s%s%s\n",
            i, p.feet_px.x(), p.feet_px.y(), p.box.x0, p.box.y0, p.box.x1, p.box.y1,
            frame.ignore_mask->top_y[fx],
            frame.robot_net_confidences ? (*frame.robot_net_confidences)[i] : -1.f,
            m ? " MATCH" : "", i >= rp.proposals.size() ? " HELD BACK, FREED" : "",
            p.wide_group ? " WIDE" : "");
        if (i >= rp.proposals.size() && frame.robot_net_confidences) {
          for (const HeldBackRobotProposal& h : rp.held_back) {
            if (h.proposal.feet_px != p.feet_px) continue;
            for (int k : h.nearer)
              std::printf("     behind prop %d net=%.3f\n", k, (*frame.robot_net_confidences)[k]);
            break;
          }
        }
      }
      if (exact_dump) {
        // Every output of the two stages at full precision (speed work must keep them exactly).
        for (const auto& fp : rp.feet_points_px) std::printf("   exact feet %.17g %.17g\n", fp.x(), fp.y());
        for (const auto& rj : rp.rejected) {
          std::printf("   exact rejected %.17g %.17g %s\n", rj.feet_px.x(), rj.feet_px.y(),
                      robotRejectReasonName(rj.reason));
        }
        for (std::size_t i = 0; i < rp.proposals.size(); ++i) {
          const auto& p = rp.proposals[i];
          std::printf("   exact prop %.17g %.17g box %.17g %.17g %.17g %.17g net %.9g\n", p.feet_px.x(),
                      p.feet_px.y(), p.box.x0, p.box.y0, p.box.x1, p.box.y1,
                      frame.robot_net_confidences && i < frame.robot_net_confidences->size()
                          ? (*frame.robot_net_confidences)[i]
                          : -1.f);
        }
        for (const auto& p : percepts) {
          const Eigen::Vector2d g = p.position_in_robot.value_or(Eigen::Vector2d(-1e9, -1e9));
          std::printf("   exact percept %.17g %.17g box %.17g %.17g %.17g %.17g conf %.9g ground %.17g %.17g\n",
                      p.feet_px.x(), p.feet_px.y(), p.box.x0, p.box.y0, p.box.x1, p.box.y1,
                      p.confidence, g.x(), g.y());
        }
      }
      for (const auto& p : percepts) {
        bool m = false;
        double vis = -1;
        for (const RobotInImage& r : truth.robots) {
          if (robotMatchCost(r, p.box, feetInField(p.feet_px), scoring)) m = true, vis = r.visible_fraction;
        }
        // A percept at least half inside a nearer one (lower feet), a robot behind it or its part (hand,
        // arm): true or false, the true robot's visible fraction, and its box and feet point in units of
        // the nearer box (height, feet above its feet, feet across from its left, top below its top, width).
        for (const auto& q : percepts) {
          if (&q == &p || q.feet_px.y() <= p.feet_px.y()) continue;
          const double in = boxInsideFraction(p.box, q.box);
          if (in < 0.5) continue;
          const double qh = q.box.height(), qw = q.box.width();
          std::printf("   NESTED %s vis=%.2f in=%.2f conf=%.3f h_rel=%.2f feet_up=%.2f feet_x=%.2f top_rel=%.2f "
                      "w_rel=%.2f\n",
                      m ? "TP" : "FP", vis, in, p.confidence, p.box.height() / qh,
                      (q.feet_px.y() - p.feet_px.y()) / qh, (p.feet_px.x() - q.box.x0) / qw,
                      (p.box.y0 - q.box.y0) / qh, p.box.width() / qw);
        }
        if (!m) {
          ++fps;
          frame_miss = true;
          // What it covers: the true robot (demanded or not) and the other percept it overlaps most
          // (intersection over this box's area).
          int on_robot = -1, on_percept = -1;
          double best_r = 0, best_p = 0;
          for (const RobotInImage& r : truth.robots) {
            if (r.in_view && boxInsideFraction(p.box, r.box) > best_r) best_r = boxInsideFraction(p.box, r.box), on_robot = r.index;
          }
          for (std::size_t j = 0; j < percepts.size(); ++j) {
            if (&percepts[j] != &p && boxInsideFraction(p.box, percepts[j].box) > best_p) {
              best_p = boxInsideFraction(p.box, percepts[j].box), on_percept = static_cast<int>(j);
            }
          }
          std::printf("   FALSE POSITIVE feet=(%.0f,%.0f) box=(%.0f,%.0f)-(%.0f,%.0f) conf=%.3f on R%d %.2f, "
                      "percept %d %.2f\n",
                      p.feet_px.x(), p.feet_px.y(), p.box.x0, p.box.y0, p.box.x1, p.box.y1, p.confidence,
                      on_robot, best_r, on_percept, best_p);
        }
      }
      if (!png_dir.empty() && (!misses_only || frame_miss)) {
        cv::Mat gray(f.image.height(), f.image.width(), CV_8UC1,
                     const_cast<std::uint8_t*>(f.image.data()));
        cv::Mat img;
        cv::cvtColor(gray, img, cv::COLOR_GRAY2BGR);
        const ContrastRegions& cr = *frame.contrast_regions;
        for (int wr = 0; wr < cr.rows; ++wr) {
          for (int wc = 0; wc < cr.columns; ++wc) {
            if (!cr.marked(wc, wr)) continue;
            const int w = cr.window_px;
            cv::rectangle(img, {wc * w, wr * w}, {wc * w + w - 1, wr * w + w - 1}, {96, 96, 0}, 1);
          }
        }
        for (const RobotInImage& r : truth.robots) {
          if (r.in_view) box(img, r.box, r.should_detect ? cv::Scalar(0, 255, 0) : cv::Scalar(128, 128, 128));
        }
        for (const auto& p : props) box(img, p.box, {255, 0, 0});
        for (const auto& p : percepts) box(img, p.box, {0, 0, 255}, 2);
        for (const auto& fp : rp.feet_points_px) cv::circle(img, pt(fp), 2, {0, 255, 255}, -1);
        for (const auto& rj : rp.rejected) cv::drawMarker(img, pt(rj.feet_px), {255, 0, 255}, cv::MARKER_CROSS, 5, 1);
        char name[256];
        std::snprintf(name, sizeof name, "%s/c%02d_f%03d.png", png_dir.c_str(), c, f.frame_index);
        if (!cv::imwrite(name, img)) throw Error(std::string(name) + ": cannot write");
        // Each robot no proposal matched, cropped with a margin and enlarged 4 times.
        for (std::size_t k = 0; k < missed_boxes.size(); ++k) {
          const PixelBox& b = missed_boxes[k];
          const int mx = int(b.width() * 0.5) + 4, my = int(b.height() * 0.2) + 4;
          const cv::Rect roi(cv::Point(std::max(0, int(b.x0) - mx), std::max(0, int(b.y0) - my)),
                             cv::Point(std::min(img.cols, int(b.x1) + mx), std::min(img.rows, int(b.y1) + my)));
          cv::Mat big;
          cv::resize(cv::Mat(gray, roi), big, {}, 4, 4, cv::INTER_NEAREST);
          cv::Mat big_c, ann;
          cv::resize(cv::Mat(img, roi), ann, {}, 4, 4, cv::INTER_NEAREST);
          cv::cvtColor(big, big_c, cv::COLOR_GRAY2BGR);
          cv::Mat both;
          cv::hconcat(big_c, ann, both);
          std::snprintf(name, sizeof name, "%s/c%02d_f%03d_miss%zu.png", png_dir.c_str(), c, f.frame_index, k);
          if (!cv::imwrite(name, both)) throw Error(std::string(name) + ": cannot write");
        }
      }
    });
  }
  std::printf("frames %d truths %d proposal hits %d (%.3f) detected %d (%.3f) false positives %d "
              "(%.3f/frame) proposals/frame %.2f\n",
              frames_seen, truths, prop_hits, truths ? double(prop_hits) / truths : 0, hits,
              truths ? double(hits) / truths : 0, fps, frames_seen ? double(fps) / frames_seen : 0,
              frames_seen ? double(proposals) / frames_seen : 0);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return probe(argc, argv);
  } catch (const std::exception& e) {  // a broken scenario, an unwritable folder
    std::fprintf(stderr, "robot_probe: %s\n", e.what());
    return 2;
  }
}
