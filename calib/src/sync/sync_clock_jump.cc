// SPDX-License-Identifier: Apache-2.0
// SyncBuffer: the clock jumps of free-running cameras (a camera whose clock restarted). A run of
// poses rejected as glitches that keep a steady rate on a new timeline while the other cameras'
// clocks advance is followed: a slave's by stepping its offset, the master's by stepping every
// slave's offset (and the buffer's master-clock state) the other way. See "Clock jumps" in
// rigcal/calib/sync_buffer.h. Runs with the buffer's mutex held; never allocates.
#include <algorithm>
#include <cmath>

#include "rigcal/base/logging.h"
#include "sync/sync_buffer_impl.h"

namespace rigcal {
namespace {

// Poses in a row at a steady rate on a new timeline that make it followed.
constexpr int kNewClockPoses = 10;
// Weight of a new sample in the camera's smoothed lead over its reference.
constexpr double kLeadGain = 1.0 / 8.0;

bool StartsNewTimeline(int camera, PushResult why) {
  return why == PushResult::kClockGlitch || why == PushResult::kOutOfOrder ||
         why == PushResult::kDuplicate || why == PushResult::kConsumed ||
         // The master's stamps that step back are at or before its last emitted one.
         (camera == 0 && why == PushResult::kLate);
}

constexpr double kLimit = 9.0e18;

int64_t ClampedNs(double ns) { return std::llround(std::clamp(ns, -kLimit, kLimit)); }

}  // namespace

int64_t SyncBuffer::Impl::ClockReference(int c) const {
  if (c == 0) return OthersNewest(0);
  return cameras_[0].any ? cameras_[0].newest_t : kNoStamp;
}

bool SyncBuffer::Impl::NewClock(const CameraPose& pose, PushResult why) {
  if (!follows_[pose.camera] || !StartsNewTimeline(pose.camera, why)) return false;
  const int64_t reference = ClockReference(pose.camera);
  if (reference == kNoStamp) return false;  // no reference clock yet
  CameraState& cam = cameras_[pose.camera];
  const int64_t recent = RecentInterval(pose.camera);
  const int64_t interval = recent > 0 ? recent : options_.frame_period_ns;
  const int64_t y = SaturatedSub(pose.t_ns, reference);
  // Own-clock stamps are >= 0: their difference cannot overflow.
  const int64_t step = pose.t_ns - cam.run_last_t;
  if (cam.run > 0 && step >= interval / 2 && step <= 3 * interval) {
    ++cam.run;
    cam.run_last_t = pose.t_ns;
    cam.run_dy_sum += static_cast<double>(SaturatedSub(y, cam.run_y0));
  } else {
    cam.run = 1;
    cam.run_first_t = cam.run_last_t = pose.t_ns;
    cam.run_first_reference = reference;
    cam.run_y0 = y;
    cam.run_dy_sum = 0.0;
  }
  if (cam.run < kNewClockPoses) return false;
  // The new clock runs with the reference's (the master's for a slave, the slaves' for the
  // master): not a replay of old data, which every camera would share.
  const int64_t span = cam.run_last_t - cam.run_first_t;
  return SaturatedSub(reference, cam.run_first_reference) >= span / 2;
}

void SyncBuffer::Impl::FollowNewClock(const CameraPose& pose) {
  const int c = pose.camera;
  if (c == 0) {
    FollowNewMasterClock(pose);
    return;
  }
  CameraState& cam = cameras_[c];
  const int64_t old_offset = cam.offset_ns;
  // The run's mean of (stamp - master's newest), less the lead the camera had over the master.
  const double mean_y = static_cast<double>(cam.run_y0) + cam.run_dy_sum / cam.run;
  const int64_t prior_ns = ClampedNs(mean_y - (cam.has_lead ? cam.lead_ns : 0.0));
  while (!cam.ring.empty()) PopOldest(c, &SyncCameraStats::never_matched);
  cam.offset_ns = prior_ns;
  cam.any = false;  // the pose is accepted next as the first of the new timeline
  cam.consumed_t = -1;
  cam.jump_run = 0;
  cam.run = 0;
  ++cam.stats.clock_jumps;
  cam.jump.count += 1;
  cam.jump.offset_ns = prior_ns;
  cam.jump.step_ns = SaturatedSub(prior_ns, old_offset);
  cam.jump.t_ns = pose.t_ns;
  ModuleLogger("calib")->warn(
      "sync: camera {} clock restarted: {} poses in a row at a steady rate on a new timeline "
      "(stamp {} ns, master's newest {} ns); following it with the offset stepped by {:.3f} s "
      "to {:.3f} s, to be re-estimated (clock jump {})",
      c, kNewClockPoses, pose.t_ns, cameras_[0].newest_t,
      static_cast<double>(cam.jump.step_ns) * 1e-9, static_cast<double>(prior_ns) * 1e-9,
      cam.jump.count);
}

void SyncBuffer::Impl::FollowNewMasterClock(const CameraPose& pose) {
  CameraState& master = cameras_[0];
  // The master entries of the old timeline are resolved first, with the partners they have.
  if (Process(/*flush=*/true) > 0) ready_cv_.notify_all();
  // The step of the master's clock: the run's mean of (stamp - the slaves' newest on the old
  // master clock), less the lead the master had over them.
  const double mean_y = static_cast<double>(master.run_y0) + master.run_dy_sum / master.run;
  const int64_t step = ClampedNs(mean_y - (master.has_lead ? master.lead_ns : 0.0));
  // Every stamp on the master clock moves with it: a slave's offset (stamp - master clock) by
  // -step, the stream's clocks by +step. The slaves' rings stay: their stamps are their own.
  for (int j = 1; j < n_; ++j) {
    CameraState& cam = cameras_[j];
    cam.offset_ns = SaturatedSub(cam.offset_ns, step);
    cam.jump.offset_ns = SaturatedSub(cam.jump.offset_ns, step);
    cam.run = 0;           // a run measured against the old master clock
    cam.has_lead = false;  // its lead grew while the master was away
  }
  now_ns_ = SaturatedAdd(now_ns_, step);
  stream_start_ns_ = SaturatedAdd(stream_start_ns_, step);
  last_resolved_master_.t_ns = SaturatedAdd(last_resolved_master_.t_ns, step);
  master.any = false;  // the pose is accepted next as the first of the new timeline
  master.any_used = false;
  master.consumed_t = -1;
  master.jump_run = 0;
  master.run = 0;
  ++master.stats.clock_jumps;
  master.jump.count += 1;
  master.jump.step_ns = step;
  master.jump.offset_ns = SaturatedAdd(master.jump.offset_ns, step);
  master.jump.t_ns = pose.t_ns;
  ModuleLogger("calib")->warn(
      "sync: the master's clock (camera 0) restarted: {} poses in a row at a steady rate on a "
      "new timeline while the slaves' clocks ran on (stamp {} ns); following it: the master's "
      "clock stepped by {:.3f} s, every slave's offset by {:.3f} s, to be re-measured (master "
      "clock jump {})",
      kNewClockPoses, pose.t_ns, static_cast<double>(step) * 1e-9,
      -static_cast<double>(step) * 1e-9, master.jump.count);
}

void SyncBuffer::Impl::OnTimeline(const CameraPose& pose) {
  CameraState& cam = cameras_[pose.camera];
  cam.run = 0;
  if (!follows_[pose.camera]) return;
  const int64_t reference = ClockReference(pose.camera);
  if (reference == kNoStamp) return;
  const auto y =
      static_cast<double>(SaturatedSub(OnMasterClock(pose.camera, pose.t_ns), reference));
  cam.lead_ns = cam.has_lead ? cam.lead_ns + kLeadGain * (y - cam.lead_ns) : y;
  cam.has_lead = true;
}

}  // namespace rigcal
