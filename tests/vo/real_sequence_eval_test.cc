// SPDX-License-Identifier: Apache-2.0
// MonocularVo on the real sequences of ../shared/data/real_mono (support/real_mono_sequence.h):
//  - visp_rbt_sequence (99 frames, metric AprilTag grid pose per frame): where the VO
//    initialises, the share of frames with a pose, and for frames 1, 5 and 10 apart the relative
//    rotation error, the translation direction error and the scale spread against the tag poses;
//    the tag poses' own noise floor (each tag's relative motion against the grid's); OpenCV's
//    ORB + 5-point (support/opencv_two_view.h) on the same pairs; the rotation error per camera
//    axis, and per axis the tags' and each estimator's own share of it (SplitRotationErrors); the
//    same against the tag poses refined with the tags' real layout on the board
//    (support/tag_grid_refinement.h), whose Cramér-Rao σ is the reference's own floor; the VO's
//    figure over RANSAC seeds 1-8; an offline bundle adjustment of all frames
//    (support/offline_bundle_adjustment.h: what the images allow, against the refined poses; and
//    from the VO's own poses with the tracks pruned by their fit over their life); the
//    same figures over 16 runs of its frames fed from other starts, backwards and every second
//    frame (AprilTagSequenceVariants: the spread of a one-sequence figure);
//  - visp_mbt_cube (218 frames, low texture, a still camera watching a hand move the object):
//    no false motion;
//  - the VO's time per frame (wall clock and the thread's CPU time: the machine is shared).
// Targets (issue 34): rotation error at 10 frames median <= 1 deg and <= half of OpenCV's,
// direction error median <= 20 deg, the first pose on visp_rbt_sequence within 10 frames (1/3 s)
// of the start of the camera's motion (MotionOnset: it stands still for its first frames, so
// "its first frames" count from there, as the cube's "first 2 s of real motion"); on visp_mbt_cube
// no turn of the still camera (the "first pose within 2 s of the start of motion" took the
// data's description for granted: the camera never moves). Slow (label eval): `ctest -L eval -R
// vo/real_sequence`. RIGCAL_VO_EVAL_VERBOSE=1 prints every frame's VO result;
// RIGCAL_VO_EVAL_READOUT_S=<s> gives the camera a rolling-shutter readout time (the sequence's is
// not known: with 0.01-0.045 s the median over RANSAC seeds 1-8 at 10 frames is 1.49-1.61 deg,
// without 1.50 deg);
// RIGCAL_VO_EVAL_POSES=<file> appends every pose with 17 digits (to check that a change meant to be
// exact keeps the VO's results).

#include <gtest/gtest.h>
#include <time.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <random>
#include <string>

#include "rigcal/base/quaternion.h"
#include "rigcal/vo/monocular_vo.h"
#include "support/offline_bundle_adjustment.h"
#include "support/opencv_two_view.h"
#include "support/real_mono_sequence.h"
#include "support/relative_pose_errors.h"
#include "support/skip.h"
#include "support/tag_grid_refinement.h"
#include "vo_eval_options.h"

