// SPDX-License-Identifier: Apache-2.0
// SyncBuffer::Impl's construction, consumer side (Pop, TryPop), Stop and counter snapshot; the
// producer side is in sync_matching.cc.
#include "sync/sync_buffer_impl.h"

#include <algorithm>

namespace rigcal {
namespace {

constexpr int64_t kMinGlitchHorizonNs = 2'000'000'000;  // 2 s

}  // namespace

SyncBuffer::Impl::Impl(const SyncOptions& options)
    : options_(options),
      n_(options.num_cameras),
      tolerance_ns_(options.EffectiveToleranceNs()),
      max_wait_ns_(options.EffectiveMaxWaitNs()),
      glitch_horizon_ns_(std::max(kMinGlitchHorizonNs, 10 * options.EffectiveMaxWaitNs())),
      by_seq_(options.match_by_trigger_seq),
      interpolate_(options.interpolate),
      max_gap_ns_(3 * options.frame_period_ns),
      snap_ns_(std::min(options.EffectiveToleranceNs(), options.frame_period_ns / 50)),
      ready_(static_cast<size_t>(options.ready_capacity),
             MatchedSet{0, std::vector<std::optional<CameraPose>>(options.num_cameras)}),
      candidates_(options.num_cameras) {
  for (int c = 0; c < n_; ++c) {
    required_.push_back(options.IsRequired(c));
    follows_.push_back(interpolate_ && c < static_cast<int>(options.follow_clock_jumps.size()) &&
                       options.follow_clock_jumps[c]);
  }
  cameras_.reserve(n_);
  for (int c = 0; c < n_; ++c) cameras_.emplace_back(static_cast<size_t>(options.capacity));
}

bool SyncBuffer::Impl::Pop(MatchedSet* out, std::chrono::milliseconds timeout) {
  if (out == nullptr) return false;
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  MutexLock lock(mutex_);
  while (ready_.empty() && !stopped_) {
    if (lock.WaitUntil(ready_cv_, deadline) == std::cv_status::timeout) break;
  }
  return TakeReady(out);
}

bool SyncBuffer::Impl::TryPop(MatchedSet* out) {
  if (out == nullptr) return false;
  MutexLock lock(mutex_);
  return TakeReady(out);
}

void SyncBuffer::Impl::Stop() {
  MutexLock lock(mutex_);
  stopped_ = true;
  ready_cv_.notify_all();
}

bool SyncBuffer::Impl::stopped() const {
  MutexLock lock(mutex_);
  return stopped_;
}

SyncStats SyncBuffer::Impl::stats() const {
  SyncStats s;
  s.cameras.resize(n_);
  MutexLock lock(mutex_);
  for (int c = 0; c < n_; ++c) {
    SyncCameraStats k = cameras_[c].stats;
    k.fill = cameras_[c].ring.size();
    s.cameras[c] = k;
    SyncCameraStats& t = s.total;
    t.pushed += k.pushed;
    t.used += k.used;
    t.stopped += k.stopped;
    t.invalid += k.invalid;
    t.late += k.late;
    t.duplicate += k.duplicate;
    t.out_of_order += k.out_of_order;
    t.clock_glitch += k.clock_glitch;
    t.consumed += k.consumed;
    t.overflow += k.overflow;
    t.never_matched += k.never_matched;
    t.optional_missing += k.optional_missing;
    t.consumer_overflow += k.consumer_overflow;
    t.fill += k.fill;
    t.clock_jumps += k.clock_jumps;
  }
  s.unknown_camera = unknown_camera_;
  s.sets_emitted = sets_emitted_;
  s.sets_popped = sets_popped_;
  s.consumer_overflow = consumer_overflow_;
  s.ready_fill = ready_.size();
  return s;
}

uint64_t SyncBuffer::Impl::ReadyBound() const {
  MutexLock lock(mutex_);
  return ready_.size() + cameras_[0].ring.size() + 1;
}

void SyncBuffer::Impl::SetTimeOffset(int camera, int64_t offset_ns,
                                     std::optional<uint64_t> after_jumps,
                                     std::optional<uint64_t> after_master_jumps) {
  MutexLock lock(mutex_);
  if (!interpolate_ || camera <= 0 || camera >= n_) return;
  if (after_jumps && *after_jumps != cameras_[camera].jump.count) return;
  if (after_master_jumps && *after_master_jumps != cameras_[0].jump.count) return;
  cameras_[camera].offset_ns = offset_ns;
}

ClockJump SyncBuffer::Impl::ClockJumps(int camera) const {
  MutexLock lock(mutex_);
  if (camera < 0 || camera >= n_) return {};
  return cameras_[camera].jump;
}

bool SyncBuffer::Impl::TakeReady(MatchedSet* out) {
  if (ready_.empty()) return false;
  const MatchedSet& set = ready_.front();
  out->t_ns = set.t_ns;
  out->master_clock_step_ns = set.master_clock_step_ns;
  out->poses = set.poses;  // reuses out's storage once it has num_cameras slots
  ready_.PopFront();
  ++sets_popped_;
  return true;
}

}  // namespace rigcal
