// SPDX-License-Identifier: Apache-2.0
#pragma once
// V4l2Device: a CameraDevice reading a Video4Linux2 capture node by mmap streaming.
//
// Open resolves the device (path, by-id link, bus info or card name), negotiates the format
// (the first of the preferred pixel formats the driver lists, at the camera's size; an error
// when the driver changes the size), the frame interval and the controls, maps the buffers and
// starts streaming. Grab polls with a short timeout (so Interrupt is prompt), dequeues a buffer,
// converts it to grey (pixel_format.h), stamps it (v4l2_timestamp.h) and requeues it. Sequence
// gaps are counted as drops; buffers flagged V4L2_BUF_FLAG_ERROR are dropped and counted.
//
// Device loss (ENODEV, EIO, POLLERR, the node vanishing, or no frame within frame_timeout_s):
// the device logs it, counts it, closes and - when options.reconnect - reopens with backoff
// inside Grab until the device is back or Interrupt is called; frame sequence numbers keep
// increasing across reconnections. Without reconnect Grab returns the error (the pipeline marks
// the camera dead and keeps calibrating the others).
//
// Threads: one capture thread calls Grab; Interrupt and stats() any thread.

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

#include "rigcal/base/status.h"
#include "rigcal/base/thread_annotations.h"
#include "rigcal/capture/capture_device.h"
#include "rigcal/capture/v4l2_options.h"

namespace rigcal::capture {

struct V4l2Stats {
  int64_t frames = 0;          // frames delivered by Grab
  int64_t sequence_drops = 0;  // frames missing in the driver's sequence numbers
  int64_t error_buffers = 0;   // buffers the driver flagged as erroneous
  int64_t device_losses = 0;   // times the device was lost
  int64_t reconnections = 0;   // times it was reopened after a loss
  bool connected = false;      // streaming now
  std::string last_loss;       // why the device was last lost ("" if never)
};

// What Open negotiated.
struct V4l2Negotiated {
  std::string node;      // /dev/videoN opened
  std::string card;      // VIDIOC_QUERYCAP card
  std::string bus_info;  // VIDIOC_QUERYCAP bus_info
  std::string driver;
  ImageLayout layout;
  uint32_t fourcc = 0;
  double frame_rate_hz = 0.0;  // from VIDIOC_G_PARM, 0 when the driver does not say
  int buffers = 0;
};

class V4l2Device final : public CameraDevice {
 public:
  // `name`: the camera name; `camera_index`: written into every Frame. Errors name the camera,
  // the device and what failed (no such device, not a capture device, no supported format,
  // size refused, a control the driver lacks, ...).
  static Expected<std::unique_ptr<V4l2Device>> Open(std::string name, int camera_index,
                                                    V4l2Options options);
  ~V4l2Device() override;

  const std::string& name() const override { return name_; }
  double frame_rate_hz() const override;
  Expected<std::optional<Frame>> Grab() override;
  void Interrupt() override;

  const V4l2Negotiated& negotiated() const { return negotiated_; }  // the capture thread's
  V4l2Stats stats() const RIGCAL_EXCLUDES(mutex_);

 private:
  struct Stream;
  V4l2Device() = default;
  // Opens, configures and starts streaming; fills negotiated_.
  Status Connect();
  void Disconnect();
  // Records a loss; Error when reconnecting is off.
  Status Lost(const std::string& why);
  // Waits with backoff until Connect succeeds (true) or Interrupt (false).
  bool Reconnect();
  // Sleeps up to `ns` unless interrupted; false when interrupted.
  bool Sleep(int64_t ns);

  std::string name_;
  int camera_index_ = 0;
  V4l2Options options_;
  V4l2Negotiated negotiated_;
  std::unique_ptr<Stream> stream_;  // capture thread's; null while disconnected
  int wake_fd_ = -1;                // eventfd written by Interrupt
  std::atomic<bool> interrupted_{false};
  int64_t last_sequence_ = -1;  // driver sequence of the last buffer of this connection
  int64_t seq_base_ = 0;        // added to driver sequences (grows on reconnection)
  int64_t last_seq_out_ = -1;   // Frame.seq last returned
  int64_t exposure_ns_ = 0;
  int64_t last_frame_ns_ = 0;  // monotonic time of the last frame (or of connecting)
  bool warned_clock_ = false;
  mutable Mutex mutex_;
  V4l2Stats stats_ RIGCAL_GUARDED_BY(mutex_);
};

}  // namespace rigcal::capture
