#include "colorfree/perception/image.h"

#include <fstream>
#include <iterator>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "colorfree/perception/error.h"

namespace colorfree {

GrayImage::GrayImage(int width, int height, std::uint8_t fill) : width_(width), height_(height) {
  if (width < 0 || height < 0) throw Error("image size must not be negative");
  pixels_.assign(static_cast<std::size_t>(width) * height, fill);
}

GrayImage grayFromYuyv(const std::vector<std::uint8_t>& yuyv, int width, int height) {
  if (width <= 0 || height <= 0 || width % 2 != 0) {
    throw Error("YUYV frame: width must be positive and even, height positive (got " +
                std::to_string(width) + "x" + std::to_string(height) + ")");
  }
  const std::size_t expected = static_cast<std::size_t>(width) * height * 2;
  if (yuyv.size() != expected) {
    throw Error("YUYV frame: expected " + std::to_string(expected) + " bytes for " +
                std::to_string(width) + "x" + std::to_string(height) + ", got " +
                std::to_string(yuyv.size()));
  }
  GrayImage out(width, height);
  std::uint8_t* dst = out.data();
  const std::size_t n = static_cast<std::size_t>(width) * height;
  for (std::size_t i = 0; i < n; ++i) dst[i] = yuyv[2 * i];
  return out;
}

GrayImage readGrayImage(const std::string& path) {
  cv::Mat m = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (m.empty()) throw Error(path + ": cannot read image (missing file or unknown format)");
  if (m.depth() != CV_8U) throw Error(path + ": image is not 8 bits per channel");
  cv::Mat gray;
  if (m.channels() == 1) {
    gray = m;
  } else if (m.channels() == 3) {
    cv::cvtColor(m, gray, cv::COLOR_BGR2GRAY);
  } else if (m.channels() == 4) {
    cv::cvtColor(m, gray, cv::COLOR_BGRA2GRAY);
  } else {
    throw Error(path + ": unsupported channel count " + std::to_string(m.channels()));
  }
  GrayImage out(gray.cols, gray.rows);
  for (int y = 0; y < gray.rows; ++y) {
    std::copy(gray.ptr<std::uint8_t>(y), gray.ptr<std::uint8_t>(y) + gray.cols, &out.at(0, y));
  }
  return out;
}

GrayImage readYuyvFile(const std::string& path, int width, int height) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open YUYV file");
  std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  try {
    return grayFromYuyv(bytes, width, height);
  } catch (const Error& e) {
    throw Error(path + ": " + e.what());
  }
}

void writeGrayPng(const std::string& path, const GrayView& image) {
  cv::Mat m(image.height, image.width, CV_8UC1, const_cast<std::uint8_t*>(image.data),
            static_cast<std::size_t>(image.stride));
  bool ok = false;
  try {
    ok = cv::imwrite(path, m);
  } catch (const cv::Exception&) {
    ok = false;
  }
  if (!ok) throw Error(path + ": cannot write PNG");
}

}  // namespace colorfree
