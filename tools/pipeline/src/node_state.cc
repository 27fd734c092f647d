// SPDX-License-Identifier: Apache-2.0
// CalibNode's estimator state (calib_node.h): atomic saves on the schedule and at the end, and
// --resume, which sets a state it cannot use aside and never overwrites it.
#include <filesystem>
#include <string>

#include "calib_node_impl.h"
#include "rigcal/io/atomic_file.h"
#include "rigcal/io/estimator_state_file.h"
#include "rigcal/io/text_file.h"

namespace rigcal::pipeline {

bool CalibNode::Impl::CalibratedNothing() {
  return !summary.resumed && calibrator->sync_stats().sets_emitted == 0;
}

void CalibNode::Impl::SaveState() {
  if (state_path.empty()) return;
  // An empty state never replaces the one a previous run saved.
  if (CalibratedNothing() && std::filesystem::exists(state_path)) return;
  if (const Status status = io::WriteFileAtomically(
          state_path, io::FormatEstimatorState(calibrator->SaveState()), state_new_file_mode);
      !status.ok()) {
    // Reported once (a full disk fails every save alike; one error per save grew without
    // bound), counted, retried at the next save interval only.
    summary.state_last_save_failed = true;
    if (summary.state_save_failures++ == 0) {
      AddError("state not saved: " + status.message() +
               " (retried at every save interval, reported once; a state saved before is kept)");
    }
    return;
  }
  if (summary.state_last_save_failed) {
    log->info("state saved to {} again after {} failed saves", state_path,
              summary.state_save_failures);
  }
  summary.state_last_save_failed = false;
  ++summary.state_saves;
}

void CalibNode::Impl::ReportStateSaves() {
  if (summary.state_save_failures == 0) return;
  const std::string counts = std::to_string(summary.state_save_failures) + " of " +
                             std::to_string(summary.state_save_failures + summary.state_saves) +
                             " saves of " + state_path + " failed";
  if (summary.state_last_save_failed) {
    AddError("state: " + counts + ", the last one too: this run's final state is not saved (" +
             (summary.state_saves > 0 ? "the state saved last in this run is kept"
                                      : "the state file, if any, is as it was before the run") +
             ")");
  } else {
    log->warn("state: {} (the final save succeeded)", counts);
  }
}

Status CalibNode::Impl::CheckStatePath() const {
  if (state_path.empty()) return Status::Ok();
  if (const Status replaceable = io::CheckReplaceable(state_path); !replaceable.ok()) {
    return Error{(options.resume ? "--resume: " : "state: ") + replaceable.message()};
  }
  return Status::Ok();
}

void CalibNode::Impl::RestoreState() {
  if (state_path.empty()) {
    log->warn("--resume: no state file configured (state.path or --state); starting afresh");
    return;
  }
  if (!std::filesystem::exists(std::filesystem::symlink_status(state_path))) {
    log->warn("--resume: no state file '{}' yet; starting afresh", state_path);
    return;
  }
  auto text = io::ReadWholeFile(state_path);
  const Expected<RigEstimatorState> state =
      text ? io::ParseEstimatorState(*text) : Expected<RigEstimatorState>(text.status());
  const Status restored = state ? calibrator->RestoreState(*state) : state.status();
  if (restored.ok()) {
    summary.resumed = true;
    if (pipeline) SetSegmentOffsets(*state);  // our own VO restarted with the process
    std::string consumed;
    for (size_t i = 0; i < state->consumed_t_ns.size() && i < names.size(); ++i) {
      if (state->consumed_t_ns[i] >= 0) {
        consumed += (consumed.empty() ? "" : ", ") + names[i] + " " +
                    std::to_string(state->consumed_t_ns[i]) + " ns";
      }
    }
    log->info("resumed from {}{}", state_path,
              consumed.empty() ? std::string()
                               : "; poses up to the stamps consumed there are skipped (" +
                                     consumed + ", counted consumed)");
    return;
  }
  // A rejected state (corrupt, newer version, other rig) is kept for a look, never overwritten.
  const Expected<io::KeptAside> aside = io::KeepAside(state_path, "rejected");
  if (!aside) {
    AddError("--resume: " + state_path + ": " + restored.message() + "; " + aside.error() +
             "; the state is not saved in this run");
    state_path.clear();
    return;
  }
  summary.rejected_state = aside->path;
  state_new_file_mode = aside->mode;  // the new state is as private as the rejected one
  log->warn("--resume: {}: {}; kept as {}, starting afresh", state_path, restored.message(),
            aside->path);
}

void CalibNode::Impl::SetSegmentOffsets(const RigEstimatorState& state) {
  segment_offset.assign(names.size(), 0);
  if (state.have_master_segment) segment_offset[0] = state.master_segment + 1;
  for (size_t i = 0; i < state.slaves.size() && i + 1 < names.size(); ++i) {
    segment_offset[i + 1] = state.slaves[i].segment + 1;
  }
  log->info(
      "resumed with a restarted VO: its scale segments continue after the saved ones "
      "(master from segment {})",
      segment_offset[0]);
}

}  // namespace rigcal::pipeline
