// SPDX-License-Identifier: Apache-2.0
// The producer side of SyncBuffer: Push and Flush, the classification of a pushed pose, and the
// matching rule stated in rigcal/calib/sync_buffer.h. Runs with the buffer's mutex held.
#include <algorithm>
#include <cmath>

#include "rigcal/base/logging.h"
#include "sync/sync_buffer_impl.h"

namespace rigcal {
namespace {

bool IsValid(const CameraPose& p) {
  return p.t_ns >= 0 && p.pose.q.coeffs().allFinite() && p.pose.q.coeffs().squaredNorm() > 0.0 &&
         p.pose.C.allFinite() && std::isfinite(p.quality);
}

SyncKey KeyOf(const CameraPose& p) { return {p.t_ns, p.trigger_seq}; }

// Poses in a row on a jumped timeline that make the jump accepted.
constexpr int kJumpConfirmations = 5;
// Frame intervals ahead of its own rate (and of the other cameras) that make a stamp of a camera
// that follows clock jumps a step of its clock.
constexpr int64_t kFollowedGapIntervals = 6;
// Accepted poses in a row that end a burst of rejected stamps (its one warning).
constexpr int kQuietPoses = 50;

}  // namespace

PushResult SyncBuffer::Impl::Push(const CameraPose& pose) {
  MutexLock lock(mutex_);
  if (pose.camera < 0 || pose.camera >= n_) {
    ++unknown_camera_;
    return PushResult::kUnknownCamera;
  }
  CameraState& cam = cameras_[pose.camera];
  ++cam.stats.pushed;
  PushResult result = Classify(pose);
  if (result == PushResult::kAccepted && ClockGlitch(pose)) result = PushResult::kClockGlitch;
  if (result != PushResult::kAccepted && NewClock(pose, result)) {
    FollowNewClock(pose);
    result = PushResult::kAccepted;
  }
  switch (result) {
    case PushResult::kAccepted:
      break;
    case PushResult::kStopped:
      ++cam.stats.stopped;
      return result;
    case PushResult::kInvalid:
      ++cam.stats.invalid;
      return result;
    case PushResult::kLate:
      ++cam.stats.late;
      return result;
    case PushResult::kDuplicate:
      ++cam.stats.duplicate;
      WarnOncePerBurst(pose, result);
      return result;
    case PushResult::kOutOfOrder:
      ++cam.stats.out_of_order;
      WarnOncePerBurst(pose, result);
      return result;
    case PushResult::kClockGlitch:
      ++cam.stats.clock_glitch;
      WarnOncePerBurst(pose, result);
      return result;
    case PushResult::kConsumed:
      ++cam.stats.consumed;
      WarnOncePerBurst(pose, result);
      return result;
    case PushResult::kUnknownCamera:
      return result;
  }
  if (++cam.accepted_in_row >= kQuietPoses) cam.in_glitch_burst = false;
  Accept(pose);
  OnTimeline(pose);
  if (Process(/*flush=*/false) > 0) ready_cv_.notify_all();
  return PushResult::kAccepted;
}

void SyncBuffer::Impl::SkipConsumed(const std::vector<int64_t>& consumed_t_ns) {
  MutexLock lock(mutex_);
  for (int c = 0; c < n_ && c < static_cast<int>(consumed_t_ns.size()); ++c) {
    cameras_[c].consumed_t = consumed_t_ns[c];
  }
}

void SyncBuffer::Impl::WarnOncePerBurst(const CameraPose& pose, PushResult why) {
  CameraState& cam = cameras_[pose.camera];
  cam.accepted_in_row = 0;
  if (cam.in_glitch_burst) return;
  cam.in_glitch_burst = true;
  const char* what = why == PushResult::kClockGlitch
                         ? "far from the cameras' clocks: a clock glitch"
                     : why == PushResult::kDuplicate ? "a duplicate"
                     : why == PushResult::kConsumed
                         ? "at or before the stamp consumed before the restart (replayed data; a "
                           "new drive on a clock that restarted needs a fresh state)"
                         : "out of order";
  ModuleLogger("calib")->warn(
      "sync: camera {} pose stamped {} ns is {} (its newest {} ns, newest of any camera {} ns); "
      "not buffered (counted {}; warned once per burst)",
      pose.camera, pose.t_ns, what, cam.any ? cam.newest_t : -1, has_stream_ ? now_ns_ : -1,
      ToString(why));
}

int64_t SyncBuffer::Impl::RecentInterval(int c) const {
  const CameraState& cam = cameras_[c];
  if (cam.interval_count < 4) return 0;
  const int n = std::min(cam.interval_count, CameraState::kIntervals);
  int64_t sorted[CameraState::kIntervals];
  std::copy(cam.intervals, cam.intervals + n, sorted);
  std::nth_element(sorted, sorted + n / 2, sorted + n);
  return sorted[n / 2];
}

int64_t SyncBuffer::Impl::OnMasterClock(int c, int64_t t_ns) const {
  if (!interpolate_ || c == 0) return t_ns;
  return SaturatedSub(t_ns, cameras_[c].offset_ns);
}

int64_t SyncBuffer::Impl::OthersNewest(int c) const {
  int64_t newest = kNoStamp;
  for (int j = 0; j < n_; ++j) {
    if (j != c && cameras_[j].any) {
      newest = std::max(newest, OnMasterClock(j, cameras_[j].newest_t));
    }
  }
  return newest;
}

bool SyncBuffer::Impl::PastGlitch(const CameraPose& pose) const {
  if (by_seq_ || !has_stream_) return false;
  const CameraState& cam = cameras_[pose.camera];
  const int64_t clock =
      cam.any ? std::max(OnMasterClock(pose.camera, cam.newest_t), now_ns_) : now_ns_;
  // Stamp mode: stamps are >= 0 (IsValid) and clock <= INT64_MAX, no overflow; on the master
  // clock (interpolation mode) the difference saturates.
  return SaturatedSub(clock, OnMasterClock(pose.camera, pose.t_ns)) > glitch_horizon_ns_;
}

bool SyncBuffer::Impl::ClockGlitch(const CameraPose& pose) {
  if (by_seq_ || !has_stream_) return false;  // trigger mode: clocks may be offset
  CameraState& cam = cameras_[pose.camera];
  // now_ns_: the newest stamp of any camera, this one included, on the master clock. Own-clock
  // stamps are >= 0 (IsValid), so their differences cannot overflow; the master-clock ones
  // saturate.
  const int64_t t = OnMasterClock(pose.camera, pose.t_ns);
  bool ahead = SaturatedSub(t, now_ns_) > glitch_horizon_ns_;
  if (!ahead && cam.any) {
    // Against the camera's own recent rate, confirmed by the other cameras' clocks.
    const int64_t interval = RecentInterval(pose.camera);
    const int64_t others = OthersNewest(pose.camera);
    // A camera that follows clock jumps: a step of its clock beyond a few of its frame
    // intervals is one (sync_clock_jump.cc); others: a second at 20 Hz.
    const int64_t own_gap = (follows_[pose.camera] ? kFollowedGapIntervals : 20) * interval;
    ahead = interval > 0 && others != kNoStamp &&
            pose.t_ns - cam.newest_t > std::max(own_gap, max_wait_ns_) &&
            SaturatedSub(t, others) > max_wait_ns_;
  }
  if (!ahead) {
    cam.jump_run = 0;
    return false;
  }
  // Ahead of the clocks: a glitch unless the camera keeps to the new timeline at its steady rate
  // and the stream confirms it (Accept resets the other cameras' runs).
  const int64_t recent = RecentInterval(pose.camera);
  const int64_t interval = recent > 0 ? recent : options_.frame_period_ns;
  const int64_t step = pose.t_ns - cam.jump_t;  // own-clock stamps >= 0: no overflow
  if (cam.jump_run > 0 && step >= interval / 2 && step <= 3 * interval) {
    ++cam.jump_run;
  } else {
    cam.jump_run = 1;
    cam.jump_others_pushed = OthersPushed(pose.camera);
    cam.jump_named = false;
  }
  cam.jump_t = pose.t_ns;
  if (cam.jump_run >= kJumpConfirmations && JumpConfirmed(pose.camera)) {
    cam.jump_run = 0;
    return false;
  }
  if (cam.jump_run >= kJumpConfirmations && !cam.jump_named) {
    cam.jump_named = true;
    ModuleLogger("calib")->warn(
        "sync: camera {}: {} poses in a row on a timeline {:.3f} s ahead of the cameras' clocks "
        "(stamp {} ns) that no other camera shares: clock glitches, not a restart (one is "
        "followed once another camera's poses reach the new timeline, or after {} poses while "
        "every other camera is silent)",
        pose.camera, cam.jump_run, static_cast<double>(SaturatedSub(t, now_ns_)) * 1e-9, pose.t_ns,
        LonePoses(interval));
  }
  return true;
}

int SyncBuffer::Impl::LonePoses(int64_t interval) const {
  const int64_t poses = glitch_horizon_ns_ / std::max<int64_t>(interval, 1);
  return static_cast<int>(std::clamp<int64_t>(poses, kJumpConfirmations, 1 << 20));
}

uint64_t SyncBuffer::Impl::OthersPushed(int c) const {
  uint64_t pushed = 0;
  for (int j = 0; j < n_; ++j) {
    if (j != c) pushed += cameras_[j].stats.pushed;
  }
  return pushed;
}

bool SyncBuffer::Impl::JumpConfirmed(int c) const {
  const CameraState& cam = cameras_[c];
  const int64_t t = OnMasterClock(c, cam.jump_t);
  // Another camera's poses on the same new timeline (its run of jumps ahead, near this one).
  for (int j = 0; j < n_; ++j) {
    if (j == c || cameras_[j].jump_run == 0) continue;
    const int64_t d = SaturatedSub(OnMasterClock(j, cameras_[j].jump_t), t);
    if (d >= -glitch_horizon_ns_ && d <= glitch_horizon_ns_) return true;
  }
  // Every other camera silent (no push at all) for as long as the horizon at the camera's rate.
  const int64_t recent = RecentInterval(c);
  const int64_t interval = recent > 0 ? recent : options_.frame_period_ns;
  return OthersPushed(c) == cam.jump_others_pushed && cam.jump_run >= LonePoses(interval);
}

void SyncBuffer::Impl::Flush() {
  MutexLock lock(mutex_);
  if (Process(/*flush=*/true) > 0) ready_cv_.notify_all();
}

PushResult SyncBuffer::Impl::Classify(const CameraPose& pose) const {
  if (stopped_) return PushResult::kStopped;
  if (!IsValid(pose)) return PushResult::kInvalid;
  const CameraState& cam = cameras_[pose.camera];
  if (pose.t_ns <= cam.consumed_t) return PushResult::kConsumed;
  if (PastGlitch(pose)) return PushResult::kClockGlitch;
  const SyncKey key = KeyOf(pose);
  if (cam.any_used && (key.t_ns <= cam.last_used.t_ns ||
                       (SeqPair(key.seq, cam.last_used.seq) && key.seq <= cam.last_used.seq)))
    return PushResult::kLate;
  if (pose.camera != 0 && !interpolate_ && has_resolved_master_ &&
      Unmatchable(key, last_resolved_master_))
    return PushResult::kLate;
  if (cam.any && (key.t_ns == cam.newest_t || (key.seq >= 0 && key.seq == cam.newest_seq)))
    return PushResult::kDuplicate;
  for (size_t i = 0; i < cam.ring.size(); ++i) {
    const CameraPose& e = cam.ring[i];
    if (e.t_ns == key.t_ns || (key.seq >= 0 && e.trigger_seq == key.seq))
      return PushResult::kDuplicate;
  }
  if (cam.any && key.t_ns < cam.newest_t) return PushResult::kOutOfOrder;
  if (SeqPair(key.seq, cam.newest_seq) && key.seq < cam.newest_seq) return PushResult::kOutOfOrder;
  return PushResult::kAccepted;
}

void SyncBuffer::Impl::Accept(const CameraPose& pose) {
  CameraState& cam = cameras_[pose.camera];
  if (interpolate_ && pose.camera != 0) {
    if (cam.ring.full()) PopOldest(pose.camera, &SyncCameraStats::overflow);
    cam.ring.PushBack() = pose;
    cam.contributed.PushBack() = 0;
  } else {
    if (cam.ring.full()) {
      cam.ring.PopFront();
      ++cam.stats.overflow;
    }
    cam.ring.PushBack() = pose;
  }
  if (cam.any && pose.t_ns > cam.newest_t) {
    cam.intervals[cam.interval_count % CameraState::kIntervals] = pose.t_ns - cam.newest_t;
    ++cam.interval_count;
    if (cam.interval_count >= 2 * CameraState::kIntervals)
      cam.interval_count -= CameraState::kIntervals;
  }
  // A pose on the current timeline: a jump of another camera is not every camera's.
  for (int j = 0; j < n_; ++j) {
    if (j != pose.camera) cameras_[j].jump_run = 0;
  }
  cam.any = true;
  cam.newest_t = pose.t_ns;
  cam.newest_has_seq = pose.trigger_seq >= 0;
  if (pose.trigger_seq >= 0) cam.newest_seq = pose.trigger_seq;
  const int64_t t = OnMasterClock(pose.camera, pose.t_ns);
  if (!has_stream_) {
    has_stream_ = true;
    stream_start_ns_ = t;
    now_ns_ = t;
  }
  if (t > now_ns_) now_ns_ = t;
}

int64_t SyncBuffer::Impl::WaitClockNs() const {
  if (interpolate_) {
    int64_t now = NewestOnMasterClock(0);
    for (int c = 1; c < n_; ++c) now = std::max(now, NewestOnMasterClock(c));
    return now;
  }
  return by_seq_ ? cameras_[0].newest_t : now_ns_;
}

SyncBuffer::Impl::Candidate SyncBuffer::Impl::FindCandidate(int j, const CameraPose& m) const {
  Candidate best;
  const FixedRing<CameraPose>& ring = cameras_[j].ring;
  for (size_t i = 0; i < ring.size(); ++i) {
    const CameraPose& s = ring[i];
    if (SeqPair(s.trigger_seq, m.trigger_seq)) {
      if (s.trigger_seq == m.trigger_seq) return {static_cast<int>(i), 0, false};
      continue;
    }
    const int64_t d = s.t_ns >= m.t_ns ? s.t_ns - m.t_ns : m.t_ns - s.t_ns;
    if (d <= tolerance_ns_ && (best.index < 0 || d < best.distance))
      best = {static_cast<int>(i), d, false};
    if (!by_seq_ && s.t_ns > m.t_ns) break;  // later entries are farther away
  }
  return best;
}

bool SyncBuffer::Impl::CloserCanArrive(int j, const CameraPose& m, const Candidate& c) const {
  const CameraState& cam = cameras_[j];
  if (c.index >= 0 && c.distance == 0) return false;
  if (!cam.any) return true;
  if (by_seq_ && m.trigger_seq >= 0 && cam.newest_has_seq) return cam.newest_seq < m.trigger_seq;
  // Future stamps are > newest_t; closer means at most m.t_ns + reach.
  const int64_t reach = c.index >= 0 ? c.distance - 1 : tolerance_ns_;
  return cam.newest_t - m.t_ns < reach;
}

bool SyncBuffer::Impl::Stale(int j) const {
  if (by_seq_) return false;
  if (interpolate_) return WaitClockNs() - NewestOnMasterClock(j) > max_wait_ns_;
  const CameraState& cam = cameras_[j];
  const int64_t newest = cam.any ? cam.newest_t : stream_start_ns_;
  return now_ns_ - newest > max_wait_ns_;
}

int SyncBuffer::Impl::Process(bool flush) {
  int emitted = 0;
  FixedRing<CameraPose>& masters = cameras_[0].ring;
  while (!masters.empty()) {
    const CameraPose& m = masters.front();
    bool impossible = false;
    bool all_final = true;
    bool required_present = true;
    for (int j = 1; j < n_ && !impossible; ++j) {
      Candidate& c = candidates_[j];
      if (interpolate_) {
        c = FindInterpolation(j, m);
        c.final = c.final || (!required_[j] && Stale(j));
      } else {
        c = FindCandidate(j, m);
        c.final = !CloserCanArrive(j, m, c) || (!required_[j] && Stale(j));
      }
      all_final = all_final && c.final;
      if (required_[j] && c.index < 0) {
        required_present = false;
        impossible = c.final;
      }
    }
    if (impossible) {
      DropMaster();
      continue;
    }
    if (all_final) {
      Emit();
      ++emitted;
      continue;
    }
    if (!flush && WaitClockNs() - m.t_ns <= max_wait_ns_) break;
    if (required_present) {
      Emit();
      ++emitted;
    } else {
      DropMaster();
    }
  }
  return emitted;
}

void SyncBuffer::Impl::Emit() {
  if (ready_.full()) {
    // The consumer fell behind: the oldest ready set is lost, and with it one entry of every
    // camera in it (counted where it happens, per camera).
    const MatchedSet& lost = ready_.front();
    for (int c = 0; c < n_; ++c) {
      if (lost.poses[c].has_value()) ++cameras_[c].stats.consumer_overflow;
    }
    ready_.PopFront();
    ++consumer_overflow_;
  }
  MatchedSet& set = ready_.PushBack();
  CameraState& master = cameras_[0];
  const SyncKey m = KeyOf(master.ring.front());
  set.t_ns = m.t_ns;
  set.master_clock_step_ns = master.jump.offset_ns;
  set.poses[0] = master.ring.front();
  master.ring.PopFront();
  ++master.stats.used;
  master.any_used = true;
  master.last_used = m;
  for (int j = 1; j < n_; ++j) {
    CameraState& cam = cameras_[j];
    const Candidate& c = candidates_[j];
    if (c.index < 0) {
      set.poses[j].reset();
      ++cam.stats.optional_missing;
      continue;
    }
    if (interpolate_) {
      set.poses[j] = TakeInterpolation(j, c);
      continue;
    }
    set.poses[j] = cam.ring[c.index];
    for (int i = 0; i < c.index; ++i) {
      cam.ring.PopFront();
      ++cam.stats.never_matched;
    }
    cam.last_used = KeyOf(cam.ring.front());
    cam.any_used = true;
    cam.ring.PopFront();
    ++cam.stats.used;
  }
  ++sets_emitted_;
  Resolved(m);
}

void SyncBuffer::Impl::DropMaster() {
  CameraState& master = cameras_[0];
  const SyncKey m = KeyOf(master.ring.front());
  master.ring.PopFront();
  ++master.stats.never_matched;
  Resolved(m);
}

void SyncBuffer::Impl::Resolved(const SyncKey& m) {
  has_resolved_master_ = true;
  last_resolved_master_ = m;
  for (int j = 1; j < n_; ++j) {
    if (interpolate_) {
      ResolvedInterpolated(j, m);
      continue;
    }
    CameraState& cam = cameras_[j];
    while (!cam.ring.empty() && Unmatchable(KeyOf(cam.ring.front()), m)) {
      cam.ring.PopFront();
      ++cam.stats.never_matched;
    }
  }
}

}  // namespace rigcal
