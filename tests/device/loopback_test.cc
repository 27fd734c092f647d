// The customer's whole path through the real V4L2 API: a simulated two-camera rig renders its
// frames, a writer feeds them to two v4l2loopback devices (GREY and YUYV), the V4L2 source
// captures them (mmap streaming, kernel stamps), and the live Pipeline runs VO per camera and the
// online calibrator. The calibration must converge as in simulation; its errors against the
// simulated truth are printed (figures for the issue note).
//
// The writer paces itself by the pipeline: frame k+1 is written once both cameras have
// processed frame k (at least kMinPeriodMs apart), so emulation speed does not drop frames.
// The poses are stamped by the kernel at the write; the test maps each stamp back to the frame
// the writer wrote then, to score the run against the simulated truth (EvaluateRun).

#include <fcntl.h>
#include <gtest/gtest.h>
#include <linux/videodev2.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <fstream>
#include <thread>
#include <vector>

#include "guest_skip.h"
#include "rigcal/drivers/v4l2_device.h"
#include "rigcal/drivers/v4l2_timestamp.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/pipeline/pipeline.h"
#include "rigcal/pipeline/run_evaluation.h"

namespace rigcal::tools {
namespace {

constexpr int kWidth = 320;
constexpr int kHeight = 240;
constexpr int kFrames = 240;
constexpr int kMinPeriodMs = 60;  // > sync.tolerance (25 ms): consecutive sets stay apart

const char* kRig =
    "rig: {name: loopback, master: cam0}\n"
    "cameras:\n"
    "  - {name: cam0, model: pinhole, resolution: [320, 240], intrinsics: [200, 200, 159.5, "
    "119.5]}\n"
    "  - name: cam1\n"
    "    model: pinhole\n"
    "    resolution: [320, 240]\n"
    "    intrinsics: [200, 200, 159.5, 119.5]\n"
    "    truth: {q_wxyz: [0.70710678118654752, 0, 0.70710678118654752, 0], C: [0.5, 0, 0]}\n"
    "sync: {frame_rate_hz: 20}\n"
    "source:\n"
    "  type: simulated\n"
    "  frame_rate_hz: 20\n"
    "  num_frames: 240\n"
    "  seed: 3\n"
    "  realtime: false\n"
    "  scene: {type: room, size: [20, 16, 6], boxes: 10}\n"
    "  trajectory:\n"
    "    waypoint_interval_s: 2\n"
    "    waypoints:\n"
    "      - {p: [-3.0, 0.0, 3.0], ypr_deg: [0, 0, 0]}\n"
    "      - {p: [-2.3, 0.8, 3.2], ypr_deg: [20, -10, 8]}\n"
    "      - {p: [-1.4, 1.5, 3.0], ypr_deg: [38, 5, -6]}\n"
    "      - {p: [-0.4, 1.2, 2.8], ypr_deg: [15, 15, -15]}\n"
    "      - {p: [0.5, 0.4, 3.1], ypr_deg: [-10, 0, 5]}\n"
    "      - {p: [1.2, -0.6, 3.4], ypr_deg: [-35, -15, 12]}\n"
    "      - {p: [0.8, -1.6, 3.1], ypr_deg: [-20, 8, 18]}\n";

// The writer side of one loopback device.
class LoopbackWriter {
 public:
  LoopbackWriter(const std::string& node, drivers::PixelFormat format) : format_(format) {
    fd_ = open(node.c_str(), O_RDWR);
    EXPECT_GE(fd_, 0) << node << ": " << std::strerror(errno);
    v4l2_format f{};
    f.type = V4L2_BUF_TYPE_VIDEO_OUTPUT;
    f.fmt.pix.width = kWidth;
    f.fmt.pix.height = kHeight;
    f.fmt.pix.pixelformat = drivers::V4l2Fourcc(format);
    f.fmt.pix.field = V4L2_FIELD_NONE;
    const int bpp = format == drivers::PixelFormat::kYuyv ? 2 : 1;
    f.fmt.pix.bytesperline = kWidth * bpp;
    f.fmt.pix.sizeimage = kWidth * kHeight * bpp;
    EXPECT_EQ(ioctl(fd_, VIDIOC_S_FMT, &f), 0) << node << ": S_FMT: " << std::strerror(errno);
    EXPECT_EQ(f.fmt.pix.pixelformat, drivers::V4l2Fourcc(format)) << node;
    bytes_.resize(f.fmt.pix.sizeimage);
  }
  ~LoopbackWriter() {
    if (fd_ >= 0) close(fd_);
  }
  bool Write(const cv::Mat& grey) {
    if (format_ == drivers::PixelFormat::kYuyv) {
      for (int y = 0; y < kHeight; ++y) {
        for (int x = 0; x < kWidth; ++x) {
          bytes_[2 * (y * kWidth + x)] = grey.at<uint8_t>(y, x);
          bytes_[2 * (y * kWidth + x) + 1] = 128;  // neutral chroma
        }
      }
    } else {
      for (int y = 0; y < kHeight; ++y) std::memcpy(&bytes_[y * kWidth], grey.ptr(y), kWidth);
    }
    return write(fd_, bytes_.data(), bytes_.size()) == static_cast<ssize_t>(bytes_.size());
  }

