// SPDX-License-Identifier: Apache-2.0
#include "no_sets_reason.h"

#include <sstream>

namespace rigcal::cli {
namespace {

std::string CameraList(const std::vector<std::string>& names) {
  std::string text;
  for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
  return text;
}

// Image replay: the cameras that got frames and gave no pose.
std::string VoNeverInitialised(const std::vector<std::string>& names,
                               const pipeline::CalibNodeSummary& summary) {
  std::ostringstream text;
  for (size_t i = 0; i < summary.cameras.size() && i < names.size(); ++i) {
    const pipeline::CameraInputStats& c = summary.cameras[i];
    if (c.images > 0 && c.received == 0) {
      text << (text.tellp() > 0 ? "; " : "") << "the VO of camera " << names[i]
           << " never initialised over its " << c.images
           << " frames (initialising needs parallax: a rig that stands still, or a view "
              "without texture, never gives it)";
    }
  }
  return text.str();
}

// Why the sync buffer made no set of the poses it was given, empty when it was given none.
std::string SyncReason(const SyncStats& sync) {
  const SyncCameraStats& t = sync.total;
  std::ostringstream text;
  if (t.pushed == 0) return "";
  if (t.consumed > 0 && t.consumed + t.invalid >= t.pushed) {
    text << "every pose (" << t.consumed
         << ") is older than what the resumed state has already consumed: the log was "
            "calibrated before (start without --resume, or with another --state)";
  } else if (t.never_matched > 0 && t.used == 0) {
    text << "the cameras' stamps never coincide within the tolerance (" << t.never_matched
         << " poses unmatched): cameras that run free need `estimator.time_offset: auto` in "
            "the config (solve: --time-offset auto), or a wider sync.tolerance_ms";
  } else if (t.late + t.out_of_order + t.duplicate + t.clock_glitch > 0) {
    text << "the sync buffer refused the poses: " << t.late << " late, " << t.out_of_order
         << " out of order, " << t.duplicate << " duplicate, " << t.clock_glitch
         << " clock glitches";
  }
  return text.str();
}

}  // namespace

std::string NoSetsReason(const std::string& log_path, const std::vector<std::string>& names,
                         const pipeline::CalibNodeSummary& summary) {
  std::ostringstream text;
  text << "no synchronised pose set reached the estimator: ";
  const std::string vo = summary.image_replay ? VoNeverInitialised(names, summary) : "";
  const std::string sync = SyncReason(summary.sync);
  if (log_path.empty() && summary.sync.total.pushed == 0) {
    text << "no RIGCAL_POSE_<camera> messages of the config's cameras were received";
  } else if (!log_path.empty() && summary.log_events == 0) {
    text << log_path << " holds no events";
  } else if (!vo.empty()) {
    text << vo;
  } else if (!sync.empty()) {
    text << sync;
  } else {
    text << (log_path.empty() ? std::string("the bus") : log_path) << " holds no usable "
         << (summary.image_replay ? "RIGCAL_IMAGE_<camera>" : "RIGCAL_POSE_<camera>")
         << " messages of the config's cameras";
  }
  text << " (cameras: " << CameraList(names) << ")";
  if (!summary.skipped_channels.empty()) {
    text << "; channels in the log not replayed:";
    for (const auto& [channel, count] : summary.skipped_channels) {
      text << " " << channel << " (" << count << ")";
    }
  }
  if (summary.unknown_channel > 0) {
    text << "; " << summary.unknown_channel << " pose messages of cameras not in the config";
  }
  return text.str();
}

}  // namespace rigcal::cli
