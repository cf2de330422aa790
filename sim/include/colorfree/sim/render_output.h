#pragma once

#include <functional>
#include <optional>
#include <string>

#include "colorfree/sim/runner.h"

namespace colorfree::sim {

struct RenderDirOptions {
  std::string out_dir;
  std::optional<int> case_index;  ///< only this case; all when empty
  std::optional<int> frames;      ///< frames per case; the scenario's count when empty
  bool object_maps = false;       ///< also write objects_NNNNNN.png (16-bit labels)
};

/// Called after every frame with the frames done and the frames in all.
using RenderProgress = std::function<void(int done, int total, const RenderedFrame& frame)>;

/// Renders the scenario's cases into `out_dir`:
///   render.json                  the scenario, its cases, their sweep values, the frame count
///   case_NNN/frame_NNNNNN.png    8-bit grayscale frames
///   case_NNN/objects_NNNNNN.png  16-bit object maps (with object_maps)
///   case_NNN/truth.jsonl         one WorldState per line (world_state_json.h), plus "image"
/// Everything is written to a temporary folder beside `out_dir` and renamed to it only when
/// complete; an earlier render in `out_dir` is replaced then. A folder that exists, is not empty
/// and holds no render.json is never touched (colorfree::Error). Returns the frames written.
int renderToDirectory(ScenarioRunner& runner, const RenderDirOptions& options,
                      const RenderProgress& progress = {});

/// "frame_000012.png" and the like.
std::string frameFileName(const std::string& stem, int frame_index, const std::string& ext);

}  // namespace colorfree::sim
