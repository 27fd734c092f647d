// SyncBuffer: the clock jumps of free-running slaves (a camera whose clock restarted). A run of
// poses rejected as glitches that keep a steady rate on a new timeline while the master's clock
// advances is followed; see "Clock jumps" in rigcal/calib/sync_buffer.h. Runs with the buffer's
// mutex held; never allocates.
#include <algorithm>
#include <cmath>

#include "rigcal/calib/logging.h"
#include "sync_buffer_impl.h"

namespace rigcal {
namespace {

// Poses in a row at a steady rate on a new timeline that make it followed.
constexpr int kNewClockPoses = 10;
// Weight of a new sample in the camera's smoothed lead over the master.
constexpr double kLeadGain = 1.0 / 8.0;

bool StartsNewTimeline(PushResult why) {
  return why == PushResult::kClockGlitch || why == PushResult::kOutOfOrder ||
         why == PushResult::kDuplicate || why == PushResult::kConsumed;
}

}  // namespace

bool SyncBuffer::Impl::NewClock(const CameraPose& pose, PushResult why) {
  if (!follows_[pose.camera] || !StartsNewTimeline(why)) return false;
  const CameraState& master = cameras_[0];
  if (!master.any) return false;  // no reference clock yet
  CameraState& cam = cameras_[pose.camera];
  const int64_t recent = RecentInterval(pose.camera);
  const int64_t interval = recent > 0 ? recent : options_.frame_period_ns;
  const int64_t y = SaturatedSub(pose.t_ns, master.newest_t);
  // Own-clock stamps are >= 0: their difference cannot overflow.
  const int64_t step = pose.t_ns - cam.run_last_t;
  if (cam.run > 0 && step >= interval / 2 && step <= 3 * interval) {
    ++cam.run;
    cam.run_last_t = pose.t_ns;
    cam.run_dy_sum += static_cast<double>(SaturatedSub(y, cam.run_y0));
  } else {
    cam.run = 1;
    cam.run_first_t = cam.run_last_t = pose.t_ns;
    cam.run_first_master = master.newest_t;
    cam.run_y0 = y;
    cam.run_dy_sum = 0.0;
  }
  if (cam.run < kNewClockPoses) return false;
  // The new clock runs with the master's: old data replayed by every camera does not.
  const int64_t span = cam.run_last_t - cam.run_first_t;
  return SaturatedSub(master.newest_t, cam.run_first_master) >= span / 2;
}

void SyncBuffer::Impl::FollowNewClock(const CameraPose& pose) {
  const int c = pose.camera;
  CameraState& cam = cameras_[c];
  const int64_t old_offset = cam.offset_ns;
  // The run's mean of (stamp - master's newest), less the lead the camera had over the master.
  const double mean_y = static_cast<double>(cam.run_y0) + cam.run_dy_sum / cam.run;
  const double prior = mean_y - (cam.has_lead ? cam.lead_ns : 0.0);
  constexpr double kLimit = 9.0e18;
  const int64_t prior_ns = std::llround(std::clamp(prior, -kLimit, kLimit));
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

void SyncBuffer::Impl::OnTimeline(const CameraPose& pose) {
  CameraState& cam = cameras_[pose.camera];
  cam.run = 0;
  if (!follows_[pose.camera] || !cameras_[0].any) return;
  const auto y = static_cast<double>(
      SaturatedSub(OnMasterClock(pose.camera, pose.t_ns), cameras_[0].newest_t));
  cam.lead_ns = cam.has_lead ? cam.lead_ns + kLeadGain * (y - cam.lead_ns) : y;
  cam.has_lead = true;
}

}  // namespace rigcal
