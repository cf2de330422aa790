#include "colorfree/groundtruth/gallery.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "colorfree/perception/error.h"

namespace colorfree {

std::string base64Encode(const std::vector<unsigned char>& bytes) {
  static const char* kTable = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const unsigned v = (bytes[i] << 16) | ((i + 1 < bytes.size() ? bytes[i + 1] : 0) << 8) |
                       (i + 2 < bytes.size() ? bytes[i + 2] : 0);
    out += kTable[(v >> 18) & 63];
    out += kTable[(v >> 12) & 63];
    out += i + 1 < bytes.size() ? kTable[(v >> 6) & 63] : '=';
    out += i + 2 < bytes.size() ? kTable[v & 63] : '=';
  }
  return out;
}

std::string cropPngBase64(const GrayImage& image, PixelBox region,
                          const std::vector<Overlay>& overlays, int out_size_px) {
  if (image.empty()) return {};
  const double pad = std::max(8.0, 0.25 * std::max(region.width(), region.height()));
  const int x0 = std::clamp(static_cast<int>(std::floor(region.x0 - pad)), 0, image.width() - 1);
  const int y0 = std::clamp(static_cast<int>(std::floor(region.y0 - pad)), 0, image.height() - 1);
  const int x1 = std::clamp(static_cast<int>(std::ceil(region.x1 + pad)), x0 + 1, image.width());
  const int y1 = std::clamp(static_cast<int>(std::ceil(region.y1 + pad)), y0 + 1, image.height());
  const cv::Mat gray(image.height(), image.width(), CV_8UC1,
                     const_cast<std::uint8_t*>(image.data()));
  cv::Mat crop;
  const double scale = static_cast<double>(out_size_px) / std::max(x1 - x0, y1 - y0);
  cv::resize(gray(cv::Rect(x0, y0, x1 - x0, y1 - y0)), crop, cv::Size(), scale, scale,
             scale >= 1 ? cv::INTER_NEAREST : cv::INTER_AREA);
  cv::Mat bgr;
  cv::cvtColor(crop, bgr, cv::COLOR_GRAY2BGR);
  auto pt = [&](const Eigen::Vector2d& p) {
    return cv::Point(static_cast<int>(std::lround((p.x() - x0) * scale)),
                     static_cast<int>(std::lround((p.y() - y0) * scale)));
  };
  for (const auto& o : overlays) {
    const cv::Scalar colour = o.role == Overlay::Role::kTruth     ? cv::Scalar(60, 220, 60)
                              : o.role == Overlay::Role::kPercept ? cv::Scalar(40, 40, 255)
                                                                  : cv::Scalar(0, 220, 255);
    const int thick = o.role == Overlay::Role::kProposal ? 1 : 2;
    switch (o.shape) {
      case Overlay::Shape::kCircle:
        cv::circle(bgr, pt(o.a), std::max(1, static_cast<int>(std::lround(o.radius_px * scale))),
                   colour, thick, cv::LINE_AA);
        break;
      case Overlay::Shape::kBox:
        cv::rectangle(bgr, pt({o.box.x0, o.box.y0}), pt({o.box.x1, o.box.y1}), colour, thick);
        break;
      case Overlay::Shape::kLine:
        cv::line(bgr, pt(o.a), pt(o.b), colour, thick, cv::LINE_AA);
        break;
      case Overlay::Shape::kCross:
        cv::drawMarker(bgr, pt(o.a), colour, cv::MARKER_CROSS, 10, thick);
        break;
    }
    if (!o.label.empty()) {
      const cv::Point at = o.shape == Overlay::Shape::kBox ? pt({o.box.x0, o.box.y0}) : pt(o.a);
      cv::putText(bgr, o.label, at + cv::Point(2, -3), cv::FONT_HERSHEY_SIMPLEX, 0.4, colour, 1,
                  cv::LINE_AA);
    }
  }
  std::vector<unsigned char> png;
  if (!cv::imencode(".png", bgr, png)) throw Error("gallery: cannot encode a PNG crop");
  return base64Encode(png);
}

}  // namespace colorfree
