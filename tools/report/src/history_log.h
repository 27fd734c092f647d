// SPDX-License-Identifier: Apache-2.0
#pragma once
// Reading an LCM log for the report: the RIGCAL_EXTRINSICS and RIGCAL_STATUS history and the
// RIGCAL_POSE_<camera> poses, every message validated (rejected ones counted).

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/rig_extrinsics_t.hpp"
#include "rigcal/rig_status_t.hpp"

namespace rigcal::report::internal {

// The poses of one camera as they arrived (time order of the log).
struct CameraPoses {
  std::vector<int64_t> t_ns;
  std::vector<Pose> poses;
  std::vector<int> segment;
};

struct LogContents {
  std::vector<rig_extrinsics_t> extrinsics;
  std::vector<rig_status_t> status;
  std::map<std::string, CameraPoses> poses;  // by camera name
  int64_t events = 0;
  int64_t rejected = 0;         // messages that failed validation
  std::string first_rejection;  // the first one's message
  std::string damage;           // "<path>: truncated or corrupt event after byte N of M"
};

// Whether `path` starts with LCM's event sync word (an LCM log).
bool IsLcmLog(const std::string& path);

// Reads every event of the log. Errors: the file cannot be opened.
Expected<LogContents> ReadLogContents(const std::string& path);

}  // namespace rigcal::report::internal
