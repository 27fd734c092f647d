// SPDX-License-Identifier: Apache-2.0
#include "rigcal/pipeline/capture_loops.h"

#include <utility>

namespace rigcal::pipeline {

CaptureLoops::CaptureLoops(std::vector<std::unique_ptr<capture::CameraDevice>> devices)
    : devices_(std::move(devices)), running_(static_cast<int>(devices_.size())) {}

CaptureLoops::~CaptureLoops() { Stop(); }

void CaptureLoops::Start() {
  if (!threads_.empty()) return;
  for (size_t i = 0; i < devices_.size(); ++i) threads_.emplace_back([this, i] { Loop(i); });
}

void CaptureLoops::Loop(size_t index) {
  capture::CameraDevice& device = *devices_[index];
  while (true) {
    Expected<std::optional<capture::Frame>> grabbed = device.Grab();
    if (!grabbed) {
      MutexLock lock(mutex_);
      problems_.push_back("camera '" + device.name() + "' died: " + grabbed.error());
      break;
    }
    if (!grabbed->has_value()) break;
  }
  --running_;
}

void CaptureLoops::Stop() {
  for (auto& device : devices_) device->Interrupt();
  for (std::thread& thread : threads_) {
    if (thread.joinable()) thread.join();
  }
}

std::vector<std::string> CaptureLoops::Problems() const {
  MutexLock lock(mutex_);
  return problems_;
}

}  // namespace rigcal::pipeline
