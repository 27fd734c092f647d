// SPDX-License-Identifier: Apache-2.0
#pragma once
// Per-motion residua and measured scales (thesis fig. 5.11, 5.12) of the poses of a log, against
// the final estimate of the report.

#include <map>
#include <string>

#include "history_log.h"
#include "rigcal/base/status.h"
#include "rigcal/report/report_data.h"

namespace rigcal::report::internal {

// Matches the poses of data.master and data.slaves by time (nearest stamps within half the
// master's median step), forms the motions of the walk pairs and evaluates ResidualOf against
// data.final_result's estimate of each slave (the scale of the motion's segment when the result
// has it). Times relative to data.t0_ns. Errors: a camera without poses, no time overlap, too
// few matched poses.
Expected<MotionAnalysis> AnalyseMotions(const std::map<std::string, CameraPoses>& poses,
                                        const ReportData& data, const std::string& source);

}  // namespace rigcal::report::internal
