// SPDX-License-Identifier: Apache-2.0
#pragma once
// SyncBuffer: matches the odometry poses of all cameras of a rig by capture time (or by
// hardware trigger sequence number) and hands time-corresponding sets to the estimator.
//
// Threads: producers (one VO thread per camera, or an LCM receive thread) call Push, possibly
// concurrently; one consumer (the estimator thread) calls Pop/TryPop. The buffer owns no
// thread and starts none. Every member function is thread-safe.
//
// Memory: everything is allocated in the constructor: one fixed ring of `capacity` entries per
// camera and a fixed queue of `ready_capacity` matched sets. Nothing grows afterwards; a full
// ring or queue drops its oldest element, and every drop is counted in SyncStats by cause.
//
// Matching rule. Entries of each camera form a stream strictly increasing in t_ns (Push rejects
// the rest). Only the OLDEST buffered master entry m is ever resolved, so sets leave in strictly
// increasing master time; it is resolved (emitted or dropped) as soon as one of these holds:
//
//  * Partner of m in slave j: the entry s of j's ring that matches m with the smallest distance
//    (ties: the earlier entry). s matches m when, in trigger mode (match_by_trigger_seq) and both
//    carry a sequence number (>= 0), s.trigger_seq == m.trigger_seq (distance 0, stamps ignored);
//    otherwise when |s.t_ns - m.t_ns| <= tolerance (distance = |s.t_ns - m.t_ns|).
//  * The partner of j is FINAL when no entry still to come from j could be strictly closer: it
//    is exact (distance 0), or j's newest entry already lies at or beyond m.t_ns + distance - 1
//    (later entries are later still), or, without a partner, j's newest entry lies beyond
//    m.t_ns + tolerance. In trigger mode, when j's newest entry carries a sequence number, future
//    entries of j are assumed to carry increasing numbers too: a match can still arrive iff j's
//    newest number is < m's. An OPTIONAL slave that has fallen more than max_wait behind the
//    newest stamp of any camera (dead or badly lagging; stamp mode only) is final as it is.
//  * Emit m when every slave is final and every required slave has a partner; the set holds the
//    partners (an optional slave without one is left empty and counted optional_missing).
//  * Drop m (never_matched) as soon as a required slave is final without a partner.
//  * Timeout: when m has waited longer than max_wait in stream time (newest stamp of any camera
//    minus m.t_ns; in trigger mode the newest MASTER stamp, as slave clocks may be offset), m is
//    emitted with the partners it has if every required slave has one, else dropped
//    (never_matched).
//
// After m is resolved, each used slave entry and every older entry of its ring leave the ring
// (the older ones count never_matched: entries are used at most once, in time order), and slave
// entries that can no longer match any later master (stamp < m.t_ns - tolerance + 1, or in
// trigger mode sequence <= m's) are dropped as never_matched. Everything is deterministic: the
// same sequence of Push calls gives the same sets.
//
// Interpolation mode (interpolate: cameras that run free, their own instants and clocks).
// Slave j's stamps read the master clock + its time offset (SetTimeOffset, 0 until set). A
// slave's partner of m is its pose at the instant m.t_ns + offset_j, interpolated from its
// entries around that instant (pose_interpolation.h: cubic through two entries on either side,
// else SLERP/linear between the two around it), never across a gap of more than 3 frame
// periods or a segment change; an entry within min(tolerance, frame_period / 50) of the instant
// is taken as it is (synchronised stamps are matched exactly as in stamp mode). The partner is
// final once the entry after the one following the instant is there (or cannot help: gap,
// segment), or when no entry precedes the instant (no partner); timeouts and optional slaves
// as above, with stream time on the master clock (each camera's newest stamp minus its offset).
// The latency is therefore bounded by two slave frames plus the offset, or max_wait. The
// interpolated pose carries the instant (slave clock) as t_ns, trigger_seq -1, the segment of
// the entry before it and the lowest quality of the entries used. Slave entries stay in their
// ring while a later master may still use them (they are counted `used` when they leave it
// having served a set, never_matched otherwise); trigger numbers are ignored.
//
// Clock glitches (stamp mode only). A pose is not accepted (kClockGlitch, counted clock_glitch,
// one warning per burst of a camera; a burst ends after 50 accepted poses in a row) when it is
// stamped
//  * more than the glitch horizon (max(2 s, 10 * max_wait)) ahead of the newest stamp of every
//    camera (up to INT64_MAX), or
//  * ahead of its camera's own recent rate (more than max(20 of its recent frame intervals,
//    max_wait) after its newest stamp; 6 intervals for a camera that follows clock jumps) while
//    also more than max_wait ahead of every other camera's newest stamp (a clock that stepped
//    by a second), or
//  * more than the glitch horizon behind its camera's newest stamp or the newest stamp of any
//    camera (a stamp from the past).
// One such stamp would otherwise make every later pose of the camera out of order and time out
// every master entry. A jump ahead is a new timeline of the stream only when the data confirm
// it: the camera's poses ahead form a run at its steady rate (each between half and three of
// its recent frame intervals after the previous; 5 of them at least) while no other camera
// delivered a pose on the old timeline, and either another camera's poses ahead lie on the same
// new timeline (its own run, within the glitch horizon of this one: every camera paused and
// resumed) or every other camera stayed silent (no push at all) for as long as the glitch
// horizon at the camera's rate (40 poses at 20 Hz: the only camera left after a restart); or
// as soon as another camera's clock reaches it. A camera whose clock alone jumped is rejected
// until the others agree, and so are a few poses on a timeline of their own (ten stamped 4e18
// ns at the camera's rate, back to back in a log): named once in a warning ("... that no other
// camera shares: clock glitches"), counted clock_glitch, and no clock moves. Duplicates and
// poses out of order are warned about once per burst too.
//
// Clock jumps of free-running slaves (interpolation mode, slaves with follow_clock_jumps). In
// interpolation mode the rules above compare stamps on the master clock (a slave's stamp minus
// its offset). A slave whose clock restarted (its stamps step by seconds, or restart near 0)
// would be rejected by them forever; instead, poses of a following slave that the rules reject
// (clock glitch, out of order, duplicate, or consumed before a resume) start a run on a NEW
// timeline of the camera: each next rejected pose continues the run when it lies after the
// previous one by between half and three of the camera's recent frame intervals (a steady
// rate). When the run holds kNewClockPoses (10)
// poses and the master advanced by at least half the run's span meanwhile (the new clock runs
// with the master's: not a replay of old data, which the master would share), the new timeline
// is followed: the camera's ring is emptied (its entries counted used or never_matched), its
// offset becomes the step's prior (the mean of stamp - master's newest stamp over the run, less
// the camera's lead over the master before the step), the jump is counted (clock_jumps, a
// ClockJump record) and warned about once, and the run's last pose is accepted. An accepted pose
// on the old timeline ends a run: isolated glitches, bursts of them at no steady rate, and old
// data replayed by every camera stay rejected. Steps of at most 6 frame intervals ahead or
// fewer than 10 frames back stay on the old timeline here: the ClockOffsetTracker finds those
// (it searches ± its search window, 0.5 s, around the last offset).
//
// Clock jumps of the master (interpolation mode, follow_clock_jumps[0]). The same rule with
// the roles swapped: master poses that the rules reject (as above, or kLate: at or before its
// last emitted stamp) start a run on a new timeline of the master, continued by each next one
// between half and three of its recent frame intervals after the previous; after
// kNewClockPoses (10) of them, while the slaves' clocks advanced by at least half the run's span
// (their newest stamp on the master clock; a replay by every camera does not), the master's new
// timeline is followed: its buffered entries of the old timeline are resolved first (as by
// Flush), the step S of its clock is the run's mean of (stamp - the slaves' newest stamp on the
// old master clock) less the master's usual lead over them, and every stamp on the master clock
// moves with it: every slave's offset (and its ClockJump offset_ns) by -S (the slaves' rings and
// own stamps stay, so matching goes on without a new search), the stream's clocks by +S. It is
// counted on the master (stats clock_jumps of camera 0; ClockJumps(0): offset_ns the sum of the
// steps followed, step_ns the last one) and warned about once; sets carry the sum
// (MatchedSet::master_clock_step_ns). Isolated master glitches stay rejected; steps of at most 6
// frame intervals ahead or fewer than 10 frames back are accepted on the old timeline (every
// slave's ClockOffsetTracker sees its offset step).
//
// Resume: SkipConsumed(t) makes every pose of camera c stamped at or before t[c] kConsumed (the
// estimator took it before a restart), so replaying the same data after a resume adds nothing.

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"

