// SPDX-License-Identifier: Apache-2.0
// SimulatedCamera: one camera of a simulated rig as a capture device (pacing, drops, failures,
// interruption).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <sstream>

#include "rigcal/base/logging.h"
#include "rigcal/base/thread_annotations.h"
#include "rigcal/sim/simulated_rig.h"
#include "sim_rig_clock.h"
#include "sim_rig_data.h"

namespace rigcal::sim {

using internal::MonotonicNs;

struct SimulatedCamera::State {
  Mutex mutex;
  std::condition_variable cv;  // signalled by Interrupt
  bool interrupted RIGCAL_GUARDED_BY(mutex) = false;
  std::vector<float> acc;
  std::vector<internal::Hit> hits;
};

SimulatedCamera::SimulatedCamera(std::shared_ptr<const internal::SimulatedRigData> data,
                                 std::shared_ptr<internal::RigClock> clock, int camera)
    : data_(std::move(data)),
      clock_(std::move(clock)),
      camera_(camera),
      state_(std::make_unique<State>()) {}

SimulatedCamera::~SimulatedCamera() = default;

const std::string& SimulatedCamera::name() const { return data_->spec.names[camera_]; }

double SimulatedCamera::frame_rate_hz() const { return data_->spec.frame_rate_hz; }

void SimulatedCamera::Interrupt() {
  {
    MutexLock lock(state_->mutex);
    state_->interrupted = true;
  }
  state_->cv.notify_all();
}

Expected<std::optional<capture::Frame>> SimulatedCamera::Grab() {
  const internal::SimulatedRigData& d = *data_;
  const SimulatedRigSpec& spec = d.spec;
  // Waits until CLOCK_MONOTONIC reaches t_ns; false when interrupted.
  auto wait_until = [this](int64_t t_ns) {
    MutexLock lock(state_->mutex);
    const auto deadline = std::chrono::steady_clock::time_point(std::chrono::nanoseconds(t_ns));
    while (!state_->interrupted) {
      if (lock.WaitUntil(state_->cv, deadline) == std::cv_status::timeout) break;
    }
    return !state_->interrupted;
  };
  {
    MutexLock lock(state_->mutex);
    if (state_->interrupted) return std::optional<capture::Frame>();
  }
  const std::optional<double> fail_after = d.fail_after_s[camera_];
  auto failure = [&]() {
    std::ostringstream msg;
    msg << name() << ": simulated camera failure at stream time " << *fail_after
        << " s (source.fail_after_s)";
    return Error{msg.str()};
  };
  if (failed_) return failure();
  const int64_t epoch = spec.realtime ? clock_->StartOnce() : spec.start_time_ns;
  // Frame k's nominal stamp (in realtime on the rig clock, which may follow a trigger's).
  auto due_ns = [&](int64_t k) {
    return spec.realtime ? clock_->HostNs(d.OffsetNs(k)) : epoch + d.OffsetNs(k);
  };
  const int64_t period_ns = std::llround(1e9 / spec.frame_rate_hz);
  while (next_frame_ < d.num_frames) {
    int64_t k = next_frame_;
    if (spec.realtime) {
      const int64_t late = MonotonicNs() - due_ns(k);
      if (late > period_ns) {
        // The frames that were due meanwhile are gone, as from an overflowing driver buffer.
        const int64_t newest = std::min<int64_t>(
            d.num_frames,
            static_cast<int64_t>(std::floor(static_cast<double>(MonotonicNs() - epoch) * 1e-9 *
                                            spec.frame_rate_hz)));
        if (newest > k) {
          late_skipped_ += newest - k;
          if (late_skipped_ == newest - k || late_skipped_ % 100 == 0) {
            ModuleLogger("sim")->warn("{}: rendering fell behind real time; {} frames skipped",
                                      name(), late_skipped_);
          }
          k = next_frame_ = newest;
          if (k >= d.num_frames) break;
        }
      }
    }
    if (fail_after && d.StreamTime(k) >= *fail_after) {
      if (spec.realtime && !wait_until(due_ns(k))) {
        return std::optional<capture::Frame>();
      }
      failed_ = true;
      ModuleLogger("sim")->warn("{}: simulated failure at stream time {} s", name(), *fail_after);
      return failure();
    }
    ++next_frame_;
    if (d.Dropped(camera_, k)) {
      ++dropped_;
      continue;
    }
    capture::Frame frame;
    frame.camera = camera_;
    frame.seq = k;
    frame.image = d.Render(camera_, k, &state_->acc, &state_->hits, RenderKernel::kSimd);
    if (d.Blackout(camera_, k)) frame.image.setTo(0);
    if (spec.realtime && !wait_until(due_ns(k))) return std::optional<capture::Frame>();
    frame.t_ns = due_ns(k) + d.JitterNs(camera_, k);  // after the wait: the clock may move
    return std::optional<capture::Frame>(std::move(frame));
  }
  return std::optional<capture::Frame>();
}

}  // namespace rigcal::sim
