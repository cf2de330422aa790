#include "colorfree/perception/image.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "colorfree/perception/error.h"

namespace colorfree {
namespace {

TEST(Image, YuyvTakesTheLumaBytes) {
  const std::vector<std::uint8_t> yuyv = {10, 128, 20, 129, 30, 130, 40, 131,
                                          50, 1,   60, 2,   70, 3,   80, 4};
  const GrayImage g = grayFromYuyv(yuyv, 4, 2);
  ASSERT_EQ(g.width(), 4);
  ASSERT_EQ(g.height(), 2);
  EXPECT_EQ(g.at(0, 0), 10);
  EXPECT_EQ(g.at(3, 0), 40);
  EXPECT_EQ(g.at(0, 1), 50);
  EXPECT_EQ(g.at(3, 1), 80);
}

TEST(Image, YuyvOfWrongSizeIsAnError) {
  EXPECT_THROW(grayFromYuyv(std::vector<std::uint8_t>(15), 4, 2), Error);
  EXPECT_THROW(grayFromYuyv(std::vector<std::uint8_t>(12), 3, 2), Error);
}

TEST(Image, PngRoundTrip) {
  GrayImage g(7, 5);
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 7; ++x) g.at(x, y) = static_cast<std::uint8_t>(x * 30 + y);
  const std::string path = ::testing::TempDir() + "/image_round_trip.png";
  writeGrayPng(path, g.view());
  const GrayImage back = readGrayImage(path);
  EXPECT_EQ(back.pixels(), g.pixels());
  std::filesystem::remove(path);
}

TEST(Image, MissingFileNamesTheFile) {
  try {
    readGrayImage("/nonexistent/frame.png");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/frame.png"), std::string::npos);
  }
}

}  // namespace
}  // namespace colorfree