namespace rigcal {

struct SyncOptions {
  // Cameras of the rig: index 0 is the master, 1..num_cameras-1 the slaves. In [1, 256].
  int num_cameras = 2;
  // Entries buffered per camera (a fixed ring allocated once). In [1, 2^20]. A push into a full
  // ring drops that ring's oldest entry (counted as overflow).
  int capacity = 64;
  // Nominal frame period of the cameras [ns] (50 ms: 20 Hz). Sets the defaults of tolerance_ns
  // and max_wait_ns. In (0, 1 h].
  int64_t frame_period_ns = 50'000'000;
  // Largest |t_slave - t_master| of a stamp match [ns], inclusive. 0 (default) means
  // frame_period_ns / 2. In [0, 1 h].
  int64_t tolerance_ns = 0;
  // How long a master entry waits for its partners [ns], measured in stream time (see the rule
  // above), before it is emitted with the partners it has or dropped as never matched.
  // 0 (default) means 3 * frame_period_ns. In [0, 1 h].
  int64_t max_wait_ns = 0;
  // required[i]: camera i must be in every set. Empty (default) = every camera. Otherwise one
  // flag per camera, and required[0] (the master) must be true. Optional slaves are included
  // when they have a partner when the set is emitted.
  std::vector<bool> required;
  // Trigger mode: entries that both carry a trigger sequence number (>= 0) match iff the numbers
  // are equal, whatever their stamps (cameras on different clocks). Entries without a number
  // still match by stamp. Sequence numbers must increase with t_ns within each camera.
  bool match_by_trigger_seq = false;
  // Interpolation mode (see above): slave poses interpolated at the master's instants at each
  // slave's time offset. Not with match_by_trigger_seq.
  bool interpolate = false;
  // Interpolation mode: per camera (empty = none), whether a restart of its clock is followed
  // (see "Clock jumps" above): for slaves whose offset is estimated, and [0] for the master
  // (every slave's offset then steps with it). Not without interpolate.
  std::vector<bool> follow_clock_jumps;
  // Matched sets held for the consumer (a fixed queue). In [1, 2^20]. When the consumer is too
  // slow the oldest ready set is dropped (counted as consumer_overflow).
  int ready_capacity = 32;

