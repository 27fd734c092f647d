// SPDX-License-Identifier: Apache-2.0
// Motion-based calibration against the target-based reference (thesis 5.5, Table 5.2).
#include "rigcal/pattern/reference_compare.h"

#include <cstdio>

#include "rigcal/calib/calibration_options.h"
#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/calib/slave_state.h"
#include "rigcal/pattern/reference_calibration.h"
#include "rigcal/pattern/target_poses.h"

namespace rigcal::pattern {

Expected<std::vector<SlaveComparison>> CompareWithReference(const std::vector<CameraInput>& cameras,
                                                            ReferenceKind reference,
                                                            int64_t tolerance_ns) {
  if (cameras.size() < 2) return Error{"reference comparison: give a master and a slave camera"};
  std::vector<TimedTrajectory> poses;
  for (const CameraInput& c : cameras) {
    poses.push_back(
        PosesAsTrajectory(c.views.camera, c.intrinsics.views, c.intrinsics.rejection_threshold_px));
  }
  // Motion-based: camera-local poses of each camera, matched by time.
  const TimedTrajectory master_local = CameraLocal(poses[0]);
  std::vector<TimedTrajectory> slaves_local;
  for (size_t i = 1; i < poses.size(); ++i) slaves_local.push_back(CameraLocal(poses[i]));
  auto recording = io::MatchTrajectories(master_local, slaves_local, tolerance_ns);
  if (!recording) return Error{"motion-based: " + recording.error()};
  CalibrationOptions lls;
  lls.method = Method::kLinear;
  CalibrationOptions nl;
  nl.method = Method::kNonlinear;
  const RigCalibration result_lls = CalibrateRig(*recording, lls);
  const RigCalibration result_nl = CalibrateRig(*recording, nl);

  std::vector<SlaveComparison> out;
  for (size_t i = 1; i < cameras.size(); ++i) {
    SlaveComparison cmp;
    cmp.slave = poses[i].name;
    auto global = EstimateGlobalReference(poses[0], poses[i], tolerance_ns);
    if (!global) return Error{global.error()};
    double stereo_rms = 0.0;
    auto stereo =
        EstimateStereoReference(cameras[0].views, cameras[0].intrinsics.spec, cameras[i].views,
                                cameras[i].intrinsics.spec, &stereo_rms);
    cmp.reference = "global";
    if (reference == ReferenceKind::kStereo || (reference == ReferenceKind::kAuto && stereo)) {
      if (!stereo) return Error{cmp.slave + ": stereo reference: " + stereo.error()};
      cmp.reference = "stereo";
    }
    const Similarity ref =
        cmp.reference == "stereo" ? stereo->master_from_slave : global->master_from_slave;
    char note[160];
    if (stereo) {
      std::snprintf(note, sizeof(note), "joint RMS %.3f px, %d view pairs", stereo_rms,
                    stereo->instants);
      cmp.rows.push_back({"target stereoCalibrate", stereo->master_from_slave, true, note, {}});
    }
    std::snprintf(note, sizeof(note), "%d instants, σ %.3f deg", global->instants,
                  global->rot_std_deg);
    cmp.rows.push_back({"target global model", global->master_from_slave, true, note, {}});
    for (const RigCalibration* r : {&result_lls, &result_nl}) {
      const SlaveCalibration& s = r->slaves[i - 1];
      std::snprintf(note, sizeof(note), "%s, %d motions, scale %.5f",
                    std::string(ToString(s.state)).c_str(), s.motions.used, s.estimate.scale);
      cmp.rows.push_back({r == &result_lls ? "motion-based LLS" : "motion-based NL",
                          s.estimate,
                          s.usable(),
                          note,
                          {}});
    }
    for (ComparisonRow& row : cmp.rows) {
      row.error = CompareToTruth(row.estimate, Similarity{ref.q, ref.C, 1.0});
    }
    out.push_back(std::move(cmp));
  }
  return out;
}

std::string FormatComparison(const SlaveComparison& cmp, const std::string& master) {
  std::string text;
  char line[512];
  std::snprintf(line, sizeof(line),
                "%s in the frame of %s against the %s reference (thesis Table 5.2 columns; "
                "positions in the target's unit)\n",
                cmp.slave.c_str(), master.c_str(),
                cmp.reference == "stereo" ? "stereoCalibrate" : "global-model");
  text += line;
  std::snprintf(line, sizeof(line), "%-23s %-36s %-28s %8s %8s %8s %8s  %s\n", "method", "q_wxyz",
                "C", "|C|", "rot_deg", "dir_deg", "len_pct", "");
  text += line;
  for (const ComparisonRow& row : cmp.rows) {
    const Similarity& s = row.estimate;
    char q[80];
    char c[80];
    std::snprintf(q, sizeof(q), "[%.5f %.5f %.5f %.5f]", s.q.w(), s.q.x(), s.q.y(), s.q.z());
    std::snprintf(c, sizeof(c), "[%.4g %.4g %.4g]", s.C.x(), s.C.y(), s.C.z());
    std::snprintf(line, sizeof(line), "%-23s %-36s %-28s %8.5g %8.4f %8.4f %8.4f  %s\n",
                  row.method.c_str(), q, c, s.C.norm(), row.error.rot_deg, row.error.dir_deg,
                  row.error.dist_pct, row.note.c_str());
    text += line;
  }
  return text;
}

}  // namespace rigcal::pattern
