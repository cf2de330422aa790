// `robot-data`: training patches for RobotNet, OriBoostNet and OriNet from rendered scenarios and
// their truth (scoring the robot stages is `colorfree run`'s job).
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <random>
#include <string>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "colorfree/groundtruth/field_markings.h"
#include "colorfree/groundtruth/matching.h"
#include "colorfree/groundtruth/results.h"
#include "colorfree/groundtruth/scorer.h"
#include "colorfree/groundtruth/truth_in_image.h"
#include "colorfree/perception/cnn/dataset.h"
#include "colorfree/perception/cnn/net.h"
#include "colorfree/perception/cnn/patch.h"
#include "colorfree/perception/cnn/shipped_nets.h"
#include "colorfree/perception/error.h"
#include "colorfree/perception/pipeline.h"
#include "colorfree/perception/robot_detector.h"
#include "colorfree/perception/robot_orientation.h"
#include "colorfree/perception/robot_proposer.h"
#include "colorfree/sim/runner.h"
#include "colorfree/sim/world_renderer.h"
#include "commands.h"

namespace colorfree::app {
namespace {

GrayImage cropPatch(const GrayView& image, const PixelBox& box, int side) {
  std::vector<float> v(static_cast<std::size_t>(side) * side);
  cnn::extractPatch(image,
                    {static_cast<float>(box.x0), static_cast<float>(box.y0),
                     static_cast<float>(box.width()), static_cast<float>(box.height())},
                    side, side, cnn::PatchNormalization::kUnitRange, v.data());
  GrayImage out(side, side);
  for (int i = 0; i < side * side; ++i) {
    out.data()[i] = static_cast<std::uint8_t>(std::clamp(std::lround(v[i] * 255.0f), 0L, 255L));
  }
  return out;
}

cnn::Classifier untrained(int index) {
  const cnn::ShippedNet& s = cnn::kShippedNets[index];
  cnn::Net net = cnn::readDarknetCfg(s.cfgPath());
  net.initialise(1);
  return cnn::Classifier(std::move(net));
}

cnn::Classifier shippedOrUntrained(int index) {
  const cnn::ShippedNet& s = cnn::kShippedNets[index];
  if (std::filesystem::exists(s.weightsPath())) return cnn::Classifier::load(s.cfgPath(), s.weightsPath());
  return untrained(index);
}

// The shared pipeline up to the contrast regions, and the robot stages with the shipped nets or,
// before the first training, untrained ones.
PipelineConfig regionsOnly() {
  PipelineConfig c = PipelineConfig::loadDefault();
  c.robot_stages = false;
  c.ball_stages = false;
  return c;
}
struct RobotStages {
  Pipeline pipeline{regionsOnly()};
  RobotProposer proposer{RobotProposerParams::loadDefault(), FieldDimensions::loadDefault()};
  RobotDetector detector{RobotDetectorParams::loadDefault(), shippedOrUntrained(0)};
  RobotOrientationEstimator orientation{RobotOrientationParams::loadDefault(),
                                        FieldDimensions::loadDefault(), shippedOrUntrained(3),
                                        shippedOrUntrained(4)};
};

std::optional<Eigen::Vector2d> feetInField(const WorldState& w, const Eigen::Vector2d& feet_px) {
  const auto g = w.camera.model.pixelToGround(feet_px);
  if (!g) return std::nullopt;
  return Eigen::Vector2d((robotToField(w.observer) * Eigen::Vector3d(g->x(), g->y(), 0)).head<2>());
}

double axialDiff(double a, double b) {
  double d = std::fmod(std::abs(a - b), std::numbers::pi);
  return std::min(d, std::numbers::pi - d);
}

struct DataCounts {
  int frames = 0;
  int robot = 0, none = 0, usable = 0, unusable = 0, front = 0, back = 0, side = 0;
};

void collect(const sim::RenderedFrame& f, const RobotStages& st, const ScoringParams& sp,
             const FieldMarkings& fm, const FieldDimensions& dims, std::mt19937_64& rng,
             const std::string& scenario, cnn::Dataset& robot_data, cnn::Dataset& boost_data,
             cnn::Dataset& ori_data, DataCounts& counts) {
  const CameraModel& camera = f.truth.camera.model;
  Frame frame(f.image.view(), camera);
  st.pipeline.process(frame);
  const RobotProposals props =
      st.proposer.run(frame.image, camera, *frame.ignore_mask, *frame.contrast_regions);
  const FrameTruth truth = computeFrameTruth(f.truth, fm, dims, sp);
  ++counts.frames;
  auto origin = [&](const PixelBox& b, const std::string& what) {
    cnn::SampleOrigin o;
    o.scenario = scenario;
    o.frame = f.case_index * 10000 + f.frame_index;
    o.x_px = static_cast<float>(b.x0);
    o.y_px = static_cast<float>(b.y0);
    o.width_px = static_cast<float>(b.width());
    o.height_px = static_cast<float>(b.height());
    o.truth = what;
    return o;
  };
  for (const RobotProposal& p : props.proposals) {
    const auto feet = feetInField(f.truth, p.feet_px);
    int best = -1;
    double best_cost = 1e9;
    bool any = false;
    for (std::size_t i = 0; i < truth.robots.size(); ++i) {
      const RobotInImage& r = truth.robots[i];
      if (!r.in_view) continue;
      const auto c = robotMatchCost(r, p.box, feet, sp);
      if (!c) continue;
      any = true;
      if (r.should_detect && *c < best_cost) {
        best_cost = *c;
        best = static_cast<int>(i);
      }
    }
    if (best >= 0) {
      robot_data.samples.push_back({cropPatch(frame.image, p.box, 24), 1, origin(p.box, "robot")});
      ++counts.robot;
      // Orientation samples from this robot's line regions.
      const RobotInImage& r = truth.robots[best];
      RobotPercept percept;
      percept.box = p.box;
      percept.feet_px = p.feet_px;
      percept.position_in_robot = camera.pixelToGround(p.feet_px);
      const RobotLines lines = st.orientation.findLines(frame.image, camera, percept);
      const Eigen::Vector2d robot_pos =
          percept.position_in_robot ? *percept.position_in_robot : Eigen::Vector2d::Zero();
      for (const LineRegion& region : lines.regions) {
        const Eigen::Vector2d d = region.line_in_robot.direction();
        const double diff = axialDiff(std::atan2(d.y(), d.x()), r.heading_in_observer_rad);
        const double tol = 12.0 * std::numbers::pi / 180;
        const bool usable = diff <= tol || diff >= std::numbers::pi / 2 - tol;
        const std::string what = "diff_deg=" + std::to_string(diff * 180 / std::numbers::pi);
        boost_data.samples.push_back(
            {cropPatch(frame.image, region.box, 12), usable ? 1 : 0, origin(region.box, what)});
        ++(usable ? counts.usable : counts.unusable);
        if (diff > 20.0 * std::numbers::pi / 180 && diff < 70.0 * std::numbers::pi / 180) continue;
        int label = 2;
        if (diff >= std::numbers::pi / 4) {
          const Eigen::Vector2d facing(std::cos(r.heading_in_observer_rad),
                                       std::sin(r.heading_in_observer_rad));
          label = facing.dot(-robot_pos) > 0 ? 0 : 1;
        }
        ori_data.samples.push_back({cropPatch(frame.image, region.box, 24), label, origin(region.box, what)});
        ++(label == 0 ? counts.front : label == 1 ? counts.back : counts.side);
      }
    } else if (!any) {
      robot_data.samples.push_back({cropPatch(frame.image, p.box, 24), 0, origin(p.box, "none")});
      ++counts.none;
    }
  }
  // Hard negatives: robot-sized boxes at random ground points away from every robot (lines, posts,
  // the ball, the own body, the hall).
  std::uniform_real_distribution<double> ux(0, camera.width()), uy(0, camera.height());
  for (int k = 0, tries = 0; k < 3 && tries < 30; ++tries) {
    const Eigen::Vector2d feet(ux(rng), uy(rng));
    const auto h = camera.robotHeightPx(feet, dims.robot_height_m);
    if (!h || *h < 10) continue;
    PixelBox b;
    const double w = 1.25 * *h * dims.robot_width_m / dims.robot_height_m;
    b.x0 = feet.x() - w / 2;
    b.x1 = feet.x() + w / 2;
    b.y1 = feet.y() + 0.04 * *h;
    b.y0 = b.y1 - 1.08 * *h;
    bool near_robot = false;
    for (const RobotInImage& r : truth.robots) {
      if (r.in_view && boxIou(r.box, b) > 0.05) near_robot = true;
    }
    if (near_robot) continue;
    robot_data.samples.push_back({cropPatch(frame.image, b, 24), 0, origin(b, "random")});
    ++counts.none;
    ++k;
  }
}
}  // namespace

void addRobotCommands(CLI::App& app, int& exit_code) {
  struct Args {
    std::vector<std::string> scenarios;
    std::string out;
    int frames = 0, every = 1;
    std::uint64_t seed = 7;
  };
  auto data_args = std::make_shared<Args>();
  auto* data = app.add_subcommand(
      "robot-data", "Training patches for RobotNet, OriBoostNet and OriNet from rendered scenarios");
  data->add_option("scenarios", data_args->scenarios, "scenario files")->required();
  data->add_option("--out", data_args->out, "output folder (robot_net/, ori_boost_net/, ori_net/)")
      ->required();
  data->add_option("--frames", data_args->frames, "frames per case instead of the scenario's");
  data->add_option("--every", data_args->every, "use every n-th frame");
  data->add_option("--seed", data_args->seed, "seed of the random hard negatives");
  data->callback([data_args, &exit_code]() {
    const RobotStages stages;
    const ScoringParams sp = ScoringParams::loadDefault();
    const FieldDimensions dims = FieldDimensions::loadDefault();
    const FieldMarkings fm = FieldMarkings::fromDimensions(dims);
    cnn::Dataset robot_data{24, 24, {"none", "robot"}, {}};
    cnn::Dataset boost_data{12, 12, {"unusable", "usable"}, {}};
    cnn::Dataset ori_data{24, 24, {"front", "back", "side"}, {}};
    DataCounts counts;
    std::mt19937_64 rng(data_args->seed);
    for (const std::string& path : data_args->scenarios) {
      sim::ScenarioRunner runner(sim::Scenario::load(path), sim::worldRendererFactory());
      for (int c = 0; c < runner.caseCount(); ++c) {
        const int n = data_args->frames > 0 ? data_args->frames
                                            : runner.scenarioCase(c).settings.frames;
        for (int i = 0; i < n; i += std::max(1, data_args->every)) {
          const sim::RenderedFrame f = runner.render(c, i, true);
          collect(f, stages, sp, fm, dims, rng, runner.scenario().name, robot_data, boost_data,
                  ori_data, counts);
        }
        std::fprintf(stderr, "%s case %d: %d frames, robot %d none %d usable %d unusable %d front %d back %d side %d\n",
                     runner.scenario().name.c_str(), c, counts.frames, counts.robot, counts.none,
                     counts.usable, counts.unusable, counts.front, counts.back, counts.side);
      }
    }
    std::filesystem::create_directories(data_args->out);
    cnn::writeDataset(robot_data, data_args->out + "/robot_net");
    cnn::writeDataset(boost_data, data_args->out + "/ori_boost_net");
    cnn::writeDataset(ori_data, data_args->out + "/ori_net");
    std::printf("%d frames: robot_net robot=%d none=%d; ori_boost_net usable=%d unusable=%d; ori_net front=%d back=%d side=%d -> %s\n",
                counts.frames, counts.robot, counts.none, counts.usable, counts.unusable,
                counts.front, counts.back, counts.side, data_args->out.c_str());
    exit_code = 0;
  });
}

}  // namespace colorfree::app
