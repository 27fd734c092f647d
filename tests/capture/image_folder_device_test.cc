// ImageFolderDevice: EuRoC camera folders, including the real static EuRoC frames whose cam1
// index lists 4 images that do not exist, and damaged CSV files / images.

#include "rigcal/capture/image_folder_device.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>

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

}  // namespace
}  // namespace rigcal::capture
