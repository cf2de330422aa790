#include "colorfree/sim/render_output.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

#include "colorfree/groundtruth/world_state_json.h"
#include "colorfree/perception/error.h"
#include "colorfree/sim/object_map_io.h"

namespace colorfree::sim {
namespace fs = std::filesystem;

namespace {

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();
  if (!out) throw Error(path.string() + ": cannot write");
}

nlohmann::json caseJson(const ScenarioCase& c, int frames) {
  nlohmann::json values = nlohmann::json::object();
  for (const SweepValue& v : c.values) {
    // Numbers as numbers, anything else as written.
    try {
      std::size_t used = 0;
      const double d = std::stod(v.value, &used);
      values[v.path] = used == v.value.size() ? nlohmann::json(d) : nlohmann::json(v.value);
    } catch (const std::exception&) {
      values[v.path] = v.value;
    }
  }
  return {{"name", c.name()},
          {"index", c.index},
          {"values", values},
          {"frames", frames},
          {"camera", c.settings.camera == NaoCamera::kTop ? "top" : "bottom"},
          {"width_px", c.settings.width_px},
          {"height_px", c.settings.height_px},
          {"frame_rate_hz", c.settings.frame_rate_hz},
          {"seed", c.settings.seed},
          {"orientation_tolerance_rad", c.settings.orientation_tolerance_rad}};
}

}  // namespace

std::string frameFileName(const std::string& stem, int frame_index, const std::string& ext) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "_%06d.", frame_index);
  return stem + buf + ext;
}

int renderToDirectory(ScenarioRunner& runner, const RenderDirOptions& options,
                      const RenderProgress& progress) {
  if (options.out_dir.empty()) throw Error("render: no output folder given");
  const Scenario& scenario = runner.scenario();
  std::vector<int> cases;
  if (options.case_index) {
    runner.scenarioCase(*options.case_index);  // throws on a bad index
    cases.push_back(*options.case_index);
  } else {
    for (int k = 0; k < runner.caseCount(); ++k) cases.push_back(k);
  }
  if (options.frames && *options.frames < 1) throw Error("render: --frames must be at least 1");

  const fs::path out = fs::absolute(fs::path(options.out_dir)).lexically_normal();
  const fs::path target = out.has_filename() ? out : out.parent_path();
  std::error_code ec;
  if (fs::exists(target, ec)) {
    if (!fs::is_directory(target)) throw Error(target.string() + ": exists and is not a folder");
    if (!fs::is_empty(target) && !fs::exists(target / "render.json")) {
      throw Error(target.string() +
                  ": exists, is not empty and is not a colorfree render (no render.json); "
                  "not touching it");
    }
  }
  fs::create_directories(target.parent_path(), ec);
  if (ec) throw Error(target.parent_path().string() + ": cannot create folder: " + ec.message());
  const std::string pid = std::to_string(static_cast<long>(::getpid()));
  // Hidden siblings of the target (built up with += : GCC 12 warns falsely on "." + string).
  auto sibling = [&](const char* tag) {
    std::string name = ".";
    name += target.filename().string();
    name += tag;
    name += pid;
    return target.parent_path() / name;
  };
  const fs::path temp = sibling(".partial-");
  fs::remove_all(temp, ec);
  if (!fs::create_directory(temp, ec) || ec) {
    throw Error(temp.string() + ": cannot create folder: " + ec.message());
  }

  int total = 0;
  for (int k : cases) total += options.frames.value_or(runner.scenarioCase(k).settings.frames);
  int done = 0;
  try {
    nlohmann::json manifest;
    manifest["scenario"] = scenario.name;
    manifest["file"] = scenario.path;
    manifest["object_maps"] = options.object_maps;
    manifest["cases"] = nlohmann::json::array();
    for (int k : cases) {
      const ScenarioCase& c = runner.scenarioCase(k);
      const int frames = options.frames.value_or(c.settings.frames);
      const fs::path dir = temp / c.name();
      fs::create_directory(dir);
      std::ofstream truth(dir / "truth.jsonl", std::ios::binary);
      if (!truth) throw Error((dir / "truth.jsonl").string() + ": cannot write");
      runner.runCase(k, frames, options.object_maps, [&](const RenderedFrame& f) {
        const std::string image = frameFileName("frame", f.frame_index, "png");
        writeGrayPng((dir / image).string(), f.image.view());
        nlohmann::json line = worldStateToJson(f.truth);
        line["image"] = image;
        if (options.object_maps) {
          const std::string objects = frameFileName("objects", f.frame_index, "png");
          writeObjectMapPng((dir / objects).string(), f.truth.object_map);
          line["object_map"] = objects;
        }
        truth << line.dump() << '\n';
        ++done;
        if (progress) progress(done, total, f);
      });
      truth.close();
      if (!truth) throw Error((dir / "truth.jsonl").string() + ": cannot write");
      manifest["cases"].push_back(caseJson(c, frames));
    }
    // render.json last: a folder without it was never finished.
    writeText(temp / "render.json", manifest.dump(2) + "\n");

    const fs::path old = sibling(".old-");
    const bool replace = fs::exists(target);
    if (replace) fs::rename(target, old);
    fs::rename(temp, target);
    if (replace) fs::remove_all(old, ec);
  } catch (const fs::filesystem_error& e) {
    fs::remove_all(temp, ec);
    throw Error(e.path1().string() + ": " + e.code().message());
  } catch (...) {
    fs::remove_all(temp, ec);
    throw;
  }
  return done;
}

}  // namespace colorfree::sim
