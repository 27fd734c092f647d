// SPDX-License-Identifier: Apache-2.0
#pragma once
// After a resume (OnlineCalibrator::RestoreState): is the new input the data the state already
// holds, or another drive? Poses stamped at or before what the state consumed are skipped
// (SyncBuffer::SkipConsumed). They are the same data again when a pose at the stamp of the
// first or the newest pose the state took (PoseFingerprint) is that pose; a different pose
// there, or skipped poses none of which is one of them, are another drive whose clock
// restarted: nothing of it reaches the estimator, so the estimate is the state's, not this
// drive's, and it must not be published as usable.
//
// Thread-safe (producers call Skipped, any thread Verdict).

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/base/thread_annotations.h"
#include "rigcal/base/types.h"
#include "rigcal/calib/estimator_state.h"

namespace rigcal::internal {

class ResumeCheck {
 public:
  // Starts checking against a restored state's fingerprints (one per camera; empty: a state
  // before version 6, nothing to compare with, every skipped pose unconfirmed).
  void Start(const std::vector<std::string>& names, const std::vector<PoseFingerprint>& first,
             const std::vector<PoseFingerprint>& last) RIGCAL_EXCLUDES(mutex_);
  // A pose skipped as consumed.
  void Skipped(const CameraPose& pose) RIGCAL_EXCLUDES(mutex_);
  // Why the input of camera `camera` is not the state's data, nullopt when it is (or nothing
  // was skipped).
  std::optional<std::string> Verdict(int camera) const RIGCAL_EXCLUDES(mutex_);

 private:
  struct Camera {
    std::string name;
    PoseFingerprint first, last;
    int skipped = 0;
    int confirmed = 0;  // skipped poses equal to a fingerprint
    int differing = 0;  // skipped poses at a fingerprint's stamp that differ from it
  };
  mutable Mutex mutex_;
  bool started_ RIGCAL_GUARDED_BY(mutex_) = false;
  std::vector<Camera> cameras_ RIGCAL_GUARDED_BY(mutex_);
};

}  // namespace rigcal::internal
