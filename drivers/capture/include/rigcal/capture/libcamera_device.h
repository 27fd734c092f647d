// SPDX-License-Identifier: Apache-2.0
#pragma once
// LibcameraDevice: a CameraDevice reading one camera through libcamera (the `libcamera` source of
// a rig config). Built only when libcamera-dev was found at configure time; otherwise Open says
// so (LibcameraBuiltIn() is false).
//
// Open takes the process's shared CameraManager (libcamera allows one at a time; it is released
// with the last device), picks the camera by id (`cam --list`) or by model ("Sensor B"),
// acquires it, generates a configuration for the stream role, sets the size and the first
// preferred pixel format the camera offers, validates it (an adjusted configuration is
// reported by validation(); a size the camera will not deliver is an error naming both sizes),
// allocates the buffers (FrameBufferAllocator), maps them and queues one request per buffer.
// Grab waits for a completed request, converts its buffer to grey (pixel_format.h), takes
// SensorTimestamp (CLOCK_MONOTONIC ns, start of exposure) from the request metadata, else the
// buffer's timestamp, and the buffer's sensor sequence, then recycles the request
// (Request::reuse(ReuseBuffers)). Sequence gaps count as drops. Camera removal
// (CameraManager::cameraRemoved) is a device loss: the device releases the camera and, when
// `reconnect`, acquires it again with backoff once the camera manager lists it again.
//
// Threads: one capture thread calls Grab; libcamera's thread completes requests (under
// mutex_); Interrupt and stats any thread.

#include <memory>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/capture/capture_device.h"
#include "rigcal/capture/pixel_format.h"

namespace rigcal::capture {

struct LibcameraOptions {
  std::string camera;  // camera id or model; empty: the first camera
  int width = 0;       // > 0: the camera model's size
  int height = 0;
  std::string role = "video";  // video (VideoRecording), viewfinder, still (StillCapture), raw
  // Preferred formats, first offered wins; empty: GREY (R8), YUYV, NV12, BGR24 (libcamera
  // RGB888), RGB24 (BGR888), MJPEG.
  std::vector<PixelFormat> formats;
  int buffers = 4;  // requested; the pipeline may adjust it, [1, 32]
  bool reconnect = true;
  double reconnect_max_backoff_s = 2.0;
  Status Check() const;
};

struct LibcameraStats {
  int64_t frames = 0;
  int64_t sequence_drops = 0;
  int64_t failed_requests = 0;  // completed with an error or a failed buffer
  int64_t removals = 0;         // the camera disappeared
  int64_t reconnections = 0;
  bool connected = false;
  bool sensor_timestamps = false;  // SensorTimestamp was in the metadata
};

// Whether this build has the libcamera source.
bool LibcameraBuiltIn();
// Ids and models of the cameras libcamera sees ("<id> (<model>)"), or an error.
Expected<std::vector<std::string>> ListLibcameraCameras();

class LibcameraDevice final : public CameraDevice {
 public:
  static Expected<std::unique_ptr<LibcameraDevice>> Open(std::string name, int camera_index,
                                                         LibcameraOptions options);
  ~LibcameraDevice() override;

  const std::string& name() const override;
  double frame_rate_hz() const override;
  Expected<std::optional<Frame>> Grab() override;
  void Interrupt() override;

  // "valid" or "adjusted: <what the camera changed>", and the configuration in use
  // ("640x480-BGR888 stride 1920, 4 buffers").
  std::string validation() const;
  std::string configuration() const;
  std::string camera_id() const;
  LibcameraStats stats() const;

  struct Impl;

 private:
  explicit LibcameraDevice(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace rigcal::capture
