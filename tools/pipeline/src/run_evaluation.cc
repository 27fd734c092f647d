#include "rigcal/pipeline/run_evaluation.h"

#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include "rigcal/base/format.h"
#include "rigcal/io/truth_alignment.h"

namespace rigcal::pipeline {
namespace {

// Unit of every VO segment of camera `camera`.
std::vector<SegmentUnit> SegmentUnits(const sim::SimulatedRig& rig, int camera,
                                      const std::vector<CameraPose>& poses) {
  std::map<int, std::vector<const CameraPose*>> by_segment;
  for (const CameraPose& pose : poses) by_segment[pose.segment].push_back(&pose);
  std::vector<SegmentUnit> units;
  const double epoch_ns = static_cast<double>(rig.epoch_ns());
  auto stream_time = [&](int64_t t_ns) { return 1e-9 * (static_cast<double>(t_ns) - epoch_ns); };
  for (const auto& [segment, members] : by_segment) {
    // Positions relative to the segment's first pose, in its frame, on both sides: the VO's
    // origin need not be its first pose written (an initialisation frame before it, a pose
    // dropped on the way), and a wrong origin shrinks the fitted unit.
    const Pose reference = rig.WorldFromCameraAt(camera, stream_time(members.front()->t_ns));
    const Pose& first = members.front()->pose;
    std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> pairs;
    for (const CameraPose* pose : members) {
      const Pose truth = reference.Between(rig.WorldFromCameraAt(camera, stream_time(pose->t_ns)));
      pairs.emplace_back(truth.C, first.Between(pose->pose).C);
    }
    const io::UnitFit fit = io::FitUnit(pairs);
    SegmentUnit unit;
    unit.segment = segment;
    unit.poses = static_cast<int>(members.size());
    unit.metres_per_unit = fit.metres_per_unit;
    unit.fit_rms_m = fit.fit_rms_m;
    units.push_back(unit);
  }
  return units;
}

}  // namespace

Expected<RunEvaluation> EvaluateRun(const sim::SimulatedRig& rig,
                                    const std::vector<std::vector<CameraPose>>& poses,
                                    const RigCalibration& result) {
  if (poses.size() != static_cast<size_t>(rig.num_cameras())) {
    return Error{"evaluation: expected poses of " + std::to_string(rig.num_cameras()) +
                 " cameras, got " + std::to_string(poses.size())};
  }
  RunEvaluation evaluation;
  for (int camera = 0; camera < rig.num_cameras(); ++camera) {
    evaluation.units.push_back(SegmentUnits(rig, camera, poses[static_cast<size_t>(camera)]));
  }
  // The master's unit: its segment with the most poses.
  const SegmentUnit* master = nullptr;
  for (const SegmentUnit& unit : evaluation.units[0]) {
    if (unit.poses >= 3 && unit.metres_per_unit > 0.0 &&
        (master == nullptr || unit.poses > master->poses)) {
      master = &unit;
    }
  }
  if (master == nullptr) {
    return Error{"evaluation: the master's VO produced no segment with 3 poses or more"};
  }
  evaluation.master_segment = master->segment;
  evaluation.master_metres_per_unit = master->metres_per_unit;
  if (evaluation.units[0].size() > 1) {
    evaluation.note = "the master VO re-initialised (" +
                      std::to_string(evaluation.units[0].size()) +
                      " segments); distances are scored in the unit of its longest segment";
  }
  const std::vector<Similarity> truth = rig.TrueRig();
  for (size_t i = 0; i < result.slaves.size() && i < truth.size(); ++i) {
    const SlaveCalibration& slave = result.slaves[i];
    SlaveEvaluation e;
    e.name = slave.name;
    e.usable = slave.usable();
    // The scored slave segment: the estimate's newest segment scale, if any.
    double estimated_scale = slave.estimate.scale;
    e.segment = 0;
    if (!slave.scales.empty()) {
      e.segment = slave.scales.back().segment;
      estimated_scale = slave.scales.back().scale;
    }
    double slave_metres_per_unit = 0.0;
    for (const SegmentUnit& unit : evaluation.units[i + 1]) {
      if (unit.segment == e.segment) slave_metres_per_unit = unit.metres_per_unit;
    }
    e.truth_master_units.q = truth[i].q;
    e.truth_master_units.C = truth[i].C / evaluation.master_metres_per_unit;
    e.truth_master_units.scale = slave_metres_per_unit > 0.0
                                     ? slave_metres_per_unit / evaluation.master_metres_per_unit
                                     : std::nan("");
    ScoreEstimate(slave, estimated_scale, &e);
    evaluation.slaves.push_back(e);
  }
  return evaluation;
}

void ScoreEstimate(const SlaveCalibration& slave, double estimated_scale, SlaveEvaluation* e) {
  Similarity estimate = slave.estimate;
  estimate.scale = estimated_scale;
  e->position_observable = slave.position_observable;
  e->axis.setZero();
  e->axis_unknown = false;
  if (slave.position_observable && slave.unobservable.size() == 1) {
    e->axis = slave.unobservable[0].normalized();
    e->axis_unknown = !slave.unobservable_from_prior;
  }
  e->error = CompareToTruth(estimate, e->truth_master_units, e->axis);
  if (e->axis_unknown) {
    // Score what was estimated: direction and distance of C within the plane.
    Similarity in_plane = estimate, truth_in_plane = e->truth_master_units;
    in_plane.C -= in_plane.C.dot(e->axis) * e->axis;
    truth_in_plane.C -= truth_in_plane.C.dot(e->axis) * e->axis;
    const CalibrationError plane = CompareToTruth(in_plane, truth_in_plane);
    e->error.dir_deg = plane.dir_deg;
    e->error.dist_pct = plane.dist_pct;
  }
}

io::TruthAlignment AlignmentOf(const RunEvaluation& evaluation) {
  io::TruthAlignment a;
  a.mode = io::TruthUnit::kMetric;
  a.applied = true;
  a.metres_per_unit = evaluation.master_metres_per_unit;
  for (const SegmentUnit& unit :
       evaluation.units.empty() ? std::vector<SegmentUnit>{} : evaluation.units[0]) {
    if (unit.segment == evaluation.master_segment) a.fit_rms_m = unit.fit_rms_m;
  }
  a.message = "positions compared after aligning the master unit to the truth: 1 master unit = " +
              SignificantText(a.metres_per_unit, 6) +
              " m (least squares of the master's VO poses on its true trajectory, VO segment " +
              std::to_string(evaluation.master_segment) + ")";
  return a;
}

std::string FormatEvaluation(const RunEvaluation& evaluation) {
  std::ostringstream out;
  char line[200];
  const double mm = 1000.0 * evaluation.master_metres_per_unit;  // master unit -> mm
  auto figure = [](double v, bool known) {
    if (!known || !std::isfinite(v)) return std::string(known ? "-" : "unobs");
    return FixedText(v, 4);
  };
  std::snprintf(line, sizeof(line), "%-10s %10s %10s %10s %10s %10s %10s  %s\n", "slave",
                "rot[deg]", "dir[deg]", "dist[%]", "scale[%]", "plane[mm]", "axis[mm]", "");
  out << "Errors against the simulated ground truth (thesis 5.1.1):\n" << line;
  bool any_in_plane = false;
  for (const SlaveEvaluation& e : evaluation.slaves) {
    if (!e.usable) {
      std::snprintf(line, sizeof(line), "%-10s %10s %10s %10s %10s %10s %10s  no usable estimate\n",
                    e.name.c_str(), "-", "-", "-", "-", "-", "-");
    } else {
      const bool planar = e.axis.squaredNorm() > 0.0;
      any_in_plane = any_in_plane || e.axis_unknown;
      std::snprintf(
          line, sizeof(line), "%-10s %10.4f %10s %10s %10.4f %10s %10s  (segment %d)\n",
          e.name.c_str(), e.error.rot_deg, figure(e.error.dir_deg, e.position_observable).c_str(),
          figure(e.error.dist_pct, e.position_observable).c_str(), e.error.scale_pct,
          figure(planar ? e.error.plane_err * mm : std::nan(""), e.position_observable).c_str(),
          figure(planar ? e.error.axis_err * mm : std::nan(""),
                 e.position_observable && !e.axis_unknown)
              .c_str(),
          e.segment);
    }
    out << line;
  }
  out << AlignmentOf(evaluation).message << "\n";
  if (any_in_plane) {
    out << "planar motion: dir and dist compare C in the plane orthogonal to the rotation axis "
           "(the offset along it is unobservable without a nominal mounting)\n";
  }
  if (!evaluation.note.empty()) out << "note: " << evaluation.note << "\n";
  return out.str();
}

}  // namespace rigcal::pipeline
