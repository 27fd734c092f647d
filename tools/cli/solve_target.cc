// SPDX-License-Identifier: Apache-2.0
// `rigcal solve --reference target`, `--metric-target`, `--master-metric`.
#include "solve_target.h"

#include <cstdio>

#include "rigcal/pattern/individual_reference.h"
#include "rigcal/pattern/metric_scale.h"
#include "rigcal/pattern/reference_calibration.h"

namespace rigcal::cli {

Expected<RigCalibration> TargetReferenceResult(const TimedTrajectory& master,
                                               const std::vector<TimedTrajectory>& slaves,
                                               int64_t tolerance_ns, bool individual) {
  RigCalibration result;
  result.master = master.name;
  for (const TimedTrajectory& slave : slaves) {
    Expected<pattern::ReferenceEstimate> reference = Error{""};
    std::string model = "global reference pose model, thesis 4.2): mean of";
    if (individual) {
      auto fitted = pattern::EstimateIndividualReference(master, slave, tolerance_ns);
      if (!fitted) return Error{fitted.error()};
      reference = fitted->estimate;
      model = "individual reference pose model, thesis 4.2): T_0 dT = W T_i fitted to";
    } else {
      reference = pattern::EstimateGlobalReference(master, slave, tolerance_ns);
    }
    if (!reference) return Error{reference.error()};
    SlaveCalibration s;
    s.name = slave.name;
    s.pairs = "target reference";
    s.estimate = reference->master_from_slave;
    s.scales.push_back(SegmentScale{0, 1.0, 0.0, 1.0, 0.0, reference->instants});
    s.rot_std_deg = reference->rot_std_deg;
    s.pos_std = reference->pos_std;
    s.motions.total = reference->instants + reference->rejected;
    s.motions.used = reference->instants;
    s.motions.residual_outlier = reference->rejected;
    s.termination = Termination::kSolved;
    s.state = SlaveState::kConverged;
    char message[400];
    std::snprintf(message, sizeof(message),
                  "target reference (%s %d instants (%d rejected), spread %.3f deg / %.3g per "
                  "instant",
                  model.c_str(), reference->instants, reference->rejected,
                  reference->rot_spread_deg, reference->pos_spread);
    s.message = message;
    result.slaves.push_back(std::move(s));
  }
  return result;
}

nlohmann::json ResultUnit::ToJson() const {
  return {{"metric", metric},
          {"metres_per_master_unit", metres_per_master_unit},
          {"std", std},
          {"source", source},
          {"message", message}};
}

Expected<ResultUnit> ApplyMetricTarget(const std::string& target_file,
                                       const TimedTrajectory& master, int64_t tolerance_ns,
                                       RigCalibration* result) {
  io::TrajectoryReadOptions options;
  auto poses = io::ReadTrajectory(target_file, options);
  if (!poses) return Error{"--metric-target: " + poses.error()};
  auto scale = pattern::EstimateWorldScale(master, *poses, tolerance_ns);
  if (!scale) return Error{"--metric-target " + target_file + ": " + scale.error()};
  pattern::ScaleResult(scale->metres_per_unit, result);
  ResultUnit unit;
  unit.metric = true;
  unit.metres_per_master_unit = scale->metres_per_unit;
  unit.std = scale->std;
  unit.source = "target";
  unit.message = scale->message;
  return unit;
}

std::string UnobservableHeightNote(const RigCalibration& result) {
  std::string text;
  for (const SlaveCalibration& s : result.slaves) {
    if (s.unobservable.empty()) continue;
    const Eigen::Vector3d& axis = s.unobservable.front();
    char line[400];
    std::snprintf(line, sizeof(line),
                  "%s: planar motion: C along the rotation axis [%.3f %.3f %.3f] (the mounting "
                  "height) is not observable; %s\n",
                  s.name.c_str(), axis.x(), axis.y(), axis.z(),
                  s.unobservable_from_prior
                      ? "it is the nominal mounting's (--prior)"
                      : "it is reported as 0: give the nominal mounting height with --prior "
                        "(a rig YAML or a rig config's cameras[].nominal)");
    text += line;
  }
  return text;
}

}  // namespace rigcal::cli
