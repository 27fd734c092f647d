// SPDX-License-Identifier: Apache-2.0
// ImageFolderDevice: EuRoC camera folders, including the real static EuRoC frames whose cam1
// index lists 4 images that do not exist, and damaged CSV files / images; plain folders of
// images stamped by a rate or a timestamps file, in 8 and 16 bits, grey and colour.

#include "rigcal/capture/image_folder_device.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "support/skip.h"

namespace rigcal::capture {
namespace {

const std::string kEuroc = std::string(RIGCAL_SHARED_DATA_DIR) + "/euroc_v101_static/mav0";

// Reads every frame; fails the test on an error.
std::vector<Frame> GrabAll(ImageFolderDevice* device) {
  std::vector<Frame> frames;
  for (;;) {
    auto grabbed = device->Grab();
    EXPECT_TRUE(grabbed.ok()) << grabbed.error();
    if (!grabbed.ok() || !grabbed->has_value()) break;
    frames.push_back(std::move(**grabbed));
  }
  return frames;
}

TEST(ImageFolderDevice, EurocCam1ReportsExactlyTheFourMissingImages) {
  if (!std::filesystem::exists(kEuroc + "/cam1/data.csv")) RIGCAL_SKIP_MISSING() << "no " << kEuroc;
  auto opened = ImageFolderDevice::Open(kEuroc + "/cam1", "cam1", 1);
  ASSERT_TRUE(opened.ok()) << opened.error();
  ImageFolderDevice& device = **opened;
  EXPECT_EQ(device.name(), "cam1");
  EXPECT_NEAR(device.frame_rate_hz(), 20.0, 0.01);
  EXPECT_EQ(device.size(), 99u);
  EXPECT_TRUE(device.csv_problems().empty());
  std::vector<std::string> expected;
  for (const char* stamp : {"1403715278012143104", "1403715278062142976", "1403715278112143104",
                            "1403715278162142976"}) {
    expected.push_back(
        (std::filesystem::path(kEuroc) / "cam1" / "data" / (std::string(stamp) + ".png")).string());
  }
  EXPECT_EQ(device.skipped_files(), expected);

  const std::vector<Frame> frames = GrabAll(&device);
  ASSERT_EQ(frames.size(), 95u);
  for (size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i].camera, 1);
    EXPECT_EQ(frames[i].image.type(), CV_8UC1);
    EXPECT_EQ(frames[i].image.cols, 752);
    EXPECT_EQ(frames[i].image.rows, 480);
    EXPECT_EQ(frames[i].seq, static_cast<int64_t>(i));
    if (i > 0) {
      EXPECT_GT(frames[i].t_ns, frames[i - 1].t_ns);
    }
  }
  EXPECT_EQ(frames.front().t_ns, 1403715273262142976);
  EXPECT_EQ(device.skipped_count(), 4u);  // nothing new at Grab
  auto end = device.Grab();
  ASSERT_TRUE(end.ok());
  EXPECT_FALSE(end->has_value());
}

TEST(ImageFolderDevice, EurocCam0IsComplete) {
  if (!std::filesystem::exists(kEuroc + "/cam0/data.csv")) RIGCAL_SKIP_MISSING() << "no " << kEuroc;
  auto opened = ImageFolderDevice::Open(kEuroc + "/cam0", "cam0", 0);
  ASSERT_TRUE(opened.ok()) << opened.error();
  EXPECT_EQ(GrabAll(opened->get()).size(), 95u);
  EXPECT_EQ((*opened)->skipped_count(), 0u);
}

class TempFolder : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() /
           ("rigcal_image_folder_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_ / "data");
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  void WriteCsv(const std::string& text) { std::ofstream(dir_ / "data.csv") << text; }
  void WriteImage(const std::string& file, int value) {
    const cv::Mat image(24, 32, CV_8UC1, cv::Scalar(value));
    // A binary PGM, which cv::imread reads like a PNG.
    std::ofstream out(dir_ / "data" / file, std::ios::binary);
    out << "P5\n32 24\n255\n";
    out.write(reinterpret_cast<const char*>(image.data), image.total());
  }
  std::filesystem::path dir_;
};

