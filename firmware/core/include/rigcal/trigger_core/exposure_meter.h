// SPDX-License-Identifier: Apache-2.0
#pragma once
// ExposureMeter: the measured exposure of each wired line's camera (VersaVIS-style exposure
// feedback). The board's input-capture channel of a wired line latches the µs counter at the
// edges of the camera's exposure-active output; the meter pairs them into exposures and queues
// an ExposureReport {seq, line, start, duration} per exposure for the main loop to send.
//
// Per line it expects, in turn, the edge to the active level (start) and the edge back (end); the
// board captures exactly that edge next (ExpectsStart). A start belongs to the line's last rise
// (Scheduler::LastRise) when it lies within one period after it (a camera exposes after its
// trigger, before the next one); an end closes the exposure when it lies within kMaxExposureUs
// after the start. Anything else, and an overcapture (two edges before the interrupt read the
// first: an exposure shorter than the interrupt's response), is counted (errors()) and dropped.
//
// Captures carry the counter's low 32 bits; they are extended against the last rise (start) or
// the start (end), which lie within 2^31 µs (NearestTime).
//
// Contexts: Start in the main loop while the capture interrupts are off; OnCapture /
// OnOvercapture / ExpectsStart in the capture context (same priority as the compare interrupt);
// Pop in the main loop.

#include <atomic>
#include <cstdint>

#include "rigcal/trigger_core/scheduler.h"
#include "rigcal/trigger_core/spsc_ring.h"
#include "rigcal/trigger_protocol/messages.h"

namespace rigcal::trigger_core {

class ExposureMeter {
 public:
  static constexpr uint32_t kReportQueue = 32;

  // A run starts: every line waits for its exposure start; queued reports are kept.
  void Start();
  // Capture context: `line`'s input made the edge the meter expected, at count `count32`.
  void OnCapture(int line, uint32_t count32, const Scheduler& scheduler);
  // Capture context: edges were lost (overcapture): the line waits for a start again.
  void OnOvercapture(int line);
  // The edge the board should capture next on `line`: true = to the active level.
  bool ExpectsStart(int line) const { return !lines_[line].in_exposure; }

  // Main loop: the oldest queued report (removed); false when none.
  bool Pop(proto::ExposureReport* report);
  uint32_t errors() const { return errors_.load(std::memory_order_relaxed); }
  uint32_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

 private:
  struct LineState {
    bool in_exposure = false;
    uint32_t seq = 0;
    uint64_t start_us = 0;
  };
  void CountError();
  LineState lines_[proto::kMaxLines];
  SpscRing<proto::ExposureReport, kReportQueue> reports_;
  std::atomic<uint32_t> errors_{0};
  std::atomic<uint32_t> dropped_{0};
};

}  // namespace rigcal::trigger_core
