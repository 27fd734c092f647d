// SPDX-License-Identifier: Apache-2.0
// Sub-pixel consistency of the simulated rig's images with its camera models, on the rendered
// sequences of the shipped configs: corners are detected in one frame, the 3D point each one
// sees is found by casting its ray into the scene at the true pose, and the point is projected
// through the camera model into the following frames at their true poses. Pyramidal KLT
// (OpenCV, tight convergence) tracks the corners frame to frame; the difference between the
// tracked and the projected positions is the renderer's inconsistency plus the tracker's error.
// Between consecutive frames its mean (a systematic shift would bias every VO) and its median
// must stay at the level KLT reaches on textured images (a few hundredths of a pixel).

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <opencv2/features2d.hpp>
#include <opencv2/video/tracking.hpp>

#include "rigcal/base/robust_statistics.h"
#include "rigcal/sim/simulated_rig.h"
#include "sim/shipped_sim_rig.h"

namespace rigcal::sim {
namespace {

struct TrackStats {
  int tracks = 0;              // corner tracks that survived all frames
  Eigen::Vector2d mean_error;  // tracked - projected after the last frame, pixels
  double rms_error = 0.0;      // pixels
  double median_error = 0.0;   // pixels
};

// Tracks corners of frame `first` over `frames` frames of camera `camera`; `noise` false
// renders noise-free views (RenderView) instead of the device's frames.
TrackStats TrackAgainstProjection(const SimulatedRig& rig, int camera, int64_t first, int frames,
                                  bool noise) {
  const camera::CameraModel& model = *rig.spec().cameras[camera];
  auto pose = [&](int64_t k) { return rig.WorldFromCameraAt(camera, rig.FrameStreamTime(k)); };
  auto image = [&](int64_t k) {
    return noise ? rig.RenderFrame(camera, k) : rig.RenderView(camera, pose(k));
  };
  cv::Mat previous = image(first);
  std::vector<cv::KeyPoint> corners;
  cv::FAST(previous, corners, 20, true);
  cv::KeyPointsFilter::retainBest(corners, 400);
  std::vector<cv::Point2f> points;
  std::vector<Eigen::Vector3d> world;
  const Pose p0 = pose(first);
  for (const cv::KeyPoint& c : corners) {
    if (c.pt.x < 20 || c.pt.y < 20 || c.pt.x > previous.cols - 20 || c.pt.y > previous.rows - 20) {
      continue;
    }
    const auto bearing = model.Unproject(Eigen::Vector2d(c.pt.x, c.pt.y));
    if (!bearing) continue;
    const Eigen::Vector3d d = p0.R() * bearing->normalized();
    const auto t = rig.CastRay(p0.C, d);
    if (!t) continue;
    // Skip corners on depth edges: their neighbours must see nearly the same depth.
    bool edge = false;
    for (const Eigen::Vector2d& o : {Eigen::Vector2d(3, 0), Eigen::Vector2d(-3, 0),
                                     Eigen::Vector2d(0, 3), Eigen::Vector2d(0, -3)}) {
      const auto nb = model.Unproject(Eigen::Vector2d(c.pt.x, c.pt.y) + o);
      const auto tn = nb ? rig.CastRay(p0.C, p0.R() * nb->normalized()) : std::nullopt;
      edge = edge || !tn || std::abs(*tn - *t) > 0.05 * *t;
    }
    if (edge) continue;
    points.push_back(c.pt);
    world.push_back(p0.C + *t * d);
  }
  std::vector<char> alive(points.size(), 1);
  const cv::TermCriteria criteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 50, 0.001);
  for (int f = 1; f <= frames; ++f) {
    const cv::Mat current = image(first + f);
    std::vector<cv::Point2f> next = points;
    std::vector<unsigned char> ok;
    std::vector<float> error;
    cv::calcOpticalFlowPyrLK(previous, current, points, next, ok, error, cv::Size(15, 15), 2,
                             criteria);
    for (size_t i = 0; i < points.size(); ++i) alive[i] = alive[i] && ok[i];
    points = next;
    previous = current;
  }
  TrackStats stats;
  stats.mean_error.setZero();
  std::vector<double> norms;
  double sum2 = 0.0;
  const Pose last = pose(first + frames);
  for (size_t i = 0; i < points.size(); ++i) {
    if (!alive[i]) continue;
    const Eigen::Vector3d in_camera = last.R().transpose() * (world[i] - last.C);
    const auto px = model.Project(in_camera);
    if (!px) continue;
    const Eigen::Vector2d e = Eigen::Vector2d(points[i].x, points[i].y) - *px;
    if (e.norm() > 3.0) continue;  // lost on an occlusion or a repeated pattern
    stats.mean_error += e;
    sum2 += e.squaredNorm();
    norms.push_back(e.norm());
    ++stats.tracks;
  }
  if (stats.tracks == 0) return stats;
  stats.mean_error /= stats.tracks;
  stats.rms_error = std::sqrt(sum2 / stats.tracks);
  stats.median_error = UpperMedian(std::move(norms));
  return stats;
}

void ExpectConsistent(const std::string& file) {
  const SimulatedRig rig = testing::LoadShippedSimulatedRig(file);
  for (int camera = 0; camera < rig.num_cameras(); ++camera) {
    for (bool noise : {false, true}) {
      // One frame: the images must agree with the model to KLT's sub-pixel accuracy. Over
      // 5 and 10 frames the patches deform (zoom, perspective) and translation-only KLT
      // drifts: printed, as the front-end error the VO has to live with.
      for (int frames : {1, 5, 10}) {
        const TrackStats s = TrackAgainstProjection(rig, camera, 40, frames, noise);
        std::printf(
            "%s camera %d (%s): %d tracks over %2d frame(s), tracked - projected: mean (%6.3f, "
            "%6.3f) px, rms %.3f px, median %.3f px\n",
            file.c_str(), camera, noise ? "noise 1.5" : "no noise ", s.tracks, frames,
            s.mean_error.x(), s.mean_error.y(), s.rms_error, s.median_error);
        EXPECT_GE(s.tracks, 50) << file << " camera " << camera;
        if (frames != 1) continue;
        // A systematic shift (wrong principal point, half-pixel convention, texture offset)
        // shows in the mean; 0.03 px is 3 sigma of the mean of ~300 tracks at 0.15 px rms.
        EXPECT_LT(s.mean_error.norm(), 0.03) << file << " camera " << camera;
        // Per track: pyramidal KLT on these textures reaches a few hundredths of a pixel.
        EXPECT_LT(s.median_error, 0.08) << file << " camera " << camera;
      }
    }
  }
}

TEST(RenderedTrackConsistency, ThesisVirtualPinhole) {
  ExpectConsistent("sim_thesis_virtual.yaml");
}

TEST(RenderedTrackConsistency, SewerFisheye) { ExpectConsistent("sim_sewer.yaml"); }

TEST(RenderedTrackConsistency, SphericalScaramuzza) { ExpectConsistent("sim_spherical.yaml"); }

}  // namespace
}  // namespace rigcal::sim
