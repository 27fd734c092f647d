// SPDX-License-Identifier: Apache-2.0
// Recognising the state's own data after a resume (resume_check.h).
#include "online/resume_check.h"

namespace rigcal::internal {
namespace {

bool Same(const PoseFingerprint& f, const CameraPose& p) {
  return f.t_ns == p.t_ns && f.q.coeffs() == p.pose.q.coeffs() && f.C == p.pose.C;
}

}  // namespace

void ResumeCheck::Start(const std::vector<std::string>& names,
                        const std::vector<PoseFingerprint>& first,
                        const std::vector<PoseFingerprint>& last) {
  MutexLock lock(mutex_);
  started_ = true;
  cameras_.assign(names.size(), Camera{});
  for (size_t c = 0; c < names.size(); ++c) {
    cameras_[c].name = names[c];
    if (c < first.size()) cameras_[c].first = first[c];
    if (c < last.size()) cameras_[c].last = last[c];
  }
}

void ResumeCheck::Skipped(const CameraPose& pose) {
  MutexLock lock(mutex_);
  if (!started_ || pose.camera < 0 || pose.camera >= static_cast<int>(cameras_.size())) return;
  Camera& c = cameras_[static_cast<size_t>(pose.camera)];
  ++c.skipped;
  for (const PoseFingerprint* f : {&c.first, &c.last}) {
    if (f->t_ns < 0 || f->t_ns != pose.t_ns) continue;
    if (Same(*f, pose)) {
      ++c.confirmed;
    } else {
      ++c.differing;
    }
  }
}

std::optional<std::string> ResumeCheck::Verdict(int camera) const {
  MutexLock lock(mutex_);
  if (!started_ || camera < 0 || camera >= static_cast<int>(cameras_.size())) return std::nullopt;
  const Camera& c = cameras_[static_cast<size_t>(camera)];
  const std::string count = std::to_string(c.skipped) + " pose" + (c.skipped == 1 ? "" : "s");
  if (c.differing > 0) {
    return "after the resume, '" + c.name + "' has another pose than the state took at the same " +
           "stamp: another drive on a restarted clock; its " + count +
           " at or before the state's stamps were skipped, the estimate is the state's, not " +
           "this drive's (run without --resume to calibrate it)";
  }
  if (c.skipped > 0 && c.confirmed == 0) {
    return "after the resume, " + count + " of '" + c.name +
           "' are stamped at or before what the state consumed and none is a pose the state " +
           "took (a restarted clock, another drive): skipped, the estimate is the state's, not " +
           "confirmed by this input (run without --resume to calibrate a new drive)";
  }
  return std::nullopt;
}

}  // namespace rigcal::internal
