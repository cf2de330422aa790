#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace colorfree {

/// A non-owning view of an 8-bit grayscale image, rows top-down, `stride` bytes apart.
struct GrayView {
  const std::uint8_t* data = nullptr;
  int width = 0;
  int height = 0;
  int stride = 0;

  std::uint8_t at(int x, int y) const { return data[y * stride + x]; }
  const std::uint8_t* row(int y) const { return data + y * stride; }
  bool empty() const { return data == nullptr || width <= 0 || height <= 0; }
  bool contains(int x, int y) const { return x >= 0 && y >= 0 && x < width && y < height; }
};

/// An owning 8-bit grayscale image, rows top-down, tightly packed.
class GrayImage {
 public:
  GrayImage() = default;
  GrayImage(int width, int height, std::uint8_t fill = 0);

  int width() const { return width_; }
  int height() const { return height_; }
  std::uint8_t* data() { return pixels_.data(); }
  const std::uint8_t* data() const { return pixels_.data(); }
  std::uint8_t& at(int x, int y) { return pixels_[static_cast<std::size_t>(y) * width_ + x]; }
  std::uint8_t at(int x, int y) const { return pixels_[static_cast<std::size_t>(y) * width_ + x]; }
  GrayView view() const { return {pixels_.data(), width_, height_, width_}; }
  bool empty() const { return pixels_.empty(); }
  const std::vector<std::uint8_t>& pixels() const { return pixels_; }

 private:
  int width_ = 0;
  int height_ = 0;
  std::vector<std::uint8_t> pixels_;
};

/// The Y plane of a NAO camera frame in YUV422 (YUYV: Y0 U Y1 V per two pixels).
/// Throws colorfree::Error when the buffer size does not match width × height × 2.
GrayImage grayFromYuyv(const std::vector<std::uint8_t>& yuyv, int width, int height);

/// Reads a PNG (or any format OpenCV reads) as 8-bit grayscale; a colour file is converted to luma.
/// Throws colorfree::Error naming the file when it cannot be read.
GrayImage readGrayImage(const std::string& path);

/// Reads a raw YUYV frame of the given size from a file.
GrayImage readYuyvFile(const std::string& path, int width, int height);

/// Writes the image as PNG; throws colorfree::Error naming the file on failure.
void writeGrayPng(const std::string& path, const GrayView& image);

}  // namespace colorfree
