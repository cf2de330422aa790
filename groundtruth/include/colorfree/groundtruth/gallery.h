#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "colorfree/perception/image.h"
#include "colorfree/perception/percepts.h"

namespace colorfree {

/// A shape drawn over a crop: truth in green, percepts in red, proposals in yellow.
struct Overlay {
  enum class Shape { kCircle, kBox, kLine, kCross };
  enum class Role { kTruth, kPercept, kProposal };
  Shape shape = Shape::kBox;
  Role role = Role::kTruth;
  Eigen::Vector2d a = Eigen::Vector2d::Zero();  ///< circle/cross centre, line start
  Eigen::Vector2d b = Eigen::Vector2d::Zero();  ///< line end
  double radius_px = 0;
  PixelBox box;
  std::string label;
};

/// Cuts `region` (padded, clipped to the image) out of the image, scales it so its longer side is
/// `out_size_px`, draws the overlays and returns a base64 PNG.
std::string cropPngBase64(const GrayImage& image, PixelBox region,
                          const std::vector<Overlay>& overlays, int out_size_px);

std::string base64Encode(const std::vector<unsigned char>& bytes);

}  // namespace colorfree
