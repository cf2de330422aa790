#pragma once

#include <string>

#include "colorfree/groundtruth/world_state.h"

namespace colorfree::sim {

/// Writes the object map as a 16-bit grayscale PNG (one label per pixel); throws colorfree::Error
/// naming the file on failure.
void writeObjectMapPng(const std::string& path, const ObjectMap& map);

/// Reads what writeObjectMapPng wrote; throws colorfree::Error naming the file when it is missing
/// or not a 16-bit single-channel image.
ObjectMap readObjectMapPng(const std::string& path);

}  // namespace colorfree::sim
