// SPDX-License-Identifier: Apache-2.0
#pragma once
// CameraDevice: the interface every capture source implements (V4L2, libcamera, image folders,
// the simulated rig of rigcal_sim, the pipeline's LCM log replay). The pipeline runs one capture
// thread per device that calls Grab() in a loop and pushes the frames into that camera's bounded
// queue.

#include <optional>
#include <string>

#include "rigcal/base/status.h"
#include "rigcal/capture/frame.h"

namespace rigcal::capture {

class CameraDevice {
 public:
  virtual ~CameraDevice() = default;
  CameraDevice() = default;
  CameraDevice(const CameraDevice&) = delete;
  CameraDevice& operator=(const CameraDevice&) = delete;

  // Camera name as in the rig config (`cameras[].name`). Constant; any thread.
  virtual const std::string& name() const = 0;

  // Nominal frame rate, frames per second (> 0). Constant; any thread.
  virtual double frame_rate_hz() const = 0;

  // The next frame, blocking until it is available (a device paced in real time waits for the
  // frame's capture time; a device that is not paced returns at once).
  //  - a Frame: `camera` is the device's index in the rig, `t_ns` its capture time
  //    (CLOCK_MONOTONIC nanoseconds for a live device), `seq` the frame/trigger number
  //    (increasing; gaps mean dropped frames), `image` a CV_8UC1 image the caller owns.
  //  - nullopt: end of stream (a finite recording or simulation has ended, or Interrupt() was
  //    called). Later calls return nullopt too.
  //  - Error: the device failed; the message says which camera and why. Later calls keep
  //    failing.
  // Thread: called from one capture thread per device (not concurrently on one device);
  // different devices may be grabbed concurrently.
  virtual Expected<std::optional<Frame>> Grab() = 0;

  // Makes a Grab that is blocked, or the next Grab, return nullopt promptly (clean shutdown).
  // Thread-safe: any thread, any time; idempotent.
  virtual void Interrupt() = 0;
};

}  // namespace rigcal::capture
