// SPDX-License-Identifier: Apache-2.0
#pragma once
// SyncBuffer::Impl: the state of a SyncBuffer behind its one mutex. Private to rigcal_calib.
//   sync_matching.cc    producer side: Push and Flush, the classification of a pushed pose and
//                       the matching rule of sync_buffer.h
//   sync_buffer_impl.cc construction, consumer side (Pop, TryPop), Stop, the counter snapshot
//
// Threads: producers call Push (and Flush), the consumer calls Pop/TryPop, any thread calls
// Stop, stopped and stats; every public function takes mutex_ itself (RIGCAL_EXCLUDES), the
// private ones run with it held (RIGCAL_REQUIRES). A push does O(num_cameras * capacity) work
// under the lock, so finer locking would not pay.

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <limits>
#include <optional>
#include <vector>

#include "rigcal/base/thread_annotations.h"
#include "rigcal/calib/sync_buffer.h"
#include "sync/fixed_ring.h"

namespace rigcal {

// No stamp (on the master clock a stamp may be negative).
inline constexpr int64_t kNoStamp = std::numeric_limits<int64_t>::min();

// a - b, saturated to the int64_t range (stamps moved to the master clock by an offset).
inline int64_t SaturatedSub(int64_t a, int64_t b) {
  int64_t out = 0;
  if (!__builtin_sub_overflow(a, b, &out)) return out;
  return b < 0 ? std::numeric_limits<int64_t>::max() : std::numeric_limits<int64_t>::min();
}

// a + b, saturated likewise.
inline int64_t SaturatedAdd(int64_t a, int64_t b) {
  int64_t out = 0;
  if (!__builtin_add_overflow(a, b, &out)) return out;
  return b > 0 ? std::numeric_limits<int64_t>::max() : std::numeric_limits<int64_t>::min();
}

// What identifies an entry in time: its stamp and trigger sequence number.
struct SyncKey {
  int64_t t_ns = 0;
  int64_t seq = -1;
};

class SyncBuffer::Impl {
 public:
  // Allocates all storage; `options` must be valid (SyncBuffer checks them).
  explicit Impl(const SyncOptions& options);

  const SyncOptions& options() const { return options_; }

  // SyncBuffer's functions of the same name (sync_buffer.h).
  PushResult Push(const CameraPose& pose) RIGCAL_EXCLUDES(mutex_);
  void SkipConsumed(const std::vector<int64_t>& consumed_t_ns) RIGCAL_EXCLUDES(mutex_);
  void Flush() RIGCAL_EXCLUDES(mutex_);
  bool Pop(MatchedSet* out, std::chrono::milliseconds timeout) RIGCAL_EXCLUDES(mutex_);
  bool TryPop(MatchedSet* out) RIGCAL_EXCLUDES(mutex_);
  void Stop() RIGCAL_EXCLUDES(mutex_);
  bool stopped() const RIGCAL_EXCLUDES(mutex_);
  SyncStats stats() const RIGCAL_EXCLUDES(mutex_);
  uint64_t ReadyBound() const RIGCAL_EXCLUDES(mutex_);
  void SetTimeOffset(int camera, int64_t offset_ns, std::optional<uint64_t> after_jumps,
                     std::optional<uint64_t> after_master_jumps) RIGCAL_EXCLUDES(mutex_);
  ClockJump ClockJumps(int camera) const RIGCAL_EXCLUDES(mutex_);

 private:
  struct CameraState {
    explicit CameraState(size_t capacity)
        : ring(capacity, CameraPose{}), contributed(capacity, uint8_t{0}) {}

    FixedRing<CameraPose> ring;  // strictly increasing t_ns
    // Interpolation mode: per entry of `ring` (kept in step with it), whether it served a set.
    FixedRing<uint8_t> contributed;
    int64_t offset_ns = 0;        // interpolation mode: stamp - master clock (SetTimeOffset)
    bool any = false;             // an entry was ever accepted
    int64_t newest_t = 0;         // stamp of the newest accepted entry
    int64_t newest_seq = -1;      // highest trigger_seq accepted (-1: none)
    bool newest_has_seq = false;  // whether the newest accepted entry carries a trigger_seq
    bool any_used = false;        // an entry was a member of an emitted set
    SyncKey last_used;            // the member of the last emitted set that had this camera
    SyncCameraStats stats;        // fill is filled in by stats()
    // Clock glitches: the stamp of the last pose held back as a jump ahead, how many poses in a
    // row have followed it on the new timeline at the camera's steady rate, the other cameras'
    // pushes when that run began (a run while they are silent), whether the run was named as
    // unconfirmed, and whether a burst is being reported.
    int64_t jump_t = 0;
    int jump_run = 0;
    uint64_t jump_others_pushed = 0;
    bool jump_named = false;
    bool in_glitch_burst = false;
    int accepted_in_row = 0;  // accepted poses since the last rejected stamp
    // The camera's recent frame intervals (a fixed ring of the last kIntervals, in order of
    // arrival) and how many of them are measured.
    static constexpr int kIntervals = 8;
    int64_t intervals[kIntervals] = {};
    int interval_count = 0;
    // Resume: stamps at or before this were consumed before the restart (-1: none).
    int64_t consumed_t = -1;
    // Clock jumps (sync_clock_jump.cc): the camera's lead over its reference (ClockReference) at
    // its accepted poses (stamp on the master clock - reference, smoothed), and the run of
    // rejected poses on a new timeline: its length, first and last stamp, the reference at its
    // first pose, and the sum of (stamp - reference - run_y0) over it.
    double lead_ns = 0.0;
    bool has_lead = false;
    int run = 0;
    int64_t run_first_t = 0;
    int64_t run_last_t = 0;
    int64_t run_first_reference = 0;
    int64_t run_y0 = 0;
    double run_dy_sum = 0.0;
    ClockJump jump;  // the jumps followed
  };

