#pragma once
// ImageFolderDevice: a CameraDevice that replays one camera folder of a EuRoC-format recording
// (ASL layout): <folder>/data.csv with lines "timestamp_ns,filename" ("#" lines are comments)
// and the images in <folder>/data/<filename> (8- or 16-bit grey or colour; delivered as
// CV_8UC1). It is not paced: Grab returns the next frame at once.
//
// Damaged recordings do not stop a replay:
//  - a malformed or out-of-order CSV line is skipped; a warning names it as file:line and it
//    is listed by csv_problems();
//  - an image that is listed but missing (checked when the folder is opened) or unreadable
//    (found by Grab) is skipped, logged, counted and listed by skipped_files(). The frame's
//    `seq` is its line index among the valid CSV entries, so skipped frames leave gaps.
//
// Threads: one capture thread calls Grab; any thread calls Interrupt (an atomic flag) and
// skipped_files/skipped_count (the list is guarded by mutex_). The rest is immutable after Open.

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/thread_annotations.h"
#include "rigcal/capture/capture_device.h"

namespace rigcal::capture {

class ImageFolderDevice final : public CameraDevice {
 public:
  // Opens `folder` (the camera folder, e.g. .../mav0/cam0). `name` is the camera name,
  // `camera_index` the index written into every Frame. `frame_rate_hz` <= 0: the rate is the
  // inverse of the median stamp interval (20 Hz when there is a single entry).
  // Error when data.csv cannot be read or has no valid entry.
  static Expected<std::unique_ptr<ImageFolderDevice>> Open(const std::string& folder,
                                                           std::string name, int camera_index,
                                                           double frame_rate_hz = 0.0);

  const std::string& name() const override { return name_; }
  double frame_rate_hz() const override { return frame_rate_hz_; }
  // The next readable image, nullopt at the end of the list or after Interrupt(). Never an
  // error: a bad image is skipped (see above). One capture thread.
  Expected<std::optional<Frame>> Grab() override;
  void Interrupt() override { interrupted_ = true; }

  // Number of valid CSV entries (readable or not).
  size_t size() const { return entries_.size(); }
  // Image paths listed in data.csv that are missing or could not be read as images, in CSV
  // order of discovery (missing ones at Open, unreadable ones when Grab reaches them).
  // Any thread.
  std::vector<std::string> skipped_files() const RIGCAL_EXCLUDES(mutex_);
  size_t skipped_count() const RIGCAL_EXCLUDES(mutex_);
  // "file:line: reason" for every CSV line that was skipped.
  const std::vector<std::string>& csv_problems() const { return csv_problems_; }

 private:
  struct Entry {
    int64_t t_ns = 0;
    std::string path;
    bool exists = true;
  };
  ImageFolderDevice() = default;

  std::string name_;
  int camera_index_ = 0;
  double frame_rate_hz_ = 20.0;
  std::vector<Entry> entries_;
  std::vector<std::string> csv_problems_;
  size_t next_ = 0;  // the capture thread's
  std::atomic<bool> interrupted_{false};
  mutable Mutex mutex_;
  std::vector<std::string> skipped_ RIGCAL_GUARDED_BY(mutex_);
};

}  // namespace rigcal::capture