TEST_F(TempFolder, BadLinesAreNamedAndSkipped) {
  WriteImage("a.pgm", 10);
  WriteImage("b.pgm", 20);
  WriteImage("c.pgm", 30);
  WriteCsv(
      "#timestamp [ns],filename\r\n"
      "100,a.pgm\r\n"
      "not-a-number,b.pgm\n"
      "200\n"
      "\n"
      "150,b.pgm\n"
      "50,c.pgm\n"
      "300, c.pgm \n");
  auto opened = ImageFolderDevice::Open(dir_.string(), "cam", 2, 10.0);
  ASSERT_TRUE(opened.ok()) << opened.error();
  const auto& problems = (*opened)->csv_problems();
  ASSERT_EQ(problems.size(), 3u);
  const std::string csv = (dir_ / "data.csv").string();
  EXPECT_EQ(problems[0].rfind(csv + ":3:", 0), 0u) << problems[0];
  EXPECT_EQ(problems[1].rfind(csv + ":4:", 0), 0u) << problems[1];
  EXPECT_EQ(problems[2].rfind(csv + ":7:", 0), 0u) << problems[2];  // 50 after 150
  EXPECT_DOUBLE_EQ((*opened)->frame_rate_hz(), 10.0);
  const std::vector<Frame> frames = GrabAll(opened->get());
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_EQ(frames[0].t_ns, 100);
  EXPECT_EQ(frames[1].t_ns, 150);
  EXPECT_EQ(frames[2].t_ns, 300);
  EXPECT_EQ(frames[2].image.at<unsigned char>(0, 0), 30);
  EXPECT_EQ(frames[2].camera, 2);
}

TEST_F(TempFolder, UnreadableAndMissingImagesAreSkippedAndListed) {
  WriteImage("a.pgm", 10);
  std::ofstream(dir_ / "data" / "broken.png") << "this is not a png";
  WriteImage("c.pgm", 30);
  WriteCsv("1000,a.pgm\n2000,broken.png\n3000,gone.png\n4000,c.pgm\n");
  auto opened = ImageFolderDevice::Open(dir_.string(), "cam", 0);
  ASSERT_TRUE(opened.ok()) << opened.error();
  ImageFolderDevice& device = **opened;
  EXPECT_NEAR(device.frame_rate_hz(), 1e6, 1e-6);
  ASSERT_EQ(device.skipped_count(), 1u);  // the missing one, known at Open
  const std::vector<Frame> frames = GrabAll(&device);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].seq, 0);
  EXPECT_EQ(frames[1].seq, 3);  // the gap shows the skipped frames
  const std::vector<std::string> skipped = device.skipped_files();
  ASSERT_EQ(skipped.size(), 2u);
  EXPECT_EQ(skipped[0], (dir_ / "data" / "gone.png").string());
  EXPECT_EQ(skipped[1], (dir_ / "data" / "broken.png").string());
}

TEST_F(TempFolder, MissingOrEmptyIndexIsAnError) {
  auto missing = ImageFolderDevice::Open(dir_.string(), "cam", 0);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(missing.error().find("data.csv"), std::string::npos);
  WriteCsv("#timestamp [ns],filename\n");
  auto empty = ImageFolderDevice::Open(dir_.string(), "cam", 0);
  ASSERT_FALSE(empty.ok());
  EXPECT_NE(empty.error().find("no valid image"), std::string::npos);
}

TEST_F(TempFolder, InterruptEndsTheStream) {
  WriteImage("a.pgm", 10);
  WriteCsv("1,a.pgm\n2,a.pgm\n");
  auto opened = ImageFolderDevice::Open(dir_.string(), "cam", 0);
  ASSERT_TRUE(opened.ok());
  (*opened)->Interrupt();
  auto grabbed = (*opened)->Grab();
  ASSERT_TRUE(grabbed.ok());
  EXPECT_FALSE(grabbed->has_value());
}

// A plain folder: images of any name in natural order (frame2 before frame10), other files
// ignored, stamped at the rate.
TEST_F(TempFolder, PlainFolderInNaturalOrderAtTheRate) {
  const std::filesystem::path plain = dir_ / "data";
  for (const auto& [name, value] : std::vector<std::pair<std::string, int>>{
           {"frame10.pgm", 30}, {"frame2.pgm", 20}, {"frame1.pgm", 10}}) {
    WriteImage(name, value);
  }
  std::ofstream(plain / "notes.txt") << "not an image";
  auto none = ImageFolderDevice::Open(plain.string(), "cam", 0);
  ASSERT_FALSE(none.ok());
  EXPECT_NE(none.error().find("needs rate_hz or a timestamps file"), std::string::npos)
      << none.error();
  auto opened = ImageFolderDevice::Open(plain.string(), "cam", 1, 25.0);
  ASSERT_TRUE(opened.ok()) << opened.error();
  EXPECT_EQ((*opened)->size(), 3u);
  EXPECT_DOUBLE_EQ((*opened)->frame_rate_hz(), 25.0);
  EXPECT_NE((*opened)->layout().find("plain folder"), std::string::npos);
  const std::vector<Frame> frames = GrabAll(opened->get());
  ASSERT_EQ(frames.size(), 3u);
  for (size_t i = 0; i < frames.size(); ++i) {
    EXPECT_EQ(frames[i].t_ns, static_cast<int64_t>(i) * 40'000'000);
    EXPECT_EQ(frames[i].image.at<unsigned char>(0, 0), 10 * (i + 1));
    EXPECT_EQ(frames[i].seq, static_cast<int64_t>(i));
    EXPECT_EQ(frames[i].camera, 1);
  }
}