  // The partner of the current master entry in one slave ring.
  struct Candidate {
    int index = -1;  // in the ring; -1: none
    int64_t distance = 0;
    bool final = false;
    // Interpolation mode: the entries [first, first + count) of the ring give the pose at
    // target_ns (count 1: that entry as it is; 2: linear; 4: cubic).
    int first = -1;
    int count = 0;
    int64_t target_ns = 0;
  };

  // sync_matching.cc: see the matching rule in sync_buffer.h.

  // Both entries carry a trigger sequence number and trigger mode is on.
  bool SeqPair(int64_t seq_a, int64_t seq_b) const { return by_seq_ && seq_a >= 0 && seq_b >= 0; }
  // True when slave entry `s` cannot match any master entry newer than `m` (masters arrive with
  // increasing stamps and sequence numbers).
  bool Unmatchable(const SyncKey& s, const SyncKey& m) const {
    if (SeqPair(s.seq, m.seq)) return s.seq <= m.seq;
    return s.t_ns <= m.t_ns - tolerance_ns_;
  }
  // kAccepted, or why `pose` (of a camera in range) is rejected.
  PushResult Classify(const CameraPose& pose) const RIGCAL_REQUIRES(mutex_);
  // Whether `pose` (otherwise acceptable) is a clock glitch: see sync_buffer.h. Updates the
  // camera's jump confirmation.
  bool ClockGlitch(const CameraPose& pose) RIGCAL_REQUIRES(mutex_);
  // Whether the run of jumps ahead of camera `c` (its jump_run poses up to jump_t) is confirmed
  // as a new timeline of the stream: see "Clock glitches" in sync_buffer.h.
  bool JumpConfirmed(int c) const RIGCAL_REQUIRES(mutex_);
  // Poses of a run of jumps ahead that confirm it while every other camera is silent: the glitch
  // horizon at the camera's frame `interval` (40 at 20 Hz), at least kJumpConfirmations.
  int LonePoses(int64_t interval) const;
  // Pushes of every camera but `c` so far.
  uint64_t OthersPushed(int c) const RIGCAL_REQUIRES(mutex_);
  // Whether `pose` lies more than the glitch horizon behind its camera's or the stream's clock.
  bool PastGlitch(const CameraPose& pose) const RIGCAL_REQUIRES(mutex_);
  // The median of camera `c`'s recent frame intervals; 0 while fewer than 4 are measured.
  int64_t RecentInterval(int c) const RIGCAL_REQUIRES(mutex_);
  // The newest stamp of any camera but `c` on the master clock; kNoStamp when none has data.
  int64_t OthersNewest(int c) const RIGCAL_REQUIRES(mutex_);
  // A stamp of camera `c` on the master clock (interpolation mode: minus the camera's offset,
  // saturated), the stamp itself otherwise.
  int64_t OnMasterClock(int c, int64_t t_ns) const RIGCAL_REQUIRES(mutex_);
  // sync_clock_jump.cc: the clock jumps of following slaves (see sync_buffer.h).

  // Whether a pose of a following camera rejected as `why` continues a run on a new timeline
  // that is now to be followed.
  bool NewClock(const CameraPose& pose, PushResult why) RIGCAL_REQUIRES(mutex_);
  // Follows the camera's new timeline (the run ending with `pose`): empties its ring, sets the
  // offset prior, counts and warns.
  void FollowNewClock(const CameraPose& pose) RIGCAL_REQUIRES(mutex_);
  // The master's: resolves its old entries, steps every slave's offset and the stream's clocks
  // by the master's step, counts and warns.
  void FollowNewMasterClock(const CameraPose& pose) RIGCAL_REQUIRES(mutex_);
  // What camera `c`'s clock is compared with: for a slave the master's newest stamp, for the
  // master the newest stamp of any slave on the master clock; kNoStamp when there is none.
  int64_t ClockReference(int c) const RIGCAL_REQUIRES(mutex_);
  // After an accepted pose of camera `c`: its lead over the master, and the end of any run.
  void OnTimeline(const CameraPose& pose) RIGCAL_REQUIRES(mutex_);

