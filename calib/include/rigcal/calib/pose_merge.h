// SPDX-License-Identifier: Apache-2.0
#pragma once
// PoseMerge: the hand-over from the VO threads to the calibrator in a lossless pipeline. It
// forwards every camera's poses in one canonical order, by the stamp of the frame that produced
// them and then by camera index, whatever the thread interleaving, so the SyncBuffer sees the
// same sequence of pushes in every run of the same source: lossless runs are deterministic.
//
// A camera's poses are held until every other camera still streaming has processed a frame at
// least as late (then nothing earlier can come any more); End() removes a camera (end of
// stream, or a dead device). Deliver() also keeps the threads within `lead_ns` of each other in
// stream time (it waits while another streaming camera lags further behind), so what is held
// stays bounded. The camera with the smallest stamp never waits: no deadlock. Live pipelines do
// not use it: a slow camera must never hold the others back there.
//
// Threads: each camera's VO thread calls Deliver and End for its own camera; any thread calls
// Stop. All state is guarded by mutex_. The sink runs with mutex_ held, on whichever thread
// releases the poses: it must not call back into the merge nor wait for a VO thread; it may wait
// for a consumer that does not depend on the merge (a lossless OnlineCalibrator's Push).

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <vector>

#include "rigcal/base/thread_annotations.h"
#include "rigcal/base/types.h"

namespace rigcal {

class PoseMerge {
 public:
  using Sink = std::function<void(const CameraPose&)>;

  PoseMerge(int num_cameras, int64_t lead_ns, Sink sink);

  // Camera `camera` has processed its frame at `frame_t_ns`, giving `poses` (possibly none;
  // stamps may be earlier than the frame, e.g. a segment's first pose). Frame stamps of one
  // camera must increase. Releases what has become safe, then waits while a streaming camera
  // lags more than lead_ns behind frame_t_ns (or until Stop()).
  void Deliver(int camera, int64_t frame_t_ns, std::vector<CameraPose> poses)
      RIGCAL_EXCLUDES(mutex_);
  // Camera `camera` delivers no more frames; releases what no longer waits for it.
  void End(int camera) RIGCAL_EXCLUDES(mutex_);
  // Releases every waiting Deliver. Poses are still forwarded as cameras end.
  void Stop() RIGCAL_EXCLUDES(mutex_);

 private:
  struct Held {
    int64_t frame_t_ns;
    CameraPose pose;
  };
  // Forwards every held pose that no streaming camera can precede any more, in order.
  void ReleaseSafe() RIGCAL_REQUIRES(mutex_);
  // Whether a streaming camera other than `camera` lags more than lead_ns behind t_ns.
  bool Lagging(int camera, int64_t t_ns) const RIGCAL_REQUIRES(mutex_);

  const int64_t lead_ns_;
  const Sink sink_;
  Mutex mutex_;
  std::condition_variable changed_;                          // progress, an end or Stop
  std::vector<int64_t> progress_ RIGCAL_GUARDED_BY(mutex_);  // last frame stamp per camera
  std::vector<bool> ended_ RIGCAL_GUARDED_BY(mutex_);
  std::vector<std::deque<Held>> held_ RIGCAL_GUARDED_BY(mutex_);  // per camera, in frame order
  bool stopped_ RIGCAL_GUARDED_BY(mutex_) = false;
};

}  // namespace rigcal