 private:
  int fd_ = -1;
  drivers::PixelFormat format_;
  std::vector<uint8_t> bytes_;
};

TEST(Loopback, SimulatedRigThroughV4l2Converges) {
  RIGCAL_REQUIRE_NODE("/dev/video20");
  RIGCAL_REQUIRE_NODE("/dev/video21");
  const std::string path = "/tmp/loopback_rig.yaml";
  std::ofstream(path) << kRig;
  auto config = LoadRigConfig(path);
  ASSERT_TRUE(config.ok()) << config.error();
  auto rig = drivers::MakeSimulatedRig(*config->simulated_source);
  ASSERT_TRUE(rig.ok()) << rig.error();

  LoopbackWriter writer0("/dev/video20", drivers::PixelFormat::kGrey);
  LoopbackWriter writer1("/dev/video21", drivers::PixelFormat::kYuyv);
  std::vector<int64_t> write_ns;  // CLOCK_MONOTONIC just before frame k was written
  auto write_frame = [&](int k) {
    const cv::Mat a = rig->RenderFrame(0, k);
    const cv::Mat b = rig->RenderFrame(1, k);
    write_ns.push_back(drivers::MonotonicNowNs());
    ASSERT_TRUE(writer0.Write(a));
    ASSERT_TRUE(writer1.Write(b));
  };
  write_frame(0);  // a loopback device offers formats to readers once its writer has written

  std::vector<std::unique_ptr<drivers::CameraDevice>> devices;
  std::vector<std::shared_ptr<const camera::CameraModel>> models;
  const drivers::PixelFormat formats[] = {drivers::PixelFormat::kGrey, drivers::PixelFormat::kYuyv};
  for (int i = 0; i < 2; ++i) {
    drivers::V4l2Options options;
    options.device = i == 0 ? "/dev/video20" : "/dev/video21";
    options.width = kWidth;
    options.height = kHeight;
    options.formats = {formats[i]};
    auto device = drivers::V4l2Device::Open(config->cameras[i].name, i, options);
    ASSERT_TRUE(device.ok()) << device.error();
    devices.push_back(std::move(*device));
    models.push_back(rig->spec().cameras[i]);
  }
  PipelineOptions options;
  options.record_poses = true;
  Pipeline pipeline(config->CameraNames(), std::move(devices), models, config->online, options);
  pipeline.Start();

  const auto started = std::chrono::steady_clock::now();
  auto both_caught_up = [&](int64_t captured_before) {
    const PipelineSnapshot s = pipeline.Snapshot();
    for (const CameraHealth& c : s.cameras) {
      if (c.frames_captured <= captured_before || c.frames_processed < c.frames_captured) {
        return false;
      }
    }
    return true;
  };
  int64_t stalls = 0;
  for (int k = 1; k < kFrames; ++k) {
    const int64_t captured_before = std::min(pipeline.Snapshot().cameras[0].frames_captured,
                                             pipeline.Snapshot().cameras[1].frames_captured);
    const auto earliest =
        std::chrono::steady_clock::now() + std::chrono::milliseconds(kMinPeriodMs);
    write_frame(k);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(2);
    while (!both_caught_up(captured_before) && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    if (std::chrono::steady_clock::now() >= deadline) ++stalls;
    std::this_thread::sleep_until(earliest);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  pipeline.Stop();
  const PipelineSnapshot snapshot = pipeline.Snapshot();
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  for (const CameraHealth& c : snapshot.cameras) {
    std::cout << "  " << c.name << ": " << c.frames_captured << " frames captured, "
              << c.frames_processed << " through VO, " << c.poses << " poses, " << c.dropped_backlog
              << " backlog drops, VO median " << c.vo_ms_median << " ms\n";
    EXPECT_FALSE(c.dead) << c.dead_reason;
    EXPECT_GE(c.frames_captured, kFrames * 9 / 10) << c.name;
  }
  std::cout << "  " << kFrames << " frames written in " << seconds << " s, " << stalls
            << " writes waited > 2 s for the pipeline\n";

  // Poses back on the simulation's clock: the frame written last before the kernel's stamp.
  std::vector<std::vector<CameraPose>> poses(2);
  for (int i = 0; i < 2; ++i) {
    for (CameraPose pose : pipeline.RecordedPoses(i)) {
      const auto after = std::upper_bound(write_ns.begin(), write_ns.end(), pose.t_ns);
      if (after == write_ns.begin()) continue;
      const auto k = static_cast<int64_t>(after - write_ns.begin()) - 1;
      pose.t_ns = rig->FrameTimeNs(k);
      poses[i].push_back(pose);
    }
  }
  const RigCalibration& result = snapshot.estimate.rig;
  ASSERT_EQ(result.slaves.size(), 1u);
  std::cout << "  cam1 state: " << ToString(result.slaves[0].state) << "\n";
  auto evaluation = EvaluateRun(*rig, poses, result);
  ASSERT_TRUE(evaluation.ok()) << evaluation.error();
  std::cout << FormatEvaluation(*evaluation);
  ASSERT_TRUE(result.slaves[0].usable()) << "the calibration did not converge";
  const CalibrationError& e = evaluation->slaves[0].error;
  std::cout << "RIGCAL-FIGURE loopback rot_deg=" << e.rot_deg << " dir_deg=" << e.dir_deg
            << " dist_pct=" << e.dist_pct << " scale_pct=" << e.scale_pct << "\n";
  // What the same drive gives in simulation (rigcal run --fast on this rig): well under these.
  EXPECT_LT(e.rot_deg, 1.0);
  EXPECT_LT(e.dir_deg, 5.0);
}

}  // namespace
}  // namespace rigcal::tools
