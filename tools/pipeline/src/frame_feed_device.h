// SPDX-License-Identifier: Apache-2.0
#pragma once
// FrameFeedDevice: a CameraDevice whose frames are handed in by another thread (the log replay
// reads every camera's images from one log and feeds them here). FeedUntil waits while the
// device's queue is full, so a slow VO holds the reader back instead of losing frames; the
// deadline lets the reader watch for a stop request meanwhile.
//
// Threads: one feeding thread calls Feed and End; the pipeline's capture thread calls Grab; any
// thread calls Interrupt.

#include <chrono>
#include <string>

#include "rigcal/base/bounded_queue.h"
#include "rigcal/capture/capture_device.h"

namespace rigcal::pipeline {

class FrameFeedDevice : public capture::CameraDevice {
 public:
  FrameFeedDevice(std::string name, double frame_rate_hz, size_t capacity)
      : name_(std::move(name)), frame_rate_hz_(frame_rate_hz), frames_(capacity) {}

  const std::string& name() const override { return name_; }
  double frame_rate_hz() const override { return frame_rate_hz_; }
  Expected<std::optional<capture::Frame>> Grab() override { return frames_.Pop(); }
  void Interrupt() override { frames_.Stop(); }

  enum class Fed { kFed, kStopped, kTimedOut };
  // Hands a frame over, waiting for room until `deadline` (then the frame stays with the
  // caller, kTimedOut); kStopped after Interrupt/End.
  Fed FeedUntil(capture::Frame& frame, std::chrono::steady_clock::time_point deadline) {
    using Push = BoundedQueue<capture::Frame>::WaitedPush;
    switch (frames_.PushWaitUntil(frame, deadline)) {
      case Push::kPushed:
        return Fed::kFed;
      case Push::kStopped:
        return Fed::kStopped;
      case Push::kTimedOut:
        return Fed::kTimedOut;
    }
    return Fed::kStopped;
  }
  // End of stream: Grab returns the queued frames, then nullopt.
  void End() { frames_.Stop(); }

 private:
  const std::string name_;
  const double frame_rate_hz_;
  BoundedQueue<capture::Frame> frames_;
};

}  // namespace rigcal::pipeline
