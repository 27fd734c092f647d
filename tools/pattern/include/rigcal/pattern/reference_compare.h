// SPDX-License-Identifier: Apache-2.0
#pragma once
// The motion-based calibration against the target-based reference on one recording with
// target views (thesis 5.5, Table 5.2): from every camera's views and intrinsics, the target
// poses (PnP); the reference from them (OpenCV stereoCalibrate with the intrinsics fixed, and
// the global reference pose model); the motion-based calibration (LLS and NL) from each
// camera's camera-local poses, i.e. only its own motion, no shared observation; and every
// estimate's errors against the reference in the thesis's columns (rotation error, position
// direction error, baseline length error).

#include <string>
#include <vector>

#include "rigcal/calib/error_model.h"
#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/pattern/intrinsics.h"
#include "rigcal/pattern/target_views.h"

namespace rigcal::pattern {

enum class ReferenceKind { kAuto, kStereo, kGlobal };  // auto: stereo for pinhole cameras

struct ComparisonRow {
  std::string method;   // "target stereoCalibrate", "target global model", "motion-based LLS", ...
  Similarity estimate;  // slave in the master frame, the target's unit
  bool usable = true;   // motion-based: the calibrator's state is usable
  std::string note;
  CalibrationError error;  // against the reference (rot_deg, dir_deg, dist_pct)
};

struct SlaveComparison {
  std::string slave;
  std::string reference;  // "stereo" or "global"
  std::vector<ComparisonRow> rows;
};

struct CameraInput {
  CameraViews views;
  IntrinsicsResult intrinsics;
};

// cameras[0] is the master. Views are simultaneous when their t_ns differ by at most
// tolerance_ns. Errors: fewer than 2 cameras, too few shared instants, the motion-based
// matching failing, a stereo reference asked for non-pinhole cameras.
Expected<std::vector<SlaveComparison>> CompareWithReference(const std::vector<CameraInput>& cameras,
                                                            ReferenceKind reference,
                                                            int64_t tolerance_ns);

// The table of one slave, one row per method.
std::string FormatComparison(const SlaveComparison& comparison, const std::string& master);

}  // namespace rigcal::pattern