namespace rigcal::vo {
namespace {

using support::RealMonoSequence;
using support::RelativePoseError;

double ThreadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

struct VoRun {
  std::map<int, std::map<int, Pose>> segments;  // segment -> frame -> pose
  int first_pose = -1;                          // frame of the first pose
  int frames_with_pose = 0;
  int frames_after_first = 0;  // frames fed from the first pose on
  std::vector<double> wall_ms, cpu_ms;
};

// Runs the VO over `frames` (indices into the sequence, fed in this order with the sequence's
// stamps, or with stamps at the frame rate when the order is not increasing).
VoRun RunVo(const RealMonoSequence& s, const std::vector<int>& frames,
            VoOptions options = EvalOptions()) {
  VoRun run;
  // One core for the VO, as on the vehicle computer: OpenCV's parallel loops would spread its
  // work over threads whose time the thread's CPU clock does not see.
  const int opencv_threads = cv::getNumThreads();
  cv::setNumThreads(1);
  std::shared_ptr<const camera::CameraModel> model = s.camera;
  if (const char* readout = std::getenv("RIGCAL_VO_EVAL_READOUT_S")) {
    std::shared_ptr<camera::CameraModel> copy = s.camera->Clone();
    copy->set_rolling_shutter_s(std::atof(readout));
    model = copy;
  }
  MonocularVo vo(model, 0, options);
  const bool verbose = std::getenv("RIGCAL_VO_EVAL_VERBOSE") != nullptr;
  const char* poses_path = std::getenv("RIGCAL_VO_EVAL_POSES");
  std::FILE* poses_file = poses_path != nullptr ? std::fopen(poses_path, "a") : nullptr;
  std::map<int64_t, int> frame_of;
  bool increasing = true;
  for (size_t i = 1; i < frames.size(); ++i) increasing &= frames[i] > frames[i - 1];
  for (size_t i = 0; i < frames.size(); ++i) {
    const int k = frames[i];
    const int64_t t_ns = increasing ? s.t_ns[k] : static_cast<int64_t>(i) * s.t_ns[1];
    frame_of[t_ns] = k;
    const double cpu0 = ThreadCpuMs();
    const VoResult r = vo.Process(t_ns, s.grey[k]);
    run.cpu_ms.push_back(ThreadCpuMs() - cpu0);
    run.wall_ms.push_back(r.processing_ms);
    if (verbose) {
      std::printf("%s frame %d: %s tracks %d inliers %d%s noise %.2f px %.2f ms %s\n",
                  s.name.c_str(), k, ToString(r.state).c_str(), r.tracked_features, r.inliers,
                  r.keyframe ? " keyframe" : "", r.track_noise_px, r.processing_ms,
                  r.message.c_str());
    }
    if (r.segment_start) {
      run.segments[r.segment_start->segment][frame_of.at(r.segment_start->t_ns)] =
          r.segment_start->pose;
    }
    if (r.pose) {
      run.segments[r.pose->segment][k] = r.pose->pose;
      if (poses_file != nullptr) {
        const Pose& p = r.pose->pose;
        std::fprintf(poses_file, "%s %d %d %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n",
                     s.name.c_str(), k, r.pose->segment, p.q.w(), p.q.x(), p.q.y(), p.q.z(),
                     p.C.x(), p.C.y(), p.C.z());
      }
      ++run.frames_with_pose;
      if (run.first_pose < 0) run.first_pose = static_cast<int>(i);
    }
    if (run.first_pose >= 0) ++run.frames_after_first;
  }
  if (poses_file != nullptr) std::fclose(poses_file);
  cv::setNumThreads(opencv_threads);
  return run;
}

std::vector<int> AllFrames(const RealMonoSequence& s) {
  std::vector<int> frames(s.grey.size());
  for (size_t k = 0; k < frames.size(); ++k) frames[k] = static_cast<int>(k);
  return frames;
}

std::map<int, Pose> Truth(const RealMonoSequence& s) {
  std::map<int, Pose> truth;
  for (size_t k = 0; k < s.grid_from_cam.size(); ++k)
    truth[static_cast<int>(k)] = s.grid_from_cam[k];
  return truth;
}

// Pair errors of every segment of `run` at `step` frames.
std::vector<RelativePoseError> RunErrors(const VoRun& run, const std::map<int, Pose>& truth,
                                         int step) {
  std::vector<RelativePoseError> all;
  for (const auto& [segment, poses] : run.segments) {
    const auto errors = support::RelativePoseErrors(poses, truth, step);
    all.insert(all.end(), errors.begin(), errors.end());
  }
  return all;
}

void PrintTiming(const std::string& label, const VoRun& run) {
  const auto wall = support::Stats(run.wall_ms);
  const auto cpu = support::Stats(run.cpu_ms);
  std::printf(
      "%s: VO per frame wall clock median %.2f p90 %.2f ms, thread CPU median %.2f p90 %.2f ms\n",
      label.c_str(), wall.median, wall.p90, cpu.median, cpu.p90);
}

// The tag poses' noise floor at `step` frames: every tag's own relative motion (the pose of the
// camera in the tag's frame at a and b) against the grid's, over the pairs where the tag was
// detected at both frames. Single tags are noisier than the grid fitted to all of them, so this
// bounds the grid's noise from above; the grid's own noise is estimated as the tags' scatter
// divided by the square root of the number of tags.
struct TagFloor {
  double tag_rotation_deg = 0.0;   // median over pairs of the median over tags
  double tag_direction_deg = 0.0;  // the same for the translation direction
  double grid_rotation_deg = 0.0;  // estimated grid noise: tag figure / sqrt(tags per pair)
  double grid_direction_deg = 0.0;
  double grid_position_m = 0.0;  // median |C_tag - C_grid| relative motion difference / sqrt(n)
};

TagFloor TagNoiseFloor(const RealMonoSequence& s, int step) {
  std::vector<double> rotation, direction, position, tags_per_pair;
  for (size_t a = 0; a + step < s.grey.size(); ++a) {
    const size_t b = a + step;
    std::vector<double> r, d, p;
    for (const auto& [id, tag_a] : s.tag_from_cam[a]) {
      const auto tag_b = s.tag_from_cam[b].find(id);
      if (tag_b == s.tag_from_cam[b].end()) continue;
      const RelativePoseError e = support::CompareRelativeMotion(
          tag_a, tag_b->second, s.grid_from_cam[a], s.grid_from_cam[b]);
      r.push_back(e.rotation_deg);
      d.push_back(e.direction_deg);
      const Pose tag_motion = tag_a.Between(tag_b->second);
      const Pose grid_motion = s.grid_from_cam[a].Between(s.grid_from_cam[b]);
      p.push_back((tag_motion.C - grid_motion.C).norm());
    }
    if (r.empty()) continue;
    rotation.push_back(support::Stats(r).median);
    direction.push_back(support::Stats(d).median);
    position.push_back(support::Stats(p).median);
    tags_per_pair.push_back(static_cast<double>(r.size()));
  }
  TagFloor floor;
  floor.tag_rotation_deg = support::Stats(rotation).median;
  floor.tag_direction_deg = support::Stats(direction).median;
  const double root_n = std::sqrt(support::Stats(tags_per_pair).median);
  floor.grid_rotation_deg = floor.tag_rotation_deg / root_n;
  floor.grid_direction_deg = floor.tag_direction_deg / root_n;
  floor.grid_position_m = support::Stats(position).median / root_n;
  return floor;
}

// The frame at which the hand-held camera starts to move: the first whose pose has left frame
// 0's by more than 3 σ of the tag grid's noise (TagNoiseFloor at one frame: √2 σ of one pose, so
// 3 of them is 4.2 σ) in position or in rotation. The VO can only initialise on motion; the
// camera of visp_rbt_sequence stands still for its first frames.
int MotionOnset(const RealMonoSequence& s) {
  const TagFloor floor = TagNoiseFloor(s, 1);
  for (size_t k = 1; k < s.grid_from_cam.size(); ++k) {
    const Pose motion = s.grid_from_cam[0].Between(s.grid_from_cam[k]);
    const double rotation_deg = Eigen::AngleAxisd(motion.q).angle() * 180.0 / M_PI;
    if (motion.C.norm() > 3.0 * floor.grid_position_m ||
        rotation_deg > 3.0 * floor.grid_rotation_deg) {
      return static_cast<int>(k);
    }
  }
  return -1;
}

// The rotation error per axis of the camera (x right, y down, z along the optical axis) for the
// pairs `step` frames apart: the RMS of the rotation vector's difference, and the correlation of
// the estimated with the true rotation about each axis. Rotations about x and y trade against
// sideways translations (the rotation-translation ambiguity of a narrow view); about z they do
// not.
void PrintAxisErrors(const VoRun& run, const std::map<int, Pose>& truth, int step) {
  std::array<std::vector<double>, 3> estimate, reference;
  for (const auto& [segment, poses] : run.segments) {
    for (const auto& [a, pose_a] : poses) {
      const auto b = poses.find(a + step);
      if (b == poses.end() || !truth.count(a) || !truth.count(a + step)) continue;
      const Eigen::AngleAxisd e(pose_a.Between(b->second).q);
      const Eigen::AngleAxisd t(truth.at(a).Between(truth.at(a + step)).q);
      for (int i = 0; i < 3; ++i) {
        estimate[i].push_back(e.axis()[i] * e.angle() * 180.0 / M_PI);
        reference[i].push_back(t.axis()[i] * t.angle() * 180.0 / M_PI);
      }
    }
  }
  if (estimate[0].size() < 3) return;
  std::printf("step %2d: VO rotation per camera axis (x, y, z):", step);
  for (int i = 0; i < 3; ++i) {
    const size_t n = estimate[i].size();
    double me = 0, mr = 0;
    for (size_t k = 0; k < n; ++k) me += estimate[i][k] / n, mr += reference[i][k] / n;
    double see = 0, srr = 0, ser = 0, sdd = 0;
    for (size_t k = 0; k < n; ++k) {
      const double de = estimate[i][k] - me, dr = reference[i][k] - mr;
      see += de * de, srr += dr * dr, ser += de * dr;
      sdd += (estimate[i][k] - reference[i][k]) * (estimate[i][k] - reference[i][k]);
    }
    std::printf(" error RMS %.2f deg (true RMS %.2f, correlation %.3f)%s", std::sqrt(sdd / n),
                std::sqrt(srr / n), ser / std::sqrt(see * srr), i < 2 ? ";" : "\n");
  }
}

cv::Matx33d Intrinsics(const camera::CameraModel& camera) {
  // The projection of the optical axis and of small offsets (the sequences' lenses have no
  // distortion).
  const auto centre = camera.Project(Eigen::Vector3d(0, 0, 1));
  const auto right = camera.Project(Eigen::Vector3d(0.01, 0, 1));
  const auto down = camera.Project(Eigen::Vector3d(0, 0.01, 1));
  cv::Matx33d K = cv::Matx33d::eye();
  K(0, 2) = centre->x();
  K(1, 2) = centre->y();
  K(0, 0) = (right->x() - centre->x()) / 0.01;
  K(1, 1) = (down->y() - centre->y()) / 0.01;
  return K;
}

enum class Peer { kOrb, kKlt };

// OpenCV's relative pose of every pair of `pairs` (ORB matches or KLT tracks through the frames
// between), against the tags. *failures counts the pairs OpenCV found no pose for (they are
// left out of the errors). *motions (may be null) gets OpenCV's motion of every pair it posed,
// by the pair's first frame.
std::vector<RelativePoseError> OpenCvErrors(const RealMonoSequence& s,
                                            const std::vector<RelativePoseError>& pairs, Peer peer,
                                            int* failures, std::map<int, Pose>* motions = nullptr) {
  const cv::Matx33d K = Intrinsics(*s.camera);
  std::vector<RelativePoseError> out;
  *failures = 0;
  for (const RelativePoseError& pair : pairs) {
    std::optional<Pose> b_in_a;
    if (peer == Peer::kOrb) {
      b_in_a = support::OpenCvRelativePose(s.grey[pair.a], s.grey[pair.b], K);
    } else {
      b_in_a = support::OpenCvKltRelativePose(
          std::vector<cv::Mat>(s.grey.begin() + pair.a, s.grey.begin() + pair.b + 1), K);
    }
    if (!b_in_a) {
      ++*failures;
      continue;
    }
    if (motions != nullptr) (*motions)[pair.a] = *b_in_a;
    RelativePoseError e = support::CompareRelativeMotion(Pose{}, *b_in_a, s.grid_from_cam[pair.a],
                                                         s.grid_from_cam[pair.b]);
    e.a = pair.a;
    e.b = pair.b;
    out.push_back(e);
  }
  return out;
}

// The rotation error of a motion against the tags' as a rotation vector in the first camera's
// axes, deg.
Eigen::Vector3d RotationErrorDeg(const Pose& motion, const Pose& reference_motion) {
  const Eigen::AngleAxisd e(reference_motion.q.conjugate() * motion.q);
  return e.axis() * e.angle() * 180.0 / M_PI;
}

// The tags' own share of the rotation errors, by the three-cornered hat: the VO and OpenCV's KLT
// + 5-point or ORB + 5-point measure the same motions with errors v and k independent of each
// other and of the tags' error t; against the tags they show v - t and k - t, and
// E[(v - t)(k - t)] = E[t^2]. Per camera axis: the tags' error from the mean of that product
// with either peer (the two peers share OpenCV's 5-point solver, so not their product), and each
// estimator's own error as its error against the tags with the tags' share taken out. An error
// common to the VO and the peers (of the images, not of the tags: rolling shutter, the
// intrinsics) counts as the tags'. The median of an estimator's own error is that of a Gaussian
// with those per-axis σ (the errors' own distribution cannot be separated).
struct ErrorShares {
  int pairs = 0;
  Eigen::Vector3d tags_deg = Eigen::Vector3d::Zero();  // per axis: RMS
  Eigen::Vector3d vo_deg = Eigen::Vector3d::Zero();
  Eigen::Vector3d klt_deg = Eigen::Vector3d::Zero();
  Eigen::Vector3d orb_deg = Eigen::Vector3d::Zero();
};

// The rotation errors against the tags of the VO and the two peers, for the pairs `step` frames
// apart that all three posed, in frame order.
struct PairErrors {
  std::vector<Eigen::Vector3d> vo, klt, orb;
};

PairErrors CollectPairErrors(const VoRun& run, const std::map<int, Pose>& klt,
                             const std::map<int, Pose>& orb, const RealMonoSequence& s, int step) {
  PairErrors e;
  for (const auto& [segment, poses] : run.segments) {
    for (const auto& [a, pose_a] : poses) {
      const auto b = poses.find(a + step);
      if (b == poses.end() || !klt.count(a) || !orb.count(a)) continue;
      const Pose reference = s.grid_from_cam[a].Between(s.grid_from_cam[a + step]);
      e.vo.push_back(RotationErrorDeg(pose_a.Between(b->second), reference));
      e.klt.push_back(RotationErrorDeg(klt.at(a), reference));
      e.orb.push_back(RotationErrorDeg(orb.at(a), reference));
    }
  }
  return e;
}

// The shares over the pairs `chosen` (indices into e, repeats allowed).
ErrorShares SplitRotationErrors(const PairErrors& e, const std::vector<size_t>& chosen) {
  ErrorShares shares;
  shares.pairs = static_cast<int>(chosen.size());
  if (chosen.size() < 3) return shares;
  const double n = static_cast<double>(chosen.size());
  for (int i = 0; i < 3; ++i) {
    double vv = 0, kk = 0, oo = 0, vk = 0, vo = 0;
    for (const size_t j : chosen) {
      const double v = e.vo[j][i], k = e.klt[j][i], o = e.orb[j][i];
      vv += v * v / n, kk += k * k / n, oo += o * o / n, vk += v * k / n, vo += v * o / n;
    }
    const double tags = std::max(0.0, (vk + vo) / 2.0);
    shares.tags_deg[i] = std::sqrt(tags);
    shares.vo_deg[i] = std::sqrt(std::max(0.0, vv - tags));
    shares.klt_deg[i] = std::sqrt(std::max(0.0, kk - tags));
    shares.orb_deg[i] = std::sqrt(std::max(0.0, oo - tags));
  }
  return shares;
}

// The median angle of a rotation error whose axes are independent Gaussians with RMS sigma_deg.
double GaussianMedianAngleDeg(const Eigen::Vector3d& sigma_deg, int samples = 100000) {
  std::mt19937 rng(34);
  std::normal_distribution<double> normal;
  std::vector<double> angles(static_cast<size_t>(samples));
  for (double& angle : angles) {
    angle = Eigen::Vector3d(sigma_deg.x() * normal(rng), sigma_deg.y() * normal(rng),
                            sigma_deg.z() * normal(rng))
                .norm();
  }
  return support::Stats(angles).median;
}

void PrintErrorShares(const ErrorShares& e, int step) {
  auto axes = [](const Eigen::Vector3d& d) {
    char text[96];
    std::snprintf(text, sizeof(text), "x %.2f, y %.2f, z %.2f deg (median %.2f)", d.x(), d.y(),
                  d.z(), GaussianMedianAngleDeg(d));
    return std::string(text);
  };
  std::printf(
      "step %2d: rotation error shares over %d pairs (three-cornered hat): tags %s; VO %s; KLT + "
      "5-point %s; ORB + 5-point %s\n",
      step, e.pairs, axes(e.tags_deg).c_str(), axes(e.vo_deg).c_str(), axes(e.klt_deg).c_str(),
      axes(e.orb_deg).c_str());
}

// The 10th and 90th percentiles of the VO's and the tags' median error over block-bootstrap
// resamples of the pairs: blocks of `step` consecutive pairs (pairs within a block share frames
// and errors), drawn with replacement.
void PrintShareSpread(const PairErrors& e, int step) {
  const size_t n = e.vo.size();
  if (n < static_cast<size_t>(2 * step)) return;
  std::mt19937 rng(34);
  std::uniform_int_distribution<size_t> start(0, n - static_cast<size_t>(step));
  std::vector<double> vo, tags;
  for (int draw = 0; draw < 200; ++draw) {
    std::vector<size_t> chosen;
    while (chosen.size() < n) {
      const size_t first = start(rng);
      for (int j = 0; j < step; ++j) chosen.push_back(first + static_cast<size_t>(j));
    }
    const ErrorShares shares = SplitRotationErrors(e, chosen);
    vo.push_back(GaussianMedianAngleDeg(shares.vo_deg, 10000));
    tags.push_back(GaussianMedianAngleDeg(shares.tags_deg, 10000));
  }
  std::sort(vo.begin(), vo.end());
  std::sort(tags.begin(), tags.end());
  std::printf(
      "step %2d: over 200 block-bootstrap resamples, the median of the VO's own error %.2f to "
      "%.2f deg, of the tags' %.2f to %.2f deg (10th to 90th percentile)\n",
      step, vo[20], vo[179], tags[20], tags[179]);
}

double Median(const std::vector<RelativePoseError>& errors, double RelativePoseError::*field) {
  std::vector<double> v;
  for (const RelativePoseError& e : errors) {
    if (field != &RelativePoseError::direction_deg || e.scale > 0.0) v.push_back(e.*field);
  }
  return support::Stats(v).median;
}

// The second reference (support/tag_grid_refinement.h): the camera poses re-estimated with
// the tags' real layout on the board, and their Cramér-Rao σ.
std::map<int, Pose> RefinedTruth(const support::RefinedTagGrid& g) {
  std::map<int, Pose> truth;
  for (size_t k = 0; k < g.grid_from_cam.size(); ++k) {
    truth[static_cast<int>(k)] = g.grid_from_cam[k];
  }
  return truth;
}

// The errors of a peer's motions (by the pair's first frame) against `reference`.
std::vector<RelativePoseError> MotionErrors(const std::map<int, Pose>& motions,
                                            const std::map<int, Pose>& reference, int step) {
  std::vector<RelativePoseError> out;
  for (const auto& [a, motion] : motions) {
    if (reference.count(a) == 0 || reference.count(a + step) == 0) continue;
    RelativePoseError e =
        support::CompareRelativeMotion(Pose{}, motion, reference.at(a), reference.at(a + step));
    e.a = a;
    e.b = a + step;
    out.push_back(e);
  }
  return out;
}

// The median rotation error of the refined poses themselves over `pairs`: per camera axis the
// RMS over the pairs of the two frames' Cramér-Rao σ, as a Gaussian. The bound holds the
// layout fixed; on rendered boards the motions' errors are 0.8-1.5 times it
// (vo/tag_grid_refinement).
double RefinedFloorDeg(const support::RefinedTagGrid& g,
                       const std::vector<RelativePoseError>& pairs) {
  if (pairs.empty()) return 0.0;
  Eigen::Vector3d sum2 = Eigen::Vector3d::Zero();
  for (const RelativePoseError& p : pairs) {
    sum2 += g.rotation_sigma_deg[static_cast<size_t>(p.a)].cwiseAbs2() +
            g.rotation_sigma_deg[static_cast<size_t>(p.b)].cwiseAbs2();
  }
  return GaussianMedianAngleDeg((sum2 / static_cast<double>(pairs.size())).cwiseSqrt());
}

void PrintRefinedReference(const support::RefinedTagGrid& g) {
  std::vector<double> x, y, z;
  for (const Eigen::Vector3d& s : g.rotation_sigma_deg) {
    x.push_back(s.x()), y.push_back(s.y()), z.push_back(s.z());
  }
  std::printf(
      "refined tag poses (the tags' layout on the board estimated with them): corner sigma %.3f "
      "px, corners vs pose RMS median %.2f px (recorded poses on the grid: %.2f px); Cramer-Rao "
      "sigma of a frame's rotation median x %.3f, y %.3f, z %.3f deg\n",
      g.corner_sigma_px, support::Stats(g.residual_rms_px).median,
      support::Stats(g.recorded_residual_rms_px).median, support::Stats(x).median,
      support::Stats(y).median, support::Stats(z).median);
}

void PrintAgainstRefined(int step, const VoRun& run, const std::map<int, Pose>& orb,
                         const std::map<int, Pose>& klt, const support::RefinedTagGrid& g,
                         const std::map<int, Pose>& recorded) {
  const std::map<int, Pose> refined = RefinedTruth(g);
  const std::vector<RelativePoseError> vo = RunErrors(run, refined, step);
  std::printf("step %2d: against the refined tag poses: VO %s\n", step,
              support::Describe(vo).c_str());
  std::printf("step %2d: against the refined tag poses: ORB + 5-point %s; KLT + 5-point %s\n", step,
              support::Describe(MotionErrors(orb, refined, step)).c_str(),
              support::Describe(MotionErrors(klt, refined, step)).c_str());
  std::printf(
      "step %2d: the refined poses' own rotation error (Cramer-Rao) median %.3f deg; the recorded "
      "poses against them: %s\n",
      step, RefinedFloorDeg(g, vo),
      support::Describe(support::RelativePoseErrors(recorded, refined, step)).c_str());
}

// The images' own estimate (support/offline_bundle_adjustment.h): every pose from the motion's
// onset adjusted with the KLT tracks that fit the refined tag poses within `gate_px`. Where it
// misses the tags by more than both their noise, the images (a pinhole without distortion, a
// rigid scene) and the tags disagree, and no VO can come closer to the tags than that; the VO's
// own error is its distance from this estimate.
void PrintOfflineBa(const RealMonoSequence& s, const VoRun& run, const std::map<int, Pose>& refined,
                    int onset, double gate_px) {
  std::map<int, Pose> initial;
  for (const auto& [k, pose] : refined) {
    if (k >= onset) initial[k] = pose;
  }
  support::OfflineBaOptions options;
  options.initial_gate_px = gate_px;
  const auto ba = support::OfflineBundleAdjustment(s.grey, initial, *s.camera, options);
  ASSERT_TRUE(ba.ok()) << ba.error();
  std::printf(
      "offline BA of frames %d-%d (KLT tracks within %.0f px of the refined tag poses): %d of %d "
      "tracks, residual sigma %.3f px\n",
      initial.begin()->first, initial.rbegin()->first, gate_px, ba->points, ba->tracks,
      ba->residual_sigma_px);
  for (const int step : {1, 5, 10}) {
    std::printf(
        "step %2d: offline BA (%.0f px) against the refined tag poses: %s; the VO against it: %s\n",
        step, gate_px,
        support::Describe(support::RelativePoseErrors(ba->world_from_cam, refined, step)).c_str(),
        support::Describe(RunErrors(run, ba->world_from_cam, step)).c_str());
  }
}

// The same adjustment started from the VO's own poses (no reference in it), with the tracks
// pruned by their fit over their whole life: what a VO that kept every frame of a track and
// tested the track as a whole could reach on these images.
void PrintOfflineBaFromVo(const RealMonoSequence& s, const VoRun& run,
                          const std::map<int, Pose>& refined) {
  if (run.segments.empty()) return;
  support::OfflineBaOptions options;
  options.initial_gate_px = 10.0;
  options.prune_rounds = 4;
  std::map<int, Pose> initial;  // the frames posed in a row from the first (not the
                                // initialisation's reference frame before them)
  for (const auto& [k, pose] : run.segments.begin()->second) {
    if (k >= run.first_pose) initial[k] = pose;
  }
  const auto ba = support::OfflineBundleAdjustment(s.grey, initial, *s.camera, options);
  ASSERT_TRUE(ba.ok()) << ba.error();
  std::printf(
      "offline BA from the VO's poses, tracks within 10 px of them, %d rounds of pruning: %d of "
      "%d tracks kept, residual sigma %.3f px\n",
      options.prune_rounds, ba->points, ba->tracks, ba->residual_sigma_px);
  for (const int step : {1, 5, 10}) {
    std::printf(
        "step %2d: offline BA from the VO's poses, pruned, against the refined tag poses: %s\n",
        step,
        support::Describe(support::RelativePoseErrors(ba->world_from_cam, refined, step)).c_str());
  }
}

// The VO's figure over RANSAC seeds (the same frames, other random samples: other inlier sets,
// keyframes a frame earlier or later), against both references.
void PrintSeedSpread(const RealMonoSequence& s, const std::map<int, Pose>& recorded,
                     const std::map<int, Pose>& refined) {
  std::map<int, std::vector<double>> on_recorded, on_refined, scale_spread;
  std::map<int, double> min_length;  // as the main figures: 3 σ of the grid's position noise
  for (const int step : {1, 5, 10}) min_length[step] = 3.0 * TagNoiseFloor(s, step).grid_position_m;
  for (uint32_t seed = 1; seed <= 8; ++seed) {
    VoOptions options = EvalOptions();
    options.seed = seed;
    const VoRun run = RunVo(s, AllFrames(s), options);
    for (const int step : {1, 5, 10}) {
      on_recorded[step].push_back(
          Median(RunErrors(run, recorded, step), &RelativePoseError::rotation_deg));
      on_refined[step].push_back(
          Median(RunErrors(run, refined, step), &RelativePoseError::rotation_deg));
      scale_spread[step].push_back(
          support::ScaleSpread(RunErrors(run, recorded, step), min_length[step]));
    }
  }
  for (const int step : {1, 5, 10}) {
    const auto [a_min, a_max] =
        std::minmax_element(on_recorded[step].begin(), on_recorded[step].end());
    const auto [b_min, b_max] =
        std::minmax_element(on_refined[step].begin(), on_refined[step].end());
    std::printf(
        "step %2d over RANSAC seeds 1-8: VO rotation error median of the medians %.3f deg (%.3f "
        "to %.3f) against the recorded tag poses, %.3f deg (%.3f to %.3f) against the refined; "
        "scale spread median %.1f %%\n",
        step, support::Stats(on_recorded[step]).median, *a_min, *a_max,
        support::Stats(on_refined[step]).median, *b_min, *b_max,
        100.0 * support::Stats(scale_spread[step]).median);
  }
}

TEST(RealSequenceVo, AprilTagSequenceAgainstTagsAndOpenCv) {
  if (!support::RealMonoAvailable("visp_rbt_sequence")) {
    RIGCAL_SKIP_MISSING() << "no " << support::RealMonoFolder("visp_rbt_sequence");
  }
  auto loaded = support::LoadRealMono("visp_rbt_sequence");
  ASSERT_TRUE(loaded.ok()) << loaded.error();
  const RealMonoSequence& s = *loaded;
  ASSERT_EQ(s.grid_from_cam.size(), s.grey.size());
  const VoRun run = RunVo(s, AllFrames(s));
  const std::map<int, Pose> truth = Truth(s);
  std::printf(
      "visp_rbt_sequence: first pose at frame %d, %d of %zu frames with a pose, %zu "
      "segment(s)\n",
      run.first_pose, run.frames_with_pose, s.grey.size(), run.segments.size());
  PrintTiming("visp_rbt_sequence", run);
  ASSERT_GE(run.first_pose, 0);
  const int onset = MotionOnset(s);
  std::printf(
      "visp_rbt_sequence: the camera starts to move at frame %d (tag grid), the VO's "
      "first pose %d frames later\n",
      onset, run.first_pose - onset);
  ASSERT_GE(onset, 0);
  EXPECT_LE(run.first_pose, onset + 10);
  EXPECT_EQ(run.segments.size(), 1u);
  EXPECT_EQ(run.frames_with_pose, run.frames_after_first);

  // Frames whose tag corners the grid pose explains as well as usual (within 3 robust σ of the
  // median RMS): blurred frames, whose tag poses are off, are left out of the second figures.
  const std::vector<double> tag_rms = support::TagGridResidualsPx(s);
  const double rms_median = support::Stats(tag_rms).median;
  std::vector<double> deviation;
  for (double r : tag_rms) deviation.push_back(std::abs(r - rms_median));
  const double rms_gate = rms_median + 3.0 * 1.4826 * support::Stats(deviation).median;
  std::map<int, Pose> sharp_truth;
  for (const auto& [k, pose] : truth) {
    if (tag_rms[static_cast<size_t>(k)] <= rms_gate) sharp_truth[k] = pose;
  }
  std::printf(
      "tag corners vs grid pose: RMS median %.2f px, p90 %.2f px; %zu of %zu frames within "
      "%.2f px\n",
      rms_median, support::Stats(tag_rms).p90, sharp_truth.size(), truth.size(), rms_gate);
  for (const int step : {1, 5, 10}) {
    std::printf("step %2d: VO (well-measured frames) %s\n", step,
                support::Describe(RunErrors(run, sharp_truth, step)).c_str());
    PrintAxisErrors(run, sharp_truth, step);
  }
  if (std::getenv("RIGCAL_VO_EVAL_QUICK") != nullptr) return;
  const auto refined = support::RefineTagGrid(s);
  ASSERT_TRUE(refined.ok()) << refined.error();
  PrintRefinedReference(*refined);
  for (const int step : {1, 5, 10}) {
    const std::vector<RelativePoseError> vo = RunErrors(run, truth, step);
    int cv_failures = 0, klt_failures = 0;
    std::map<int, Pose> cv_motions, klt_motions;
    const std::vector<RelativePoseError> cv =
        OpenCvErrors(s, vo, Peer::kOrb, &cv_failures, &cv_motions);
    const std::vector<RelativePoseError> klt =
        OpenCvErrors(s, vo, Peer::kKlt, &klt_failures, &klt_motions);
    const TagFloor floor = TagNoiseFloor(s, step);
    std::vector<double> lengths;
    for (const RelativePoseError& e : vo) lengths.push_back(e.reference_length);
    const double min_length = 3.0 * floor.grid_position_m;
    std::printf(
        "step %2d: tag floor: single tag vs grid rotation %.3f deg, direction %.1f deg; grid "
        "(/sqrt n) rotation %.3f deg, direction %.1f deg, position %.2f mm; true motion median "
        "%.1f mm\n",
        step, floor.tag_rotation_deg, floor.tag_direction_deg, floor.grid_rotation_deg,
        floor.grid_direction_deg, 1e3 * floor.grid_position_m,
        1e3 * support::Stats(lengths).median);
    std::printf("step %2d: VO     %s, scale spread %.1f %% (pairs moving >= %.1f mm)\n", step,
                support::Describe(vo).c_str(), 100.0 * support::ScaleSpread(vo, min_length),
                1e3 * min_length);
    std::printf("step %2d: OpenCV ORB + 5-point %s, %d failed\n", step,
                support::Describe(cv).c_str(), cv_failures);
    std::printf("step %2d: OpenCV KLT + 5-point %s, %d failed\n", step,
                support::Describe(klt).c_str(), klt_failures);
    const PairErrors pair_errors = CollectPairErrors(run, klt_motions, cv_motions, s, step);
    std::vector<size_t> all(pair_errors.vo.size());
    for (size_t j = 0; j < all.size(); ++j) all[j] = j;
    PrintErrorShares(SplitRotationErrors(pair_errors, all), step);
    PrintShareSpread(pair_errors, step);
    PrintAgainstRefined(step, run, cv_motions, klt_motions, *refined, truth);
    if (step == 10) {
      const double vo_rotation = Median(vo, &RelativePoseError::rotation_deg);
      const double cv_rotation = Median(cv, &RelativePoseError::rotation_deg);
      EXPECT_LE(vo_rotation, 1.0);
      EXPECT_LE(vo_rotation, 0.5 * cv_rotation);
      EXPECT_LE(Median(vo, &RelativePoseError::direction_deg), 20.0);
      EXPECT_GE(vo.size(), s.grey.size() - run.first_pose - 10);
    }
  }
  PrintSeedSpread(s, truth, RefinedTruth(*refined));
  for (const double gate_px : {3.0, 10.0}) {
    PrintOfflineBa(s, run, RefinedTruth(*refined), onset, gate_px);
  }
  PrintOfflineBaFromVo(s, run, RefinedTruth(*refined));
}

// One sequence gives one figure, and a VO's figure on one short sequence moves by tenths of a
// degree with any change that alters one decision (a keyframe one frame later). The same
// frames fed from other starting frames, backwards, and every second frame (twice the motion
// per frame) are 16 runs that initialise at other places and see other keyframes: their spread
// is the figure's own uncertainty, and the median over them the figure to compare.
struct Variant {
  std::string name;
  std::vector<int> frames;
};

std::vector<Variant> SequenceVariants(int count) {
  std::vector<Variant> variants;
  auto add = [&](const std::string& name, int first, int last, int stride) {
    Variant v;
    v.name = name;
    for (int k = first; stride > 0 ? k <= last : k >= last; k += stride) v.frames.push_back(k);
    variants.push_back(v);
  };
  const int end = count - 1;
  for (const int start : {0, 10, 20, 30, 40}) {
    add("forward from " + std::to_string(start), start, end, 1);
    add("backward from " + std::to_string(end - start), end - start, 0, -1);
  }
  for (const int start : {0, 1}) {
    add("every 2nd from " + std::to_string(start), start, end, 2);
    add("every 2nd backward from " + std::to_string(end - start), end - start, 0, -2);
  }
  add("forward from 5", 5, end, 1);
  add("backward from " + std::to_string(end - 5), end - 5, 0, -1);
  return variants;
}

TEST(RealSequenceVo, AprilTagSequenceVariants) {
  if (!support::RealMonoAvailable("visp_rbt_sequence")) {
    RIGCAL_SKIP_MISSING() << "no " << support::RealMonoFolder("visp_rbt_sequence");
  }
  auto loaded = support::LoadRealMono("visp_rbt_sequence");
  ASSERT_TRUE(loaded.ok()) << loaded.error();
  const RealMonoSequence& s = *loaded;
  const std::map<int, Pose> truth = Truth(s);
  std::map<int, std::vector<double>> rotation, direction;  // step -> per variant median
  int usable = 0;
  const std::vector<Variant> variants = SequenceVariants(static_cast<int>(s.grey.size()));
  for (const Variant& v : variants) {
    const VoRun run = RunVo(s, v.frames);
    std::printf("%-26s %3zu frames: %3d posed, %zu segment(s)", v.name.c_str(), v.frames.size(),
                run.frames_with_pose, run.segments.size());
    bool enough = false;  // 10 pairs at 10 frames (every 2nd frame: no odd steps)
    for (const int step : {1, 5, 10}) {
      const std::vector<RelativePoseError> e = RunErrors(run, truth, step);
      if (step == 10) enough = e.size() >= 10;
      if (e.size() < 10) continue;
      rotation[step].push_back(Median(e, &RelativePoseError::rotation_deg));
      direction[step].push_back(Median(e, &RelativePoseError::direction_deg));
      std::printf("; %2d: %.2f deg, %.0f deg", step, rotation[step].back(), direction[step].back());
    }
    std::printf("\n");
    usable += enough;
  }
  for (const int step : {1, 5, 10}) {
    if (rotation[step].empty()) continue;
    const auto [r_min, r_max] = std::minmax_element(rotation[step].begin(), rotation[step].end());
    const auto [d_min, d_max] = std::minmax_element(direction[step].begin(), direction[step].end());
    std::printf(
        "step %2d over %zu runs: rotation error median of the medians %.3f deg (%.3f to %.3f), "
        "direction %.1f deg (%.1f to %.1f)\n",
        step, rotation[step].size(), support::Stats(rotation[step]).median, *r_min, *r_max,
        support::Stats(direction[step]).median, *d_min, *d_max);
  }
  EXPECT_EQ(usable, static_cast<int>(variants.size())) << "runs with fewer than 10 pairs";
  EXPECT_LE(support::Stats(rotation[10]).median, 1.0);
  EXPECT_LE(support::Stats(direction[10]).median, 20.0);
}

// Frames removed from visp_rbt_sequence after frame kGapStart - 1 (gaps of 1, 5, 10 and 30
// frames: 1/30 s to 1 s of hand-held motion): the VO stays in one scale segment, and the motion
// across the gap (frame kGapStart - 1 to the first frame after it) against the tags'.
TEST(RealSequenceVo, AprilTagSequenceWithGaps) {
  if (!support::RealMonoAvailable("visp_rbt_sequence")) {
    RIGCAL_SKIP_MISSING() << "no " << support::RealMonoFolder("visp_rbt_sequence");
  }
  auto loaded = support::LoadRealMono("visp_rbt_sequence");
  ASSERT_TRUE(loaded.ok()) << loaded.error();
  const RealMonoSequence& s = *loaded;
  constexpr int kGapStart = 50;
  const std::map<int, Pose> truth = Truth(s);
  for (const int gap : {1, 5, 10, 30}) {
    std::vector<int> frames;
    for (int k = 0; k < static_cast<int>(s.grey.size()); ++k) {
      if (k < kGapStart || k >= kGapStart + gap) frames.push_back(k);
    }
    const VoRun run = RunVo(s, frames);
    const int before = kGapStart - 1;
    const int after = kGapStart + gap;
    std::printf("gap %2d frames: %zu segment(s), %d of %zu frames with a pose", gap,
                run.segments.size(), run.frames_with_pose, frames.size());
    for (const auto& [segment, poses] : run.segments) {
      if (poses.count(before) && poses.count(after)) {
        const RelativePoseError e = support::CompareRelativeMotion(
            poses.at(before), poses.at(after), truth.at(before), truth.at(after));
        std::printf("; across frames %d-%d rotation error %.3f deg, direction error %.1f deg",
                    before, after, e.rotation_deg, e.direction_deg);
      }
    }
    std::printf("\n");
    EXPECT_EQ(run.segments.size(), 1u) << "gap " << gap;
  }
}

// The still share of the view, measured with OpenCV alone, independently of the VO: the
// fraction of frame 0's corners that every later frame shows within 1 px of where they were
// (the smallest over the frames), and the first frame where the median corner moved by more
// than 2 px (something in the view moves).
struct ViewMotion {
  double still_fraction = 1.0;
  int first_change = -1;
};

ViewMotion MeasureViewMotion(const RealMonoSequence& s) {
  ViewMotion out;
  std::vector<cv::Point2f> corners;
  cv::goodFeaturesToTrack(s.grey[0], corners, 200, 0.01, 10);
  for (size_t k = 1; k < s.grey.size(); ++k) {
    std::vector<cv::Point2f> moved;
    std::vector<unsigned char> ok;
    std::vector<float> err;
    cv::calcOpticalFlowPyrLK(s.grey[0], s.grey[k], corners, moved, ok, err, cv::Size(21, 21), 4);
    std::vector<double> shift;
    int still = 0;
    for (size_t i = 0; i < corners.size(); ++i) {
      if (!ok[i]) continue;
      shift.push_back(cv::norm(moved[i] - corners[i]));
      still += shift.back() <= 1.0 ? 1 : 0;
    }
    out.still_fraction = std::min(out.still_fraction,
                                  static_cast<double>(still) / static_cast<double>(corners.size()));
    if (out.first_change < 0 &&
        (shift.size() < corners.size() / 2 || support::Stats(shift).median > 2.0)) {
      out.first_change = static_cast<int>(k);
    }
  }
  return out;
}

// visp_mbt_cube is not what its provenance says ("a hand-held camera moving around a textured
// cube"): the camera stands still for all 218 frames while a hand pushes the sheet that carries
// the cube and a cylinder across the desk (the desk's edge, the ruler, the telephone and its
// cable do not move; MeasureViewMotion: a still share of the view in every frame). What a VO must
// do here is report no motion: no initialisation on the moved object (the still scene gives no
// parallax), or, if it poses frames, poses that do not turn. The VO before the homography
// initialisation posed frames from 106 on, from tracks on the moving sheet: a false motion that a
// rig calibrator would take for the camera's.
TEST(RealSequenceVo, StillCameraWatchingAMovedObjectReportsNoMotion) {
  if (!support::RealMonoAvailable("visp_mbt_cube")) {
    RIGCAL_SKIP_MISSING() << "no " << support::RealMonoFolder("visp_mbt_cube");
  }
  auto loaded = support::LoadRealMono("visp_mbt_cube");
  ASSERT_TRUE(loaded.ok()) << loaded.error();
  const RealMonoSequence& s = *loaded;
  const ViewMotion view = MeasureViewMotion(s);
  const VoRun run = RunVo(s, AllFrames(s));
  double max_turn_deg = 0.0;
  for (const auto& [segment, poses] : run.segments) {
    for (const auto& [frame, pose] : poses) {
      max_turn_deg =
          std::max(max_turn_deg, AngleBetween(poses.begin()->second.q, pose.q) * kDegPerRad);
    }
  }
  std::printf(
      "visp_mbt_cube: %.0f %% of the view still in every frame, the object moves from frame %d; "
      "VO: first pose at frame %d, %d frames with a pose, %zu segment(s), largest turn %.3f "
      "deg\n",
      100.0 * view.still_fraction, view.first_change, run.first_pose, run.frames_with_pose,
      run.segments.size(), max_turn_deg);
  PrintTiming("visp_mbt_cube", run);
  // The premise: a still camera and a moving object. A camera that moves moves every corner of
  // the view; here a tenth at least never moves by a pixel (the rest lie on the moved sheet or are
  // covered by the arm at some frame).
  ASSERT_GE(view.still_fraction, 0.1) << "the camera moves: this test's premise does not hold";
  ASSERT_GE(view.first_change, 0) << "nothing in the view moves";
  // No false motion: the camera turns by 0; the VO's rotation noise on real frames is a few
  // tenths of a degree at most (vo/real_sequence_eval on visp_rbt: 0.37 deg median at 1 frame).
  EXPECT_LE(max_turn_deg, 0.5) << "the VO reports a turn of a still camera";
  EXPECT_LE(run.segments.size(), 1u);
}

}  // namespace
}  // namespace rigcal::vo
