// Development probe (not in CTest): renders the frames of a scenario and prints, per frame, the
// true ball, every ball proposal (distance to the truth, match, both nets' scores) and the
// percepts, so a miss can be traced to the proposer or to the nets.
//   ball_probe SCENARIO [frames_per_case] [case] [png_dir]
// BP_MODELS=DIR takes the nets from DIR (BP_SMEAR=0.5 routes smeared patches to its
// smeared_ball_net too); BP_TEXTURE=... and the others below override parameters.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <numbers>
#include <string>

#include "colorfree/groundtruth/field_markings.h"
#include "colorfree/groundtruth/matching.h"
#include "colorfree/groundtruth/scoring_params.h"
#include "colorfree/groundtruth/truth_in_image.h"
#include "colorfree/perception/field_dimensions.h"
#include "colorfree/perception/pipeline.h"
#include "colorfree/sim/runner.h"
#include "colorfree/sim/scenario.h"
#include "colorfree/sim/world_renderer.h"

using namespace colorfree;

namespace {

int probe(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: ball_probe SCENARIO [frames_per_case] [case] [png_dir]\n");
    return 2;
  }
  const int frames = argc > 2 ? std::atoi(argv[2]) : -1;
  const int only_case = argc > 3 ? std::atoi(argv[3]) : -1;
  const std::string png_dir = argc > 4 ? argv[4] : "";
  if (!png_dir.empty()) std::filesystem::create_directories(png_dir);
  const FieldDimensions dims = FieldDimensions::loadDefault();
  const FieldMarkings markings = FieldMarkings::fromDimensions(dims);
  const ScoringParams scoring = ScoringParams::loadDefault();
  PipelineConfig config = PipelineConfig::loadDefault();
  // Quick parameter trials: BP_TEXTURE=..., BP_SEARCH=..., BP_MINRESP=... override the files.
  const auto env = [](const char* k, double& v) {
    if (const char* e = std::getenv(k)) v = std::atof(e);
  };
  env("BP_TEXTURE", config.ball_proposer.texture_weight);
  env("BP_SEARCH", config.ball_proposer.centre_search_fraction);
  env("BP_MINGRAD", config.ball_proposer.min_gradient);
  env("BP_TNOISE", config.ball_proposer.texture_noise_factor);
  env("BP_NFREE", config.ball_proposer.noise_free_gray);
  env("BP_RNOISE", config.ball_proposer.response_noise_factor);
  env("BP_RTOL", config.ball_proposer.radius_tolerance);
  env("BP_MINRESP", config.ball_proposer.min_response);
  env("BP_LRESP", config.ball_proposer.light_response_fraction);
  env("BP_LCONT", config.ball_proposer.light_contrast_fraction);
  env("BP_INNER", config.ball_proposer.inner_fraction);
  env("BP_OUTER", config.ball_proposer.outer_fraction);
  env("BP_TEXEXP", config.ball_proposer.texture_scale_exponent);
  env("BP_BODY", config.ball_proposer.robot_body_factor);
  env("BP_BODYW", config.ball_proposer.robot_body_width_fraction);
  env("BP_OFFAXIS", config.ball_proposer.off_axis_exponent);
  env("BP_STEP", config.ball_proposer.step_fraction);
  env("BP_RIDGE", config.ball_proposer.centre_ridge_fraction);
  env("BP_RIDGEMINR", config.ball_proposer.centre_ridge_min_radius_px);
  if (const char* m = std::getenv("BP_MAXCOUNT")) config.ball_proposer.max_count = std::atoi(m);
  if (const char* m = std::getenv("BP_MODELS")) config.model_dir = m;  // nets to try
  if (const char* b = std::getenv("BP_BOOSTMIN")) config.ball_detector.boost_min_confidence = std::atof(b);
  if (const char* b = std::getenv("BP_BOOSTMIRROR")) config.ball_detector.boost_border_mirror = std::atoi(b);
  env("BP_SMEAR", config.ball_detector.smeared_min_coherence);
  if (const char* b = std::getenv("BP_DEBLUR")) config.ball_detector.deblur_iterations = std::atoi(b);
  env("BP_DEBLURSMEAR", config.ball_detector.deblur_min_camera_smear_radii);
  env("BP_DEBLURR", config.ball_detector.deblur_min_radius_px);
  env("BP_DEBLURCONF", config.ball_detector.deblur_min_confidence);
  env("BP_CAMSMEAR", config.ball_detector.smeared_min_camera_smear_radii);
  env("BP_SMEARDIR", config.ball_detector.smeared_max_direction_deg);
  env("BP_PATCHD", config.ball_detector.patch_diameters);
  env("BP_UP", config.ball_detector.rescale_up);
  env("BP_DOWN", config.ball_detector.rescale_down);
  env("BP_RESCONF", config.ball_detector.rescale_min_confidence);
  env("BP_RESCMINR", config.ball_detector.rescale_min_radius_px);
  env("BP_SMEARCONF", config.ball_detector.smeared_ball_min_confidence);
  env("BP_SHARP", config.ball_detector.sharpen_sigma_radii);
  env("BP_SHARPAMT", config.ball_detector.sharpen_amount);
  env("BP_SHARPCONF", config.ball_detector.sharpen_min_confidence);
  env("BP_SHARPMINR", config.ball_detector.sharpen_min_radius_px);
  env("BP_MIRROR", config.ball_detector.border_mirror_min_confidence);
  env("HC_LIGHT", config.high_contrast.light_contrast_fraction);
  // BP_EXACT=1: each proposal's centre, radius and response also printed in full (hexadecimal).
  const bool exact = std::getenv("BP_EXACT") != nullptr;
  const Pipeline pipeline(config);
  sim::ScenarioRunner runner(sim::Scenario::load(argv[1]), sim::worldRendererFactory());
  int truths = 0, prop_hits = 0, hits = 0, fps = 0;
  for (int c = 0; c < runner.caseCount(); ++c) {
    if (only_case >= 0 && c != only_case) continue;
    RobotTracks tracks;
    runner.runCase(c, frames, true, [&](const sim::RenderedFrame& f) {
      const FrameTruth truth = computeFrameTruth(f.truth, markings, dims, scoring);
      Frame frame(f.image.view(), f.perception_camera);
      pipeline.process(frame, nullptr, &tracks);
      const BallInImage& b = truth.ball;
      const bool demand = truth.ball_present && b.in_view && b.should_detect;
      std::printf(
          "case %d %s frame %d: ball %s c=(%.1f,%.1f) r=%.1f vis=%.2f d=%.2f camera smear "
          "(%.1f,%.1f)%s\n",
          c, runner.scenarioCase(c).name().c_str(), f.frame_index,
          truth.ball_present && b.in_view ? "in view" : "out", b.centre_px.x(), b.centre_px.y(),
          b.radius_px, b.visible_fraction, b.distance_m, f.perception_camera.exposureSmearPx().x(),
          f.perception_camera.exposureSmearPx().y(), demand ? " DEMANDED" : "");
      // BP_ROBOTS=1: the robot percepts too (their feet regions and bodies steer the proposals).
      if (std::getenv("BP_ROBOTS") && frame.robot_percepts) {
        for (const auto& r : *frame.robot_percepts)
          std::printf("   robot %.17g %.17g box %.17g %.17g %.17g %.17g\n", r.feet_px.x(),
                      r.feet_px.y(), r.box.x0, r.box.y0, r.box.x1, r.box.y1);
      }
      bool ph = false, dh = false;
      const auto& props = *frame.ball_proposals;
      for (std::size_t i = 0; i < props.size(); ++i) {
        const auto& p = props[i];
        const bool m =
            truth.ball_present && b.in_view && ballMatchCost(b, p.centre_px, scoring).has_value();
        ph = ph || (m && demand);
        BallDecision d;
        if (frame.ball_decisions) {
          for (const auto& e : *frame.ball_decisions) {
            if (e.proposal == static_cast<int>(i)) d = e;
          }
        }
        std::printf("   prop %2zu (%.1f,%.1f) r=%.1f resp=%.1f dist=%.1f%s boost=%.3f ball=%.3f",
                    i, p.centre_px.x(), p.centre_px.y(), p.radius_px, p.response,
                    (p.centre_px - b.centre_px).norm(), m ? " MATCH" : "", d.boost_confidence,
                    d.ball_confidence);
        if (d.smear >= 0) {
          // The patch's smear direction against the camera's own smear (undirected, degrees), and
          // the camera's smear in radii.
          Eigen::Vector2d along = Eigen::Vector2d::UnitX();
          patchSmear(f.image.view(),
                     ballPatchBox(p.centre_px, p.radius_px, config.ball_detector.patch_diameters),
                     &along);
          const Eigen::Vector2d cam = f.perception_camera.exposureSmearPx();
          const double angle =
              cam.norm() > 0
                  ? std::acos(std::min(1.0, std::abs(along.dot(cam)) / cam.norm())) * 180 / std::numbers::pi
                  : -1;
          std::printf(" smear=%.2f smeared=%.3f camsmear=%.2fr dir=%.0f", d.smear,
                      d.smeared_confidence, cam.norm() / p.radius_px, angle);
        }
        if (d.sharpened_confidence >= 0) std::printf(" sharp=%.3f", d.sharpened_confidence);
        if (d.deblurred_confidence >= 0) std::printf(" deblur=%.3f", d.deblurred_confidence);
        if (d.mirrored_confidence >= 0) std::printf(" mirror=%.3f", d.mirrored_confidence);
        std::printf("\n");
        // Every bit of the proposal (a speedup must leave them as they were).
        if (exact) {
          std::printf("        exact %a %a %a %a\n", p.centre_px.x(), p.centre_px.y(),
                      p.radius_px, p.response);
        }
      }
      for (const auto& bp : *frame.ball_percepts) {
        const bool m =
            truth.ball_present && b.in_view && ballMatchCost(b, bp.centre_px, scoring).has_value();
        if (m && demand) dh = true;
        if (!m) ++fps;
        std::printf("   PERCEPT (%.1f,%.1f) conf=%.3f %s\n", bp.centre_px.x(), bp.centre_px.y(),
                    bp.confidence, m ? "TP" : "FP");
      }
      if (demand) {
        ++truths;
        prop_hits += ph;
        hits += dh;
        if (!ph)
          std::printf("   >>> PROPOSAL MISS\n");
        else if (!dh)
          std::printf("   >>> NET MISS\n");
      }
      if (!png_dir.empty()) {
        char name[256];
        std::snprintf(name, sizeof name, "%s/c%02d_f%03d.png", png_dir.c_str(), c, f.frame_index);
        writeGrayPng(name, f.image.view());
        f.perception_camera.save(std::string(name) + ".camera.yaml");  // for colorfree detect
      }
    });
  }
  std::printf("truths %d proposal hits %d detected %d false positives %d\n", truths, prop_hits,
              hits, fps);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return probe(argc, argv);
  } catch (const std::exception& e) {  // a broken scenario, an unwritable folder
    std::fprintf(stderr, "ball_probe: %s\n", e.what());
    return 2;
  }
}