// A timestamps file: nanoseconds or seconds with a decimal point (exact), optionally naming each
// image; a file that does not fit the folder is an error naming the file.
TEST_F(TempFolder, PlainFolderStampedByATimestampsFile) {
  const std::filesystem::path plain = dir_ / "data";
  WriteImage("a.pgm", 10);
  WriteImage("b.pgm", 20);
  const std::string stamps = (dir_ / "stamps.txt").string();
  ImageFolderOptions options;
  options.rate_hz = 99.0;  // the file wins
  options.timestamps_file = stamps;
  std::ofstream(stamps) << "# t\n1403636579.763555584 a.pgm\n1403636579.8135 b.pgm\n";
  auto opened = ImageFolderDevice::Open(plain.string(), "cam", 0, options);
  ASSERT_TRUE(opened.ok()) << opened.error();
  const std::vector<Frame> frames = GrabAll(opened->get());
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].t_ns, 1403636579763555584);
  EXPECT_EQ(frames[1].t_ns, 1403636579813500000);
  EXPECT_NEAR((*opened)->frame_rate_hz(), 1e9 / 49944416.0, 1e-6);

  std::ofstream(stamps, std::ios::trunc) << "100\n200\n";
  auto by_ns = ImageFolderDevice::Open(plain.string(), "cam", 0, options);
  ASSERT_TRUE(by_ns.ok()) << by_ns.error();
  EXPECT_EQ(GrabAll(by_ns->get()).back().t_ns, 200);

  const std::vector<std::pair<std::string, std::string>> bad = {
      {"100\n", "1 stamps for 2 images"},
      {"100 b.pgm\n200 a.pgm\n", "stamp 1 names b.pgm, but image 1 in name order is a.pgm"},
      {"200\n100\n", "stamps.txt:2: stamp 100 not after the previous one"},
      {"1e9\n2e9\n", "stamps.txt:1: bad stamp \"1e9\""}};
  for (const auto& [text, expected] : bad) {
    std::ofstream(stamps, std::ios::trunc) << text;
    auto rejected = ImageFolderDevice::Open(plain.string(), "cam", 0, options);
    ASSERT_FALSE(rejected.ok()) << text;
    EXPECT_NE(rejected.error().find(expected), std::string::npos) << rejected.error();
  }
}

// Colour and 16-bit images arrive as CV_8UC1; a 12-bit image in 16-bit words is scaled by its
// bit depth (found on the first image, kept for the others), so 4095 becomes 255.
TEST_F(TempFolder, ColourAnd16BitImagesBecome8BitGrey) {
  const std::filesystem::path plain = dir_ / "data";
  cv::Mat colour(24, 32, CV_8UC3, cv::Scalar(200, 100, 50));
  ASSERT_TRUE(cv::imwrite((plain / "0.png").string(), colour));
  auto opened = ImageFolderDevice::Open(plain.string(), "cam", 0, 10.0);
  ASSERT_TRUE(opened.ok()) << opened.error();
  std::vector<Frame> frames = GrabAll(opened->get());
  ASSERT_EQ(frames.size(), 1u);
  ASSERT_EQ(frames[0].image.type(), CV_8UC1);
  EXPECT_NEAR(frames[0].image.at<unsigned char>(0, 0), 0.114 * 200 + 0.587 * 100 + 0.299 * 50, 1);

  std::filesystem::remove(plain / "0.png");
  cv::Mat twelve_bit(24, 32, CV_16UC1, cv::Scalar(4095));
  twelve_bit(cv::Rect(0, 0, 16, 24)).setTo(2048);
  ASSERT_TRUE(cv::imwrite((plain / "0.png").string(), twelve_bit));
  ASSERT_TRUE(cv::imwrite((plain / "1.png").string(), cv::Mat(24, 32, CV_16UC1, cv::Scalar(1023))));
  auto deep = ImageFolderDevice::Open(plain.string(), "cam", 0, 10.0);
  ASSERT_TRUE(deep.ok()) << deep.error();
  frames = GrabAll(deep->get());
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].image.at<unsigned char>(0, 31), 255);
  EXPECT_EQ(frames[0].image.at<unsigned char>(0, 0), 128);
  EXPECT_EQ(frames[1].image.at<unsigned char>(0, 0), 64);  // the same scale: 1023 * 255 / 4095
}

}  // namespace
}  // namespace rigcal::capture
