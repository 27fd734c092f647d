// SPDX-License-Identifier: Apache-2.0
#pragma once
// ImageFolderDevice: a CameraDevice that replays one camera's folder of images, in one of two
// layouts:
//  - ASL (EuRoC) camera folder: <folder>/data.csv with lines "timestamp_ns,filename" ("#"
//    lines are comments) and the images in <folder>/data/<filename>;
//  - plain folder (no data.csv): every image file of <folder> (png, jpg, jpeg, pgm, ppm, pnm,
//    bmp, tif, tiff) in natural name order (img2 before img10), stamped at a rate (frame i at
//    i / rate_hz seconds) or by a timestamps file (ImageFolderOptions).
// Images may be 8- or 16-bit, grey or colour; they are delivered as CV_8UC1. A 16-bit folder is
// scaled by the bit depth its first image uses (a 12-bit sensor's values in 16-bit words fill
// the 8 bits as a 16-bit one's do), the same scale for every frame. It is not paced: Grab
// returns the next frame at once.
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
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/thread_annotations.h"
#include "rigcal/capture/capture_device.h"

namespace rigcal::capture {

struct ImageFolderOptions {
  // Plain folder: frame i is stamped i / rate_hz seconds (from 0). ASL folder: the rate that
  // frame_rate_hz() reports. <= 0: a plain folder needs `timestamps_file`; the reported rate is
  // the inverse of the median stamp interval (20 Hz when there is a single image).
  double rate_hz = 0.0;
  // Plain folder: one stamp per image in name order, one per line: integer nanoseconds, or
  // seconds with a decimal point ("1403636579.763555584"); a second field on the line (after a
  // blank or a comma), when present, must be that image's file name (TUM's rgb.txt fits).
  // Overrides rate_hz for the stamps. Empty: none. Ignored for an ASL folder.
  std::string timestamps_file;
};

class ImageFolderDevice final : public CameraDevice {
 public:
  // Opens `folder` (an ASL camera folder, e.g. .../mav0/cam0, or a plain folder of images).
  // `name` is the camera name, `camera_index` the index written into every Frame.
  // Errors: an ASL data.csv that cannot be read or has no valid entry; a plain folder without
  // images, without a rate or timestamps file, or whose timestamps file does not fit it.
  static Expected<std::unique_ptr<ImageFolderDevice>> Open(const std::string& folder,
                                                           std::string name, int camera_index,
                                                           const ImageFolderOptions& options);
  // The same with options.rate_hz = frame_rate_hz.
  static Expected<std::unique_ptr<ImageFolderDevice>> Open(const std::string& folder,
                                                           std::string name, int camera_index,
                                                           double frame_rate_hz = 0.0);

  const std::string& name() const override { return name_; }
  double frame_rate_hz() const override { return frame_rate_hz_; }
  // The next readable image, nullopt at the end of the list or after Interrupt(). Never an
  // error: a bad image is skipped (see above). One capture thread.
  Expected<std::optional<Frame>> Grab() override;
  void Interrupt() override { interrupted_ = true; }

  // Number of frames listed (valid CSV entries or images of a plain folder; readable or not).
  size_t size() const { return entries_.size(); }
  // How the folder was read: "ASL data.csv", "plain folder stamped at 30 Hz", ...
  const std::string& layout() const { return layout_; }
  // Image paths listed in data.csv that are missing or could not be read as images, in CSV
  // order of discovery (missing ones at Open, unreadable ones when Grab reaches them).
  // Any thread.
  std::vector<std::string> skipped_files() const RIGCAL_EXCLUDES(mutex_);
  size_t skipped_count() const RIGCAL_EXCLUDES(mutex_);
  // "file:line: reason" for every CSV line that was skipped (ASL layout).
  const std::vector<std::string>& csv_problems() const { return csv_problems_; }

 private:
  struct Entry {
    int64_t t_ns = 0;
    std::string path;
    bool exists = true;
  };
  ImageFolderDevice() = default;
  // `image` (any depth and channels) as CV_8UC1; empty when it cannot be converted.
  cv::Mat ToGrey8(cv::Mat image);

  std::string name_;
  int camera_index_ = 0;
  double frame_rate_hz_ = 20.0;
  std::vector<Entry> entries_;
  std::vector<std::string> csv_problems_;
  std::string layout_;
  size_t next_ = 0;                 // the capture thread's
  double sixteen_bit_scale_ = 0.0;  // the capture thread's: fixed by the first 16-bit image
  std::atomic<bool> interrupted_{false};
  mutable Mutex mutex_;
  std::vector<std::string> skipped_ RIGCAL_GUARDED_BY(mutex_);
};

}  // namespace rigcal::capture
