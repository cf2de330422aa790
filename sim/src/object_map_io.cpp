#include "colorfree/sim/object_map_io.h"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "colorfree/perception/error.h"

namespace colorfree::sim {

void writeObjectMapPng(const std::string& path, const ObjectMap& map) {
  if (map.width <= 0 || map.height <= 0 ||
      map.labels.size() != static_cast<std::size_t>(map.width) * map.height) {
    throw Error(path + ": object map is empty or its size does not match its labels");
  }
  const cv::Mat mat(map.height, map.width, CV_16UC1, const_cast<std::uint16_t*>(map.labels.data()));
  bool ok = false;
  try {
    ok = cv::imwrite(path, mat);
  } catch (const cv::Exception& e) {
    throw Error(path + ": cannot write object map: " + e.what());
  }
  if (!ok) throw Error(path + ": cannot write object map");
}

ObjectMap readObjectMapPng(const std::string& path) {
  const cv::Mat mat = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (mat.empty()) throw Error(path + ": cannot read object map");
  if (mat.type() != CV_16UC1) throw Error(path + ": not a 16-bit single-channel object map");
  ObjectMap map;
  map.width = mat.cols;
  map.height = mat.rows;
  map.labels.resize(static_cast<std::size_t>(mat.cols) * mat.rows);
  for (int y = 0; y < mat.rows; ++y) {
    const auto* row = mat.ptr<std::uint16_t>(y);
    std::copy(row, row + mat.cols, map.labels.begin() + static_cast<std::ptrdiff_t>(y) * mat.cols);
  }
  return map;
}

}  // namespace colorfree::sim
