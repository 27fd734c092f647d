// SPDX-License-Identifier: Apache-2.0
#pragma once
// Gathers the data of `rigcal report` from its inputs.
//
// Inputs:
//  - an LCM log (recognised by LCM's event sync word): the RIGCAL_EXTRINSICS messages are the
//    estimate's history (time = their capture time t_ns) and the last one the final table; the
//    RIGCAL_STATUS messages the cameras' health (time = their utime); RIGCAL_POSE_<camera>
//    events in it are the poses of the per-motion analysis;
//  - or a result file (result YAML or --json output, ReadResultFile): the final table only.
// Per-motion residua and measured scales are in no message: they are computed from the poses
// (in the log, or `poses_log`, an LCM pose log such as `rigcal synth-log` writes): the poses
// matched by time across cameras, the motions of PairOptions' walk pairs (as `rigcal solve
// --pairs walk`), and for each motion ResidualOf (error_model.h) against the final estimate.
// The truth (io/truth_files.h): a rig YAML or a rig config whose cameras carry `truth`, or the
// directory of `rigcal run --truth-out` (truth.yaml and a TUM trajectory per camera); compared
// by the one comparison io::CompareWithTruth: with a directory and the poses, the master unit per
// master segment (the estimate's segment) and every slave's true scale from its segment's unit,
// as `run --eval` and `solve --truth DIR`; else the unit fitted from the mountings.
// The config (optional): the intrinsics table, and C in metres when its master is metric.

#include <string>

#include "rigcal/base/status.h"
#include "rigcal/report/report_data.h"

namespace rigcal::report {

struct ReportOptions {
  std::string input;      // LCM log or result file
  std::string poses_log;  // optional LCM log with RIGCAL_POSE_<camera> events
  std::string truth;      // optional rig YAML, rig config with cameras[].truth, or truth directory
  std::string config;     // optional rig config: intrinsics, metric master
};

// The report's data. Errors (bad input) name the file and what is wrong: unreadable, neither an
// LCM log nor a result file, a log without RIGCAL_EXTRINSICS, a truth without the slaves.
// A damaged log tail is not an error: the events before it are used and a note gives the byte
// offset; rejected messages are counted in a note.
Expected<ReportData> LoadReport(const ReportOptions& options);

}  // namespace rigcal::report
