#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "colorfree/groundtruth/world_state.h"

namespace colorfree {

/// WorldState as JSON (the object map's pixels are left out; they go to a 16-bit PNG). Angles in
/// radians, lengths in metres, as the struct; transforms as {"rotation": 3×3 rows,
/// "translation_m": [x, y, z]}. Numbers round-trip exactly.
nlohmann::json worldStateToJson(const WorldState& state);

/// Reads what worldStateToJson writes; keys it does not know are ignored (a truth line may carry
/// more, e.g. the image's file name). Throws colorfree::Error naming `origin` and the key when a
/// key is missing or has the wrong type, or a number is not finite.
WorldState worldStateFromJson(const nlohmann::json& json, const std::string& origin);

/// One line of truth.jsonl (no newline).
std::string worldStateToJsonLine(const WorldState& state);

}  // namespace colorfree
