// SPDX-License-Identifier: Apache-2.0
// Pixel format conversion to grey (no device needed): every V4L2 layout rigcal reads, with
// padded rows, short buffers and JPEG decoding.

#include "rigcal/capture/pixel_format.h"

#include <gtest/gtest.h>
#include <linux/videodev2.h>

#include <opencv2/imgcodecs.hpp>
#include <vector>

namespace rigcal::capture {
namespace {

// A test image whose every pixel differs from its neighbours: v = (7x + 13y) mod 256.
uint8_t Pattern(int x, int y) { return static_cast<uint8_t>((7 * x + 13 * y) % 256); }

void ExpectPattern(const cv::Mat& grey, int width, int height) {
  ASSERT_EQ(grey.type(), CV_8UC1);
  ASSERT_EQ(grey.cols, width);
  ASSERT_EQ(grey.rows, height);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      ASSERT_EQ(grey.at<uint8_t>(y, x), Pattern(x, y)) << "at " << x << "," << y;
    }
  }
}

constexpr int kW = 6;
constexpr int kH = 4;

TEST(PixelFormat, GreyWithPaddedRows) {
  const int stride = kW + 10;
  std::vector<uint8_t> buffer(stride * kH, 0xee);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) buffer[y * stride + x] = Pattern(x, y);
  auto grey = ConvertToGrey({PixelFormat::kGrey, kW, kH, stride}, buffer.data(), buffer.size());
  ASSERT_TRUE(grey.ok()) << grey.error();
  ExpectPattern(*grey, kW, kH);
}

TEST(PixelFormat, YuyvKeepsTheLuma) {
  std::vector<uint8_t> buffer(2 * kW * kH);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      buffer[y * 2 * kW + 2 * x] = Pattern(x, y);
      buffer[y * 2 * kW + 2 * x + 1] = static_cast<uint8_t>(x % 2 ? 200 : 50);  // V / U
    }
  }
  auto grey = ConvertToGrey({PixelFormat::kYuyv, kW, kH, 0}, buffer.data(), buffer.size());
  ASSERT_TRUE(grey.ok()) << grey.error();
  ExpectPattern(*grey, kW, kH);
}

TEST(PixelFormat, Nv12ReadsTheLumaPlane) {
  std::vector<uint8_t> buffer(kW * kH * 3 / 2, 128);
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) buffer[y * kW + x] = Pattern(x, y);
  auto grey = ConvertToGrey({PixelFormat::kNv12, kW, kH, kW}, buffer.data(), buffer.size());
  ASSERT_TRUE(grey.ok()) << grey.error();
  ExpectPattern(*grey, kW, kH);
}

TEST(PixelFormat, Y10AndY16KeepTheHighBits) {
  std::vector<uint8_t> y10(2 * kW * kH), y16(2 * kW * kH);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const int i = 2 * (y * kW + x);
      // 10-bit value whose top 8 bits are the pattern and low 2 bits are noise.
      const unsigned v10 = (Pattern(x, y) << 2) | static_cast<unsigned>((x + y) % 4);
      y10[i] = static_cast<uint8_t>(v10 & 0xff);
      y10[i + 1] = static_cast<uint8_t>(v10 >> 8);
      const unsigned v16 = (Pattern(x, y) << 8) | static_cast<unsigned>(37 * x + y);
      y16[i] = static_cast<uint8_t>(v16 & 0xff);
      y16[i + 1] = static_cast<uint8_t>(v16 >> 8);
    }
  }
  auto a = ConvertToGrey({PixelFormat::kY10, kW, kH, 0}, y10.data(), y10.size());
  ASSERT_TRUE(a.ok()) << a.error();
  ExpectPattern(*a, kW, kH);
  auto b = ConvertToGrey({PixelFormat::kY16, kW, kH, 0}, y16.data(), y16.size());
  ASSERT_TRUE(b.ok()) << b.error();
  ExpectPattern(*b, kW, kH);
}

