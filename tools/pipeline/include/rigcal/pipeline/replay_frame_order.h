// SPDX-License-Identifier: Apache-2.0
#pragma once
// ReplayFrameOrder: puts the frames of an image log into stamp order across cameras before a
// lossless replay feeds them to the pipeline. A log holds each camera's frames in capture order,
// but one camera's frames may be written well ahead of another's (a recording made faster than
// real time), and a camera may stop delivering while the others go on. The pipeline's merge of
// the cameras' poses waits for the camera that lags; fed in file order, such a log filled the
// leading camera's queues and stopped the reader while the lagging camera waited for frames
// behind it: a deadlock.
//
// A frame is released once no camera can still deliver an earlier one:
//  - every camera holds a frame: the earliest is released (each camera's frames come in order);
//  - otherwise once the frames held exceed `max_bytes` (a camera that stopped, or one more than
//    that far behind in the file): every camera holding nothing then gets a progress mark at
//    the released frame's stamp (capture::Frame::progress_mark), so that the merge goes on
//    without it.
// A frame read after its camera was marked at or past its stamp is dropped and counted
// (late_frames). Memory: at most `max_bytes` of image data held.
//
// Threads: one thread (the log reader) uses it.

#include <cstdint>
#include <deque>
#include <vector>

#include "rigcal/capture/frame.h"

namespace rigcal::pipeline {

class ReplayFrameOrder {
 public:
  ReplayFrameOrder(int num_cameras, int64_t max_bytes);

  // A frame of camera `frame.camera` read from the log; false when it came too late (dropped).
  bool Add(capture::Frame frame);
  // Appends the frames and progress marks that are safe to feed now, in stamp order.
  void TakeReady(std::vector<capture::Frame>* out);
  // End of the log: appends every held frame, in stamp order.
  void TakeAll(std::vector<capture::Frame>* out);

  int64_t late_frames() const { return late_frames_; }
  int64_t held_bytes() const { return held_bytes_; }

 private:
  // The camera holding the earliest frame (ties: the lower index), -1 when none holds one.
  int Earliest() const;
  bool EveryCameraHolds() const;
  void Release(int camera, std::vector<capture::Frame>* out);
  void MarkIdleCameras(int64_t t_ns, std::vector<capture::Frame>* out);

  std::vector<std::deque<capture::Frame>> held_;
  std::vector<int64_t> released_ns_;  // per camera: stamp of its last frame or mark fed
  std::vector<bool> marked_;          // per camera: that was a mark
  const int64_t max_bytes_;
  int64_t held_bytes_ = 0;
  int64_t late_frames_ = 0;
};

}  // namespace rigcal::pipeline
