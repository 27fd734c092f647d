// SPDX-License-Identifier: Apache-2.0
#pragma once
// Simulated rigs whose slave cameras run free: each camera captures at its own rate and phase
// and stamps with its own clock (slave stamp = master clock + time offset). Shared by the time
// offset tests and figures.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "rigcal/base/quaternion.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/calib/timed_trajectory.h"

namespace rigcal::free_running {

// A camera of the rig: its capture rate, the phase of its first frame and its clock offset.
struct CameraClock {
  double rate_hz = 20.0;
  double phase_s = 0.0;
  double offset_s = 0.0;
};

struct FreeRunningRig {
  TimedTrajectory master;
  std::vector<TimedTrajectory> slaves;
  std::vector<Similarity> truth;  // per slave
};

// world_from_master at master-clock time t (s): the general 6-DoF motion of synthetic.cc.
inline Pose MasterWorldAt(double t) {
  const double amp_rot = 35.0 * kRadPerDeg;
  const Eigen::Vector3d rv(amp_rot * std::sin(3.0 * t), amp_rot * std::sin(5.0 * t + 1.0),
                           amp_rot * 0.8 * std::sin(2.0 * t + 2.0));
  Pose p;
  p.q = rv.norm() > 0 ? Eigen::Quaterniond(Eigen::AngleAxisd(rv.norm(), rv.normalized()))
                      : Eigen::Quaterniond::Identity();
  p.C = 2.0 *
        Eigen::Vector3d(std::sin(2.0 * t), std::sin(3.0 * t + 0.5), 0.5 * std::sin(4.0 * t + 1.5));
  return p;
}

inline std::vector<int64_t> CaptureTimes(const CameraClock& clock, double duration_s) {
  std::vector<int64_t> t;
  for (int k = 0;; ++k) {
    const double s = clock.phase_s + k / clock.rate_hz;
    if (s > duration_s) break;
    t.push_back(std::llround((10.0 + s) * 1e9));  // true instants, master clock
  }
  return t;
}

inline TimedTrajectory ToTimed(const std::string& name, const std::vector<int64_t>& t_ns,
                               const CameraTrack& track, int64_t offset_ns) {
  TimedTrajectory out;
  out.name = name;
  for (const int64_t t : t_ns) out.t_ns.push_back(t + offset_ns);
  out.poses = track.poses;
  out.segment = track.segment;
  return out;
}

// The master at `master` (its offset ignored) and one slave per entry of `clocks`, along the
// same motion, with the noise of `options` (independent per camera).
inline FreeRunningRig MakeFreeRunningRig(const CameraClock& master,
                                         const std::vector<CameraClock>& clocks,
                                         const std::vector<Similarity>& rigs, double duration_s,
                                         DriveOptions options) {
  FreeRunningRig out;
  out.truth = rigs;
  auto world_at = [](const std::vector<int64_t>& t_ns) {
    std::vector<Pose> poses;
    for (const int64_t t : t_ns) poses.push_back(MasterWorldAt(static_cast<double>(t) * 1e-9));
    return poses;
  };
  const std::vector<int64_t> tm = CaptureTimes(master, duration_s);
  const SyntheticDrive m =
      GenerateDriveAlong({"master", "unused"}, {rigs.front()}, tm, world_at(tm), options);
  out.master = ToTimed("master", tm, m.recording.master, 0);
  for (size_t i = 0; i < clocks.size(); ++i) {
    const std::string name = "cam" + std::to_string(i + 1);
    const std::vector<int64_t> ts = CaptureTimes(clocks[i], duration_s);
    options.seed += 101;
    const SyntheticDrive s =
        GenerateDriveAlong({"master", name}, {rigs[i]}, ts, world_at(ts), options);
    out.slaves.push_back(
        ToTimed(name, ts, s.recording.slaves.front(), std::llround(clocks[i].offset_s * 1e9)));
  }
  return out;
}

// Every pose of `rig` as a live calibrator receives it, in the order of the true capture
// instants (a camera's pose reaches it when it is taken, whatever its clock): camera 0 the
// master, i + 1 slave i. The rig's stamps must be the true instants (offsets 0); slave i's pose
// taken at t is stamped t + offset_ns(i, t) (its clock, which may drift or jump).
inline std::vector<CameraPose> InCaptureOrder(
    const FreeRunningRig& rig, const std::function<int64_t(int, int64_t)>& offset_ns) {
  struct Timed {
    int64_t t_true;
    CameraPose pose;
  };
  std::vector<Timed> all;
  auto add = [&](const TimedTrajectory& tr, int camera) {
    for (size_t k = 0; k < tr.size(); ++k) {
      CameraPose p;
      p.camera = camera;
      p.t_ns = tr.t_ns[k] + (camera == 0 ? 0 : offset_ns(camera - 1, tr.t_ns[k]));
      p.segment = tr.segment.empty() ? 0 : tr.segment[k];
      p.pose = tr.poses[k];
      all.push_back({tr.t_ns[k], p});
    }
  };
  add(rig.master, 0);
  for (size_t i = 0; i < rig.slaves.size(); ++i) add(rig.slaves[i], static_cast<int>(i) + 1);
  std::stable_sort(all.begin(), all.end(),
                   [](const Timed& a, const Timed& b) { return a.t_true < b.t_true; });
  std::vector<CameraPose> out;
  for (const Timed& t : all) out.push_back(t.pose);
  return out;
}

}  // namespace rigcal::free_running
