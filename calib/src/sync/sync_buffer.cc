// SPDX-License-Identifier: Apache-2.0
// SyncBuffer's public vocabulary (options, push results, the counters' report) and the
// forwarding to SyncBuffer::Impl (sync_buffer_impl.h), where the state and its mutex live.
#include "rigcal/calib/sync_buffer.h"

#include <algorithm>
#include <sstream>
#include <stdexcept>

#include "sync/sync_buffer_impl.h"

namespace rigcal {
namespace {

constexpr int kMaxCameras = 256;
constexpr int kMaxCapacity = 1 << 20;
constexpr int64_t kMaxDurationNs = 3'600'000'000'000;  // 1 h: keeps stamp sums far from overflow

}  // namespace

int64_t SyncOptions::EffectiveToleranceNs() const {
  return tolerance_ns > 0 ? tolerance_ns : frame_period_ns / 2;
}

int64_t SyncOptions::EffectiveMaxWaitNs() const {
  return max_wait_ns > 0 ? max_wait_ns : 3 * frame_period_ns;
}

bool SyncOptions::IsRequired(int camera) const {
  if (camera == 0 || required.empty()) return true;
  return camera > 0 && camera < static_cast<int>(required.size()) && required[camera];
}

Status SyncOptions::Check() const {
  std::ostringstream e;
  if (num_cameras < 1 || num_cameras > kMaxCameras)
    e << "num_cameras: must be in [1, " << kMaxCameras << "], got " << num_cameras;
  else if (capacity < 1 || capacity > kMaxCapacity)
    e << "capacity: must be in [1, " << kMaxCapacity << "], got " << capacity;
  else if (frame_period_ns <= 0 || frame_period_ns > kMaxDurationNs)
    e << "frame_period_ns: must be in (0, " << kMaxDurationNs << "], got " << frame_period_ns;
  else if (tolerance_ns < 0 || tolerance_ns > kMaxDurationNs)
    e << "tolerance_ns: must be in [0, " << kMaxDurationNs << "] (0 = frame_period_ns / 2), got "
      << tolerance_ns;
  else if (max_wait_ns < 0 || max_wait_ns > kMaxDurationNs)
    e << "max_wait_ns: must be in [0, " << kMaxDurationNs << "] (0 = 3 * frame_period_ns), got "
      << max_wait_ns;
  else if (!required.empty() && static_cast<int>(required.size()) != num_cameras)
    e << "required: must be empty or have num_cameras (" << num_cameras << ") flags, got "
      << required.size();
  else if (!required.empty() && !required[0])
    e << "required[0]: must be true: the master is in every set";
  else if (interpolate && match_by_trigger_seq)
    e << "interpolate: not with match_by_trigger_seq (free-running cameras have no trigger)";
  else if (!follow_clock_jumps.empty() &&
           static_cast<int>(follow_clock_jumps.size()) != num_cameras)
    e << "follow_clock_jumps: must be empty or have num_cameras (" << num_cameras << ") flags, got "
      << follow_clock_jumps.size();
  else if (!interpolate && std::find(follow_clock_jumps.begin(), follow_clock_jumps.end(), true) !=
                               follow_clock_jumps.end())
    e << "follow_clock_jumps: only with interpolate (cameras that run free)";
  else if (ready_capacity < 1 || ready_capacity > kMaxCapacity)
    e << "ready_capacity: must be in [1, " << kMaxCapacity << "], got " << ready_capacity;
  if (e.str().empty()) return Status::Ok();
  return Error{e.str()};
}

const char* ToString(PushResult result) {
  switch (result) {
    case PushResult::kAccepted:
      return "accepted";
    case PushResult::kStopped:
      return "stopped";
    case PushResult::kUnknownCamera:
      return "unknown_camera";
    case PushResult::kInvalid:
      return "invalid";
    case PushResult::kLate:
      return "late";
    case PushResult::kDuplicate:
      return "duplicate";
    case PushResult::kOutOfOrder:
      return "out_of_order";
    case PushResult::kClockGlitch:
      return "clock_glitch";
    case PushResult::kConsumed:
      return "consumed";
  }
  return "?";
}

std::string SyncStats::BriefReport() const {
  std::ostringstream s;
  s << "sets " << sets_emitted << " (popped " << sets_popped << ", ready " << ready_fill;
  if (consumer_overflow) s << ", consumer_overflow " << consumer_overflow;
  s << ")";
  if (unknown_camera) s << " unknown_camera " << unknown_camera;
  for (size_t c = 0; c < cameras.size(); ++c) {
    const SyncCameraStats& k = cameras[c];
    s << " | cam" << c << " pushed " << k.pushed << " used " << k.used << " fill " << k.fill;
    auto field = [&](const char* name, uint64_t v) {
      if (v) s << ' ' << name << ' ' << v;
    };
    field("never_matched", k.never_matched);
    field("overflow", k.overflow);
    field("late", k.late);
    field("duplicate", k.duplicate);
    field("out_of_order", k.out_of_order);
    field("clock_glitch", k.clock_glitch);
    field("consumed", k.consumed);
    field("invalid", k.invalid);
    field("stopped", k.stopped);
    field("optional_missing", k.optional_missing);
    field("consumer_overflow", k.consumer_overflow);
    field("clock_jumps", k.clock_jumps);
  }
  return s.str();
}

namespace {

const SyncOptions& CheckedSyncOptions(const SyncOptions& options) {
  RequireValid(options.Check(), "SyncOptions");
  return options;
}

}  // namespace

SyncBuffer::SyncBuffer(const SyncOptions& options)
    : impl_(std::make_unique<Impl>(CheckedSyncOptions(options))) {}

SyncBuffer::~SyncBuffer() = default;

const SyncOptions& SyncBuffer::options() const { return impl_->options(); }
PushResult SyncBuffer::Push(const CameraPose& pose) { return impl_->Push(pose); }
void SyncBuffer::SkipConsumed(const std::vector<int64_t>& consumed_t_ns) {
  impl_->SkipConsumed(consumed_t_ns);
}
bool SyncBuffer::Pop(MatchedSet* out, std::chrono::milliseconds timeout) {
  return impl_->Pop(out, timeout);
}
bool SyncBuffer::TryPop(MatchedSet* out) { return impl_->TryPop(out); }
void SyncBuffer::Flush() { impl_->Flush(); }
void SyncBuffer::Stop() { impl_->Stop(); }
bool SyncBuffer::stopped() const { return impl_->stopped(); }
SyncStats SyncBuffer::stats() const { return impl_->stats(); }
ClockJump SyncBuffer::ClockJumps(int camera) const { return impl_->ClockJumps(camera); }
uint64_t SyncBuffer::ReadyBound() const { return impl_->ReadyBound(); }
void SyncBuffer::SetTimeOffset(int camera, int64_t offset_ns, std::optional<uint64_t> after_jumps,
                               std::optional<uint64_t> after_master_jumps) {
  impl_->SetTimeOffset(camera, offset_ns, after_jumps, after_master_jumps);
}

}  // namespace rigcal
