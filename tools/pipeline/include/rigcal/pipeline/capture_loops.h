// SPDX-License-Identifier: Apache-2.0
#pragma once
// CaptureLoops: one thread per capture device that grabs frames until the device ends, fails or
// is interrupted, and discards them: the capture of `rigcal record --no-vo`, where the devices
// are LogRecorder taps and recording is all that happens to a frame.
//
// Threads: the owner calls Start, Finished, Stop and Problems; one thread per device calls its
// Grab. Start once; Stop interrupts the devices and joins (idempotent, also on destruction).

#include <atomic>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "rigcal/base/thread_annotations.h"
#include "rigcal/capture/capture_device.h"

namespace rigcal::pipeline {

class CaptureLoops {
 public:
  explicit CaptureLoops(std::vector<std::unique_ptr<capture::CameraDevice>> devices);
  ~CaptureLoops();
  CaptureLoops(const CaptureLoops&) = delete;
  CaptureLoops& operator=(const CaptureLoops&) = delete;

  void Start();
  // Every device has ended or failed.
  bool Finished() const { return running_.load() == 0; }
  void Stop();
  // "camera '<name>' died: <error>" for every device that failed.
  std::vector<std::string> Problems() const RIGCAL_EXCLUDES(mutex_);

 private:
  void Loop(size_t index);

  std::vector<std::unique_ptr<capture::CameraDevice>> devices_;
  std::vector<std::thread> threads_;
  std::atomic<int> running_;
  mutable Mutex mutex_;
  std::vector<std::string> problems_ RIGCAL_GUARDED_BY(mutex_);
};

}  // namespace rigcal::pipeline
