// SPDX-License-Identifier: Apache-2.0
// Writes the binary seed corpora of the LCM fuzz targets from the fixtures of tests/lcm: a valid
// message of every type (and a few that lie about their sizes) into
// <dir>/lcm_<type>/, and small LCM logs into <dir>/lcm_log/.
//   fuzz_write_seeds tests/fuzz/corpus

#include <cstdio>
#include <fstream>
#include <string>
#include <vector>

#include "lcm/message_fixtures.h"
#include "rigcal/lcm/log_writer.h"

namespace rigcal::lcm::lcm_test {
namespace {

void WriteFile(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
  if (!out) {
    std::fprintf(stderr, "cannot write %s\n", path.c_str());
    std::exit(1);
  }
}

std::vector<uint8_t> Log(const std::vector<std::pair<std::string, std::vector<uint8_t>>>& events,
                         const std::string& path) {
  std::remove(path.c_str());
  auto writer = lcm::LogWriter::Open(path);
  if (!writer) {
    std::fprintf(stderr, "%s\n", writer.error().c_str());
    std::exit(1);
  }
  int64_t utime = 1'700'000'000'000;
  for (const auto& [channel, data] : events) {
    if (!(*writer)->Write(channel, utime, data.data(), data.size()).ok()) std::exit(1);
    utime += 33'000;
  }
  if (!(*writer)->Close().ok()) std::exit(1);
  std::ifstream in(path, std::ios::binary);
  return std::vector<uint8_t>(std::istreambuf_iterator<char>(in), {});
}

}  // namespace
}  // namespace rigcal::lcm::lcm_test

int main(int argc, char** argv) {
  using namespace rigcal;
  using namespace rigcal::lcm::lcm_test;
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <corpus dir>\n", argv[0]);
    return 2;
  }
  const std::string dir = argv[1];
  const auto pose = Encode("RIGCAL_POSE_left", MakePoseMsg());
  camera_pose_t no_cov = MakePoseMsg("front");
  no_cov.has_covariance = false;
  const auto pose_front = Encode("RIGCAL_POSE_front", no_cov);
  WriteFile(dir + "/lcm_camera_pose/valid", pose);
  WriteFile(dir + "/lcm_camera_pose/valid_no_covariance", pose_front);
  std::vector<uint8_t> lying = pose;
  PutInt32(&lying, kPoseCameraLength, 1 << 30);
  WriteFile(dir + "/lcm_camera_pose/camera_length_lies", lying);

  const rig_extrinsics_t extrinsics_msg = MakeExtrinsicsMsg();
  const auto extrinsics = Encode("RIGCAL_EXTRINSICS", extrinsics_msg);
  WriteFile(dir + "/lcm_rig_extrinsics/valid", extrinsics);
  lying = extrinsics;
  PutInt32(&lying, ExtrinsicsNumSlavesOffset(extrinsics_msg), 3);
  WriteFile(dir + "/lcm_rig_extrinsics/num_slaves_lies", lying);

  const auto status = Encode("RIGCAL_STATUS", MakeStatusMsg());
  WriteFile(dir + "/lcm_rig_status/valid", status);

  const image_t image_msg = MakeImageMsg();
  const auto image = Encode("RIGCAL_IMAGE_back", image_msg);
  WriteFile(dir + "/lcm_image/valid_grey", image);
  lying = image;
  PutInt32(&lying, ImageSizeOffset(image_msg), 1 << 30);
  WriteFile(dir + "/lcm_image/size_lies", lying);
  image_t rgb = image_msg;
  rgb.pixel_format = "RGB3";
  rgb.stride = 12;
  rgb.data.assign(36, 7);
  rgb.size = 36;
  WriteFile(dir + "/lcm_image/valid_rgb", Encode("RIGCAL_IMAGE_back", rgb));
  image_t yuyv = rgb;
  yuyv.pixel_format = "YUYV";
  yuyv.stride = 8;
  yuyv.data.assign(24, 9);
  yuyv.size = 24;
  WriteFile(dir + "/lcm_image/valid_yuyv", Encode("RIGCAL_IMAGE_back", yuyv));
  image_t y16 = yuyv;
  y16.pixel_format = "Y16 ";
  WriteFile(dir + "/lcm_image/valid_y16", Encode("RIGCAL_IMAGE_back", y16));
  // A 4x3 grey PNG (as `rigcal record --image-encoding png` stores it).
  const std::vector<uint8_t> png = {
      0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0x00, 0x00, 0x00, 0x0d, 0x49, 0x48,
      0x44, 0x52, 0x00, 0x00, 0x00, 0x04, 0x00, 0x00, 0x00, 0x03, 0x08, 0x00, 0x00, 0x00,
      0x00, 0x91, 0x9f, 0xf1, 0x1a, 0x00, 0x00, 0x00, 0x17, 0x49, 0x44, 0x41, 0x54, 0x78,
      0xda, 0x63, 0x60, 0x10, 0x54, 0x32, 0x66, 0x70, 0x09, 0x4d, 0x2b, 0x67, 0xe8, 0x98,
      0xb9, 0x6a, 0x37, 0x00, 0x15, 0x4f, 0x04, 0x63, 0x11, 0x8d, 0x33, 0x68, 0x00, 0x00,
      0x00, 0x00, 0x49, 0x45, 0x4e, 0x44, 0xae, 0x42, 0x60, 0x82};
  image_t png_msg = image_msg;
  png_msg.encoding = image_t::ENCODING_PNG;
  png_msg.stride = 0;
  png_msg.data = png;
  png_msg.size = static_cast<int32_t>(png.size());
  WriteFile(dir + "/lcm_image/valid_png", Encode("RIGCAL_IMAGE_back", png_msg));

  const std::string tmp = dir + "/lcm_log/.tmp.lcmlog";
  WriteFile(dir + "/lcm_log/poses_and_status", Log({{"RIGCAL_POSE_front", pose_front},
                                                    {"RIGCAL_POSE_left", pose},
                                                    {"RIGCAL_STATUS", status},
                                                    {"RIGCAL_EXTRINSICS", extrinsics}},
                                                   tmp));
  WriteFile(dir + "/lcm_log/image", Log({{"RIGCAL_IMAGE_back", image}}, tmp));
  std::remove(tmp.c_str());
  return 0;
}
