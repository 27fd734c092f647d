// SPDX-License-Identifier: Apache-2.0
#pragma once
// LogRecorder: records a rig's camera frames (RIGCAL_IMAGE_<camera>, image_t) and any other
// rigcal message (poses, extrinsics) into an LCM log (LogWriter: lcm-logger's format, split by
// size, readable up to the last complete event after a power loss). The engine of
// `rigcal record`.
//
//   capture thread per device --Tap: encode on the capture thread--> bounded event queue
//   other threads --Record(channel, bytes)-------------------------->      |
//                                                        writer thread: LogWriter
//
// The queue holds RecorderOptions::queue_events events. A live source never waits for the disk:
// when the queue is full the oldest event is dropped and counted (dropped_disk). A lossless
// recorder (sources not paced in real time) makes the capture wait instead.
//
// Event timestamps are capture times: t_ns / 1000 for frames, the message's utime for the rest,
// never decreasing in the file (an event queued after a later one gets that one's timestamp), so
// players pace by capture time.
//
// Threads: Open, Stop and the destructor from the owner's thread; Tap'ed devices from their
// capture threads (one per device, as CameraDevice requires); Record and Stats from any thread.
// The writer thread is owned and joined by the recorder.

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "rigcal/base/bounded_queue.h"
#include "rigcal/base/status.h"
#include "rigcal/base/thread_annotations.h"
#include "rigcal/capture/capture_device.h"
#include "rigcal/lcm/log_writer.h"
#include "rigcal/pipeline/image_codec.h"

namespace rigcal::pipeline {

struct RecorderOptions {
  ImageEncodeOptions image;  // how frames are stored
  lcm::LogWriterOptions log;      // splitting, sync interval, overwrite
  int queue_events = 64;     // >= 1: events waiting for the disk (64 raw 752x480 frames: 23 MB)
  bool lossless = false;     // capture waits for the disk instead of dropping
  // Success, or "<field>: <constraint>".
  Status Check() const;
};

struct RecorderStats {
  int64_t bytes = 0;                     // written to the log files
  int64_t events = 0;                    // written
  std::vector<int64_t> frames;           // per camera: frames written
  std::vector<int64_t> dropped_capture;  // per camera: frames the device lost (gaps in seq)
  int64_t dropped_disk = 0;              // events dropped because the disk fell behind
  int64_t other_events = 0;              // written events that are not frames (poses, ...)
  std::vector<std::string> files;        // log files started
  std::string error;                     // first encode or write error; empty when none
  int64_t FramesTotal() const;
  int64_t DroppedTotal() const;  // dropped_disk + every camera's dropped_capture
};

class LogRecorder {
 public:
  // Opens the log `path` for a rig with cameras `names` (index = camera index) and starts the
  // writer thread. Errors: invalid options, the log cannot be created.
  static Expected<std::unique_ptr<LogRecorder>> Open(const std::string& path,
                                                     std::vector<std::string> names,
                                                     const RecorderOptions& options);
  ~LogRecorder();  // Stop()
  LogRecorder(const LogRecorder&) = delete;
  LogRecorder& operator=(const LogRecorder&) = delete;

  // `device` (camera index `camera`) wrapped so that every frame its Grab returns is also
  // encoded (on the grabbing thread) and queued on RIGCAL_IMAGE_<name>. The frames are returned
  // unchanged. The recorder must outlive the returned device's Grab calls.
  std::unique_ptr<capture::CameraDevice> Tap(std::unique_ptr<capture::CameraDevice> device,
                                             int camera);

  // Queues an encoded message on `channel` at `utime` (µs). Any thread. Ignored after Stop.
  void Record(std::string channel, int64_t utime, std::vector<uint8_t> data);

  // Writes what is queued, closes the log and joins the writer. Returns the first error (also
  // in Stats().error). Idempotent; call after the capture threads have ended for a complete log.
  [[nodiscard]] Status Stop() RIGCAL_EXCLUDES(mutex_);

  RecorderStats Stats() const RIGCAL_EXCLUDES(mutex_);
  const std::vector<std::string>& names() const { return names_; }

  // Called by Tap'ed devices: encodes and queues one frame of camera `camera`.
  void RecordFrame(int camera, const capture::Frame& frame) RIGCAL_EXCLUDES(mutex_);

 private:
  struct Event {
    int camera = -1;  // the camera of a frame, -1 for other messages
    std::string channel;
    int64_t utime = 0;
    std::vector<uint8_t> data;
  };
  LogRecorder(std::vector<std::string> names, const RecorderOptions& options,
              std::unique_ptr<lcm::LogWriter> writer);
  void Enqueue(Event event) RIGCAL_EXCLUDES(mutex_);
  void WriterLoop();
  void Fail(const std::string& error) RIGCAL_EXCLUDES(mutex_);

  const std::vector<std::string> names_;
  const RecorderOptions options_;
  std::unique_ptr<lcm::LogWriter> writer_;  // the writer thread's until it is joined
  BoundedQueue<Event> queue_;
  std::thread writer_thread_;
  std::atomic<bool> stopped_{false};
  mutable Mutex mutex_;
  RecorderStats stats_ RIGCAL_GUARDED_BY(mutex_);
  std::vector<int64_t> last_seq_ RIGCAL_GUARDED_BY(mutex_);  // per camera, -1 before a frame
};

}  // namespace rigcal::pipeline
