#include "colorfree/sim/render_output.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "colorfree/groundtruth/world_state_json.h"
#include "colorfree/perception/error.h"
#include "colorfree/sim/object_map_io.h"

namespace colorfree::sim {
namespace {
namespace fs = std::filesystem;

// Draws a flat image whose grey level is the frame's time in tenths of a second; can be told to
// fail at a given render.
class TimeRenderer : public SceneRenderer {
 public:
  explicit TimeRenderer(int fail_at) : fail_at_(fail_at) {}
  void setObserver(const RobotMotionState&, const HeadAngles&) override {}
  void setRobot(int, const RobotMotionState&) override {}
  void setBall(const BallMotionState& b) override { x_ = b.position_m.x(); }
  void setLighting(const LightingState&) override {}
  CameraModel cameraModel(NaoCamera, int w, int h) const override {
    return CameraModel(CameraIntrinsics::fromHorizontalFov(w, h, 1.0), CameraPose{});
  }
  Eigen::Isometry3d cameraToField(NaoCamera) const override {
    return Eigen::Isometry3d::Identity();
  }
  RenderOutput render(NaoCamera, int w, int h, bool object_map) override {
    if (++renders_ == fail_at_) throw Error("renderer failed on purpose");
    RenderOutput out;
    out.gray = GrayImage(w, h, static_cast<std::uint8_t>(x_ * 100));
    if (object_map) {
      out.object_map.width = w;
      out.object_map.height = h;
      out.object_map.labels.assign(static_cast<std::size_t>(w) * h, kObjectBall);
      out.object_map.labels[0] = kObjectRobotBase + 3;
    }
    return out;
  }

 private:
  int fail_at_;
  int renders_ = 0;
  double x_ = 0;
};

RendererFactory factory(int fail_at = -1) {
  return [fail_at](const SceneSpec&) -> std::unique_ptr<SceneRenderer> {
    return std::make_unique<TimeRenderer>(fail_at);
  };
}

const char* kScenario = R"(name: files
camera: bottom
resolution: [32, 24]
frames: 3
frame_rate_hz: 10
seed: 1
observer: {x_m: 0, y_m: 0, heading_deg: 0}
ball: {x_m: 0, y_m: 0, velocity_x_mps: 1, deceleration_mps2: 0}
lighting: {preset: normal}
sweep:
  - path: lighting.preset
    values: [dim, uneven]
)";

class RenderOutputTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("colorfree_render_test_" +
            std::to_string(::testing::UnitTest::GetInstance()->random_seed()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  int entries() const {
    return static_cast<int>(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()));
  }
  fs::path dir_;
};

TEST_F(RenderOutputTest, WritesFramesTruthAndObjectMapsPerCase) {
  ScenarioRunner runner(Scenario::parse(kScenario, "files.yaml"), factory());
  RenderDirOptions options;
  options.out_dir = (dir_ / "out").string();
  options.object_maps = true;
  int calls = 0;
  const int written =
      renderToDirectory(runner, options, [&](int done, int total, const RenderedFrame&) {
        EXPECT_EQ(done, ++calls);
        EXPECT_EQ(total, 6);
      });
  EXPECT_EQ(written, 6);
  EXPECT_EQ(entries(), 1);  // no temporary folder left
  for (const char* c : {"case_000", "case_001"}) {
    const fs::path cd = dir_ / "out" / c;
    std::ifstream truth(cd / "truth.jsonl");
    std::string line;
    int n = 0;
    while (std::getline(truth, line)) {
      const nlohmann::json j = nlohmann::json::parse(line);
      const WorldState s = worldStateFromJson(j, "truth.jsonl");
      EXPECT_EQ(s.frame_index, n);
      EXPECT_EQ(j["image"], frameFileName("frame", n, "png"));
      const GrayImage image = readGrayImage((cd / j["image"].get<std::string>()).string());
      EXPECT_EQ(image.width(), 32);
      EXPECT_EQ(image.at(5, 5), n * 10);
      const ObjectMap map = readObjectMapPng((cd / j["object_map"].get<std::string>()).string());
      EXPECT_EQ(map.width, 32);
      EXPECT_EQ(map.at(0, 0), kObjectRobotBase + 3);
      EXPECT_EQ(map.at(1, 0), kObjectBall);
      ++n;
    }
    EXPECT_EQ(n, 3);
  }
  std::ifstream manifest_file(dir_ / "out" / "render.json");
  const nlohmann::json manifest = nlohmann::json::parse(manifest_file);
  EXPECT_EQ(manifest["scenario"], "files");
  ASSERT_EQ(manifest["cases"].size(), 2u);
  EXPECT_EQ(manifest["cases"][1]["values"]["lighting.preset"], "uneven");
}

TEST_F(RenderOutputTest, OneCaseAndFewerFramesOnRequest) {
  ScenarioRunner runner(Scenario::parse(kScenario, "files.yaml"), factory());
  RenderDirOptions options;
  options.out_dir = (dir_ / "out").string();
  options.case_index = 1;
  options.frames = 2;
  EXPECT_EQ(renderToDirectory(runner, options), 2);
  EXPECT_FALSE(fs::exists(dir_ / "out" / "case_000"));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "case_001" / "frame_000001.png"));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "case_001" / "frame_000002.png"));
  EXPECT_FALSE(fs::exists(dir_ / "out" / "case_001" / "objects_000000.png"));
  options.case_index = 2;
  EXPECT_THROW(renderToDirectory(runner, options), Error);
}

TEST_F(RenderOutputTest, AFailedRenderLeavesNothingThatLooksComplete) {
  ScenarioRunner runner(Scenario::parse(kScenario, "files.yaml"), factory(3));
  RenderDirOptions options;
  options.out_dir = (dir_ / "out").string();
  EXPECT_THROW(renderToDirectory(runner, options), Error);
  EXPECT_EQ(entries(), 0);
}

TEST_F(RenderOutputTest, AFailedRenderKeepsTheEarlierCompleteOne) {
  RenderDirOptions options;
  options.out_dir = (dir_ / "out").string();
  ScenarioRunner good(Scenario::parse(kScenario, "files.yaml"), factory());
  renderToDirectory(good, options);
  ScenarioRunner bad(Scenario::parse(kScenario, "files.yaml"), factory(2));
  options.case_index = 0;
  EXPECT_THROW(renderToDirectory(bad, options), Error);
  EXPECT_EQ(entries(), 1);
  EXPECT_TRUE(fs::exists(dir_ / "out" / "case_001" / "truth.jsonl"));
  // A complete render replaces it.
  ScenarioRunner again(Scenario::parse(kScenario, "files.yaml"), factory());
  renderToDirectory(again, options);
  EXPECT_FALSE(fs::exists(dir_ / "out" / "case_001"));
  EXPECT_TRUE(fs::exists(dir_ / "out" / "case_000" / "truth.jsonl"));
}

TEST_F(RenderOutputTest, NeverTouchesAFolderThatIsNotARender) {
  fs::create_directories(dir_ / "mine");
  std::ofstream(dir_ / "mine" / "notes.txt") << "keep";
  ScenarioRunner runner(Scenario::parse(kScenario, "files.yaml"), factory());
  RenderDirOptions options;
  options.out_dir = (dir_ / "mine").string();
  try {
    renderToDirectory(runner, options);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("not a colorfree render"), std::string::npos);
  }
  EXPECT_TRUE(fs::exists(dir_ / "mine" / "notes.txt"));
  EXPECT_EQ(entries(), 1);
}

}  // namespace
}  // namespace colorfree::sim