TEST(PixelFormat, Bgr24UsesLumaWeights) {
  // A pure green pixel: BT.601 luma 0.587 * 200 = 117.4.
  const std::vector<uint8_t> bgr = {0, 200, 0, 0, 200, 0};
  auto grey = ConvertToGrey({PixelFormat::kBgr24, 2, 1, 0}, bgr.data(), bgr.size());
  ASSERT_TRUE(grey.ok()) << grey.error();
  EXPECT_NEAR(grey->at<uint8_t>(0, 0), 117.4, 1.0);
  // Pure red in memory order R,G,B (RGB24) and B,G,R (BGR24): luma 0.299 * 200 = 59.8.
  const std::vector<uint8_t> rgb = {200, 0, 0}, red_bgr = {0, 0, 200};
  auto a = ConvertToGrey({PixelFormat::kRgb24, 1, 1, 0}, rgb.data(), rgb.size());
  auto b = ConvertToGrey({PixelFormat::kBgr24, 1, 1, 0}, red_bgr.data(), red_bgr.size());
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_NEAR(a->at<uint8_t>(0, 0), 59.8, 1.0);
  EXPECT_NEAR(b->at<uint8_t>(0, 0), 59.8, 1.0);
}

TEST(PixelFormat, MjpegDecodes) {
  // A smooth image survives JPEG at quality 100 within a few grey levels.
  cv::Mat image(32, 48, CV_8UC1);
  for (int y = 0; y < image.rows; ++y)
    for (int x = 0; x < image.cols; ++x) image.at<uint8_t>(y, x) = static_cast<uint8_t>(2 * x + y);
  std::vector<uint8_t> jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", image, jpeg, {cv::IMWRITE_JPEG_QUALITY, 100}));
  auto grey = ConvertToGrey({PixelFormat::kMjpeg, 48, 32, 0}, jpeg.data(), jpeg.size());
  ASSERT_TRUE(grey.ok()) << grey.error();
  EXPECT_LE(cv::norm(*grey, image, cv::NORM_INF), 4.0);
  // The wrong size and garbage are errors, not crashes.
  auto wrong = ConvertToGrey({PixelFormat::kMjpeg, 64, 32, 0}, jpeg.data(), jpeg.size());
  ASSERT_FALSE(wrong.ok());
  EXPECT_NE(wrong.error().find("decoded 48x32"), std::string::npos) << wrong.error();
  const std::vector<uint8_t> garbage(100, 0x42);
  EXPECT_FALSE(
      ConvertToGrey({PixelFormat::kMjpeg, 48, 32, 0}, garbage.data(), garbage.size()).ok());
}

TEST(PixelFormat, ShortBufferAndBadLayoutAreErrors) {
  std::vector<uint8_t> buffer(kW * kH - 1);
  auto short_buffer = ConvertToGrey({PixelFormat::kGrey, kW, kH, 0}, buffer.data(), buffer.size());
  ASSERT_FALSE(short_buffer.ok());
  EXPECT_NE(short_buffer.error().find("needs 24"), std::string::npos) << short_buffer.error();
  EXPECT_FALSE(ConvertToGrey({PixelFormat::kYuyv, kW, kH, kW}, buffer.data(), buffer.size()).ok());
  EXPECT_FALSE(ConvertToGrey({PixelFormat::kGrey, 0, kH, 0}, buffer.data(), buffer.size()).ok());
}

TEST(PixelFormat, NamesAndFourccs) {
  EXPECT_EQ(ParsePixelFormat("yuyv"), PixelFormat::kYuyv);
  EXPECT_EQ(ParsePixelFormat("MJPG"), PixelFormat::kMjpeg);
  EXPECT_FALSE(ParsePixelFormat("RGB3").has_value());
  EXPECT_EQ(V4l2Fourcc(PixelFormat::kY10), V4L2_PIX_FMT_Y10);
  EXPECT_EQ(FromV4l2Fourcc(V4L2_PIX_FMT_NV12), PixelFormat::kNv12);
  EXPECT_EQ(FromV4l2Fourcc(V4L2_PIX_FMT_JPEG), PixelFormat::kMjpeg);
  EXPECT_FALSE(FromV4l2Fourcc(V4L2_PIX_FMT_RGB565).has_value());
  EXPECT_EQ(FourccText(V4L2_PIX_FMT_YUYV), "YUYV");
  EXPECT_EQ(FourccText(V4L2_PIX_FMT_Y10), "Y10");
}

}  // namespace
}  // namespace rigcal::capture