  // tolerance_ns, or frame_period_ns / 2 when it is 0.
  int64_t EffectiveToleranceNs() const;
  // max_wait_ns, or 3 * frame_period_ns when it is 0.
  int64_t EffectiveMaxWaitNs() const;
  // Whether camera `camera` must be in every set (the master always is).
  bool IsRequired(int camera) const;
  // Success, or the first offending field and its constraint: "<field>: <constraint>".
  Status Check() const;
};

// The outcome of one Push. Drops of OTHER entries caused by a push (overflow, never_matched)
// are only counted in SyncStats.
enum class PushResult {
  kAccepted,       // buffered (the ring's oldest entry may have been dropped as overflow)
  kStopped,        // Stop() was called
  kUnknownCamera,  // camera index outside [0, num_cameras)
  kInvalid,        // t_ns < 0, a non-finite or zero quaternion / centre, or non-finite quality
  kLate,           // can never be matched any more: not newer than this camera's member of the
                   // last emitted set, or (slaves) too old for any master still to come
  kDuplicate,      // same stamp, or same trigger_seq (>= 0), as a buffered entry of the camera
                   // (or as its newest entry ever accepted)
  kOutOfOrder,     // older than the newest entry accepted for the camera, but not late (in
                   // trigger mode also: a lower sequence number than the newest)
  kClockGlitch,    // a stamp far from every camera's clock (see "Clock glitches" above)
  kConsumed,       // at or before the camera's stamp consumed before a restart (SkipConsumed)
};
const char* ToString(PushResult result);

// One time-corresponding set: the master entry and its partners.
struct MatchedSet {
  int64_t t_ns = 0;  // the master's stamp [ns]
  // Indexed by camera; poses[0] (the master) and every required camera are always set, an
  // optional camera without a partner is empty. Sized num_cameras by Pop.
  std::vector<std::optional<CameraPose>> poses;
  // The sum of the master's clock steps followed before the set (ClockJumps(0).offset_ns then;
  // see "Clock jumps"): t_ns - master_clock_step_ns is the set's instant on the master's clock
  // as it ran before its first restart, a timeline that does not jump.
  int64_t master_clock_step_ns = 0;
};

// Counters of one camera since construction. For every camera:
//   pushed == used + Dropped() + fill.
struct SyncCameraStats {
  uint64_t pushed = 0;            // Push calls for this camera, whatever their outcome
  uint64_t used = 0;              // entries that became members of an emitted set
  uint64_t stopped = 0;           // rejected: Push after Stop
  uint64_t invalid = 0;           // rejected: PushResult::kInvalid
  uint64_t late = 0;              // rejected: PushResult::kLate
  uint64_t duplicate = 0;         // rejected: PushResult::kDuplicate
  uint64_t out_of_order = 0;      // rejected: PushResult::kOutOfOrder
  uint64_t clock_glitch = 0;      // rejected: PushResult::kClockGlitch
  uint64_t consumed = 0;          // rejected: PushResult::kConsumed
  uint64_t overflow = 0;          // accepted, then dropped as the oldest entry of a full ring
  uint64_t never_matched = 0;     // accepted, then dropped unused (see the matching rule)
  uint64_t optional_missing = 0;  // emitted sets without this (optional) camera
  // Entries of this camera that were members of an emitted set (counted in `used`) and were
  // lost with it when the full ready queue dropped it (SyncStats::consumer_overflow).
  uint64_t consumer_overflow = 0;
  uint64_t fill = 0;  // entries buffered now (<= capacity)
  // Restarts of the camera's clock followed (an event count, not a drop; see "Clock jumps").
  uint64_t clock_jumps = 0;