  // One warning per burst of rejected stamps of a camera (ended by kQuietPoses accepted poses in
  // a row).
  void WarnOncePerBurst(const CameraPose& pose, PushResult why) RIGCAL_REQUIRES(mutex_);
  // Buffers an accepted pose (dropping its ring's oldest entry when full).
  void Accept(const CameraPose& pose) RIGCAL_REQUIRES(mutex_);
  // Stream time against which master entries time out.
  int64_t WaitClockNs() const RIGCAL_REQUIRES(mutex_);
  // The entry of slave `j` closest to master `m` among those that match it.
  Candidate FindCandidate(int j, const CameraPose& m) const RIGCAL_REQUIRES(mutex_);
  // Whether an entry still to come from slave `j` could match master `m` strictly closer than
  // `c` (any match at all when c has none).
  bool CloserCanArrive(int j, const CameraPose& m, const Candidate& c) const
      RIGCAL_REQUIRES(mutex_);
  // sync_interpolation.cc: interpolation mode.

  // The interpolation of slave `j` at master `m`'s instant (see the rule in the header).
  Candidate FindInterpolation(int j, const CameraPose& m) const RIGCAL_REQUIRES(mutex_);
  // The pose of candidate `c` of slave `j`; marks the entries it uses as contributed.
  CameraPose TakeInterpolation(int j, const Candidate& c) RIGCAL_REQUIRES(mutex_);
  // Drops slave j's entries that no master after `m` can use.
  void ResolvedInterpolated(int j, const SyncKey& m) RIGCAL_REQUIRES(mutex_);
  // Removes the oldest entry of camera `c`'s ring, counted `used` when it served a set, else
  // in `unused` (a SyncCameraStats counter).
  void PopOldest(int c, uint64_t SyncCameraStats::*unused) RIGCAL_REQUIRES(mutex_);
  // Newest stamp of camera `c` on the master clock (the stream start when it has none).
  int64_t NewestOnMasterClock(int c) const RIGCAL_REQUIRES(mutex_);

  // An optional slave that fell more than max_wait behind the stream holds no set back.
  bool Stale(int j) const RIGCAL_REQUIRES(mutex_);
  // Resolves master entries from the oldest on (see the rule in the header); returns the
  // number of sets emitted. `flush`: treat every master entry as timed out.
  int Process(bool flush) RIGCAL_REQUIRES(mutex_);
  // Emits the oldest master entry with candidates_ as partners.
  void Emit() RIGCAL_REQUIRES(mutex_);
  // Drops the oldest master entry as never matched.
  void DropMaster() RIGCAL_REQUIRES(mutex_);
  // Master entry `m` left the buffer: slave entries that cannot match a later master go.
  void Resolved(const SyncKey& m) RIGCAL_REQUIRES(mutex_);

  // sync_buffer_impl.cc.

  // Moves the oldest ready set into *out; false when none is ready.
  bool TakeReady(MatchedSet* out) RIGCAL_REQUIRES(mutex_);

  // Immutable after construction.
  const SyncOptions options_;
  const int n_;
  const int64_t tolerance_ns_;
  const int64_t max_wait_ns_;
  const int64_t glitch_horizon_ns_;
  const bool by_seq_;
  const bool interpolate_;
  const int64_t max_gap_ns_;    // interpolation: no interpolation across a larger gap
  const int64_t snap_ns_;       // interpolation: an entry this close to the instant is taken as is
  std::vector<bool> required_;  // per camera; [0] is true
  std::vector<bool> follows_;   // per camera: follow_clock_jumps (interpolation mode only)

  mutable Mutex mutex_;
  std::condition_variable ready_cv_;  // signalled when a set is emitted and on Stop
  std::vector<CameraState> cameras_ RIGCAL_GUARDED_BY(mutex_);
  FixedRing<MatchedSet> ready_ RIGCAL_GUARDED_BY(mutex_);
  std::vector<Candidate> candidates_ RIGCAL_GUARDED_BY(mutex_);  // scratch of Process, per camera
  bool has_stream_ RIGCAL_GUARDED_BY(mutex_) = false;
  int64_t stream_start_ns_ RIGCAL_GUARDED_BY(mutex_) = 0;  // first accepted stamp
  int64_t now_ns_ RIGCAL_GUARDED_BY(mutex_) = 0;           // newest accepted stamp, any camera
  bool has_resolved_master_ RIGCAL_GUARDED_BY(mutex_) = false;
  SyncKey last_resolved_master_ RIGCAL_GUARDED_BY(mutex_);  // last master emitted or dropped
  bool stopped_ RIGCAL_GUARDED_BY(mutex_) = false;
  uint64_t unknown_camera_ RIGCAL_GUARDED_BY(mutex_) = 0;
  uint64_t sets_emitted_ RIGCAL_GUARDED_BY(mutex_) = 0;
  uint64_t sets_popped_ RIGCAL_GUARDED_BY(mutex_) = 0;
  uint64_t consumer_overflow_ RIGCAL_GUARDED_BY(mutex_) = 0;
};

}  // namespace rigcal
