// SPDX-License-Identifier: Apache-2.0
// The simulated rig's SIMD texture kernels (SSE2 or NEON, whichever the build has) against the
// portable scalar ones: the same frames of the shipped simulated rigs rendered both ways must
// agree in every pixel within one grey level (the report gives the largest difference).
#include <gtest/gtest.h>

#include <cstdio>
#include <opencv2/core.hpp>
#include <string>

#include "rigcal/sim/simulated_rig.h"
#include "sim/shipped_sim_rig.h"

namespace rigcal::sim {
namespace {

struct Difference {
  double max = 0.0;    // grey levels
  int64_t pixels = 0;  // pixels that differ at all
  int64_t total = 0;
};

// Compares two 8-bit images of the same size pixel by pixel, accumulating into `difference`.
void Compare(const cv::Mat& simd, const cv::Mat& scalar, Difference* difference) {
  ASSERT_EQ(simd.size(), scalar.size());
  ASSERT_EQ(simd.type(), CV_8UC1);
  ASSERT_EQ(scalar.type(), CV_8UC1);
  cv::Mat diff;
  cv::absdiff(simd, scalar, diff);
  double max = 0.0;
  cv::minMaxLoc(diff, nullptr, &max);
  difference->max = std::max(difference->max, max);
  difference->pixels += cv::countNonZero(diff);
  difference->total += static_cast<int64_t>(diff.total());
}

// Frames spread over the run of every camera of the rig of `file`, as the devices render them
// (noise, blur) and noise-free at two render blocks, with both kernels.
void ExpectKernelsAgree(const std::string& file) {
  const SimulatedRig rig = testing::LoadShippedSimulatedRig(file);
  Difference frames, views;
  const int64_t n = rig.num_frames();
  for (const int64_t k : {int64_t{0}, n / 3, (2 * n) / 3, n - 1}) {
    for (int camera = 0; camera < rig.num_cameras(); ++camera) {
      const cv::Mat simd = rig.RenderFrame(camera, k, RenderKernel::kSimd);
      // Not a blank image: the comparison below has texture to compare.
      cv::Scalar mean, stddev;
      cv::meanStdDev(simd, mean, stddev);
      EXPECT_GT(stddev[0], 5.0) << file << " camera " << camera << " frame " << k;
      Compare(simd, rig.RenderFrame(camera, k, RenderKernel::kScalar), &frames);
      const Pose pose = rig.WorldFromCameraAt(camera, rig.FrameStreamTime(k));
      for (int block : {2, 8}) {
        Compare(rig.RenderView(camera, pose, block, RenderKernel::kSimd),
                rig.RenderView(camera, pose, block, RenderKernel::kScalar), &views);
      }
    }
  }
  for (const auto& [what, d] : {std::pair<const char*, Difference>{"frames", frames},
                                std::pair<const char*, Difference>{"views", views}}) {
    std::printf(
        "%s %s: %s vs scalar kernels: max difference %.0f grey level(s), %lld of %lld "
        "pixels differ\n",
        file.c_str(), what, SimdRenderKernelName(), d.max, static_cast<long long>(d.pixels),
        static_cast<long long>(d.total));
    EXPECT_GT(d.total, 0) << file << " " << what;
    EXPECT_LE(d.max, 1.0) << file << " " << what;
  }
}

TEST(SimRenderSimd, RoomPinholeKernelsAgree) { ExpectKernelsAgree("sim_thesis_virtual.yaml"); }

TEST(SimRenderSimd, PipeFisheyeKernelsAgree) { ExpectKernelsAgree("sim_sewer.yaml"); }

TEST(SimRenderSimd, YardWithSkyKernelsAgree) { ExpectKernelsAgree("sim_surround4.yaml"); }

}  // namespace
}  // namespace rigcal::sim