  uint64_t Dropped() const {
    return stopped + invalid + late + duplicate + out_of_order + clock_glitch + consumed +
           overflow + never_matched;
  }
};

// A snapshot of the counters. Sets: sets_emitted == sets_popped + consumer_overflow +
// ready_fill, and sets_emitted == cameras[0].used.
struct SyncStats {
  std::vector<SyncCameraStats> cameras;  // indexed by camera
  SyncCameraStats total;                 // sum over cameras
  uint64_t unknown_camera = 0;           // pushes with a camera index out of range
  uint64_t sets_emitted = 0;             // sets put into the ready queue
  uint64_t sets_popped = 0;              // sets handed to the consumer
  uint64_t consumer_overflow = 0;        // ready sets dropped because the queue was full
  uint64_t ready_fill = 0;               // ready sets waiting for the consumer now

  // One line for logs: sets, fills and the non-zero drop counters.
  std::string BriefReport() const;
};

// The clock jumps of one camera followed so far (see "Clock jumps" above).
struct ClockJump {
  uint64_t count = 0;  // jumps followed
  // A slave: the offset prior set at its last jump (stamp - master clock; stepped too by the
  // master's jumps since). The master: the sum of its steps (stamp - its clock at the start).
  int64_t offset_ns = 0;
  int64_t step_ns = 0;  // at the last one: the prior minus the offset before it (master: the step)
  int64_t t_ns = 0;     // at the last one: the stamp of the first pose accepted after it
};

class SyncBuffer {
 public:
  // Allocates all storage. Throws InvalidOptions ("SyncOptions: " and Check()'s message) when
  // `options` is invalid. Starts no thread.
  explicit SyncBuffer(const SyncOptions& options);
  ~SyncBuffer();
  SyncBuffer(const SyncBuffer&) = delete;
  SyncBuffer& operator=(const SyncBuffer&) = delete;

  const SyncOptions& options() const;

  // Offers one pose (copied). Any thread; concurrent calls are serialised. Never blocks on the
  // consumer and never allocates. Matched sets are emitted into the ready queue by this call
  // (see the matching rule); a full ready queue drops its oldest set. Returns kAccepted or the
  // reason the pose was rejected.
  PushResult Push(const CameraPose& pose);

  // Waits up to `timeout` for a ready set, copies the oldest one into *out and removes it from
  // the queue. out's storage is reused: no allocation once out->poses has held num_cameras
  // entries. Returns false on
  // timeout, or at once when Stop() was called and no ready set is left. `out` must not be null.
  // Meant for one consumer thread (several are safe, each set goes to one of them).
  bool Pop(MatchedSet* out, std::chrono::milliseconds timeout);
  // Pop without waiting: false when no set is ready.
  bool TryPop(MatchedSet* out);

  // End of stream (e.g. the end of a log): resolves every buffered master entry now, without
  // waiting for closer partners, as if its max_wait had passed (emitted with the partners it
  // has, or dropped as never_matched). Slave entries stay. Any thread; pushes may continue.
  void Flush();

  // Wakes every waiting Pop. Afterwards Push returns kStopped, and Pop returns the sets that are
  // still ready, then false. Buffered master entries are not flushed (call Flush first to get
  // them). Idempotent; any thread.
  void Stop();
  bool stopped() const;

  // Resume: poses of camera c stamped at or before consumed_t_ns[c] are rejected as kConsumed
  // (-1 or a missing entry: none). Call before the first Push; any thread.
  void SkipConsumed(const std::vector<int64_t>& consumed_t_ns);

  // A consistent snapshot of the counters (allocates the per-camera vector). Any thread.
  SyncStats stats() const;

  // Interpolation mode: slave `camera` (>= 1) stamps read master clock + offset_ns from now on
  // (see the rule above). Any thread. Ignored for the master, an unknown camera or in stamp mode,
  // and when `after_jumps` is given and differs from the camera's ClockJumps().count, or
  // `after_master_jumps` from the master's (the offset was estimated before a clock jump the
  // caller has not seen yet).
  void SetTimeOffset(int camera, int64_t offset_ns,
                     std::optional<uint64_t> after_jumps = std::nullopt,
                     std::optional<uint64_t> after_master_jumps = std::nullopt);

  // The clock jumps of `camera` followed so far (all zero for an unknown camera). Any thread.
  ClockJump ClockJumps(int camera) const;

  // How many sets could be ready once one more Push (or a Flush) has run: the sets ready now
  // plus the master entries buffered plus one (every set takes a master entry). A producer
  // that waits until this is <= options().ready_capacity never loses a set to
  // consumer_overflow (back-pressure, OnlineOptions::lossless). Any thread; never allocates.
  uint64_t ReadyBound() const;

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace rigcal
