// SPDX-License-Identifier: Apache-2.0
// The one comparison of an estimate with a truth: the master unit per master segment (from the
// odometry against the true trajectories) or from the mountings, then every slave scored.
#include "rigcal/io/truth_comparison.h"

#include <spdlog/fmt/fmt.h>

#include <cmath>
#include <limits>
#include <set>

namespace rigcal::io {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double UnitOf(const std::vector<SegmentUnit>& units, int segment) {
  for (const SegmentUnit& unit : units) {
    if (unit.segment == segment) return unit.metres_per_unit;
  }
  return 0.0;
}

bool HasTrajectories(const TruthInput& input) {
  return !input.poses.empty() && !input.trajectories.empty() && !input.poses[0].empty() &&
         static_cast<bool>(input.trajectories[0]);
}

// The master segment the estimate is in: the newest one, unless it has too few poses to fit a
// unit (the master re-initialised at the very end); then the newest one before it that has.
const SegmentUnit* EstimateSegment(const std::vector<SegmentUnit>& master, std::string* note) {
  for (auto it = master.rbegin(); it != master.rend(); ++it) {
    if (it->poses >= 3 && it->metres_per_unit > 0.0) {
      if (it != master.rbegin()) {
        *note = fmt::format(
            "the newest master segment {} has {} poses, too few for a unit: scored in segment {}",
            master.back().segment, master.back().poses, it->segment);
      }
      return &*it;
    }
  }
  return nullptr;
}

// The unit of the estimate's master segment and of every camera's segments.
Status AlignPerSegment(const TruthInput& input, TruthComparison* c) {
  for (size_t i = 0; i < input.poses.size(); ++i) {
    const bool known = i < input.trajectories.size() && input.trajectories[i];
    c->units.push_back(known ? FitSegmentUnits(input.poses[i], input.trajectories[i])
                             : std::vector<SegmentUnit>{});
  }
  std::set<int> segments;
  for (const CameraPose& pose : input.poses[0]) segments.insert(pose.segment);
  c->master_segments = static_cast<int>(segments.size());
  const SegmentUnit* master = EstimateSegment(c->units[0], &c->note);
  if (master == nullptr) {
    return Error{"truth comparison: no master odometry segment has 3 poses with a true pose"};
  }
  c->master_segment = master->segment;
  c->master_metres_per_unit = master->metres_per_unit;
  TruthAlignment& a = c->alignment;
  a.mode = input.unit;
  a.applied = true;
  a.metres_per_unit = master->metres_per_unit;
  a.fit_rms_m = master->fit_rms_m;
  a.message = fmt::format(
      "positions compared after aligning the master unit to the truth per master segment: the "
      "estimate is in master segment {} (of {}), 1 master unit = {:.6g} m (least squares of its "
      "{} odometry poses on the true trajectory, RMS {:.2g} m); each slave's true scale is the "
      "unit of its scored segment over it",
      master->segment, c->master_segments, master->metres_per_unit, master->poses,
      master->fit_rms_m);
  return Status::Ok();
}

// The master unit fitted from the mountings (no trajectories): a slave's unit stays unknown.
void AlignFromMountings(const RigCalibration& result, const TruthInput& input, TruthComparison* c) {
  c->alignment = AlignTruthUnit(result, input.mountings, input.unit);
  if (c->alignment.applied) {
    c->master_metres_per_unit = c->alignment.metres_per_unit;
    c->alignment.message +=
        "; no scale errors: the slaves' odometry units are not known without their true "
        "trajectories";
  }
}

// The truth of one slave in master units.
Similarity SlaveTruth(const TruthComparison& c, const Similarity& truth, size_t camera,
                      int segment) {
  Similarity t = truth;
  if (!c.alignment.applied) return t;
  t.C /= c.master_metres_per_unit;
  const double slave_unit = camera < c.units.size() ? UnitOf(c.units[camera], segment) : 0.0;
  t.scale = slave_unit > 0.0 ? slave_unit / c.master_metres_per_unit : kNaN;
  return t;
}

}  // namespace

double ScoredScale(const SlaveCalibration& slave, int* segment) {
  *segment = 0;
  if (slave.scales.empty()) return slave.estimate.scale;
  *segment = slave.scales.back().segment;
  return slave.scales.back().scale;
}

void ScoreSlave(const SlaveCalibration& slave, SlaveScore* score) {
  Similarity estimate = slave.estimate;
  estimate.scale = ScoredScale(slave, &score->segment);
  score->position_observable = slave.position_observable;
  score->axis.setZero();
  score->axis_unknown = false;
  if (slave.position_observable && slave.unobservable.size() == 1) {
    score->axis = slave.unobservable[0].normalized();
    score->axis_unknown = !slave.unobservable_from_prior;
  } else if (slave.position_observable && slave.observability.planar_axis.norm() > 0.0) {
    score->axis = slave.observability.planar_axis.normalized();
  }
  score->error = CompareToTruth(estimate, score->truth_master_units, score->axis);
  if (score->axis_unknown) {
    // Score what was estimated: direction and distance of C within the plane.
    Similarity in_plane = estimate;
    Similarity truth_in_plane = score->truth_master_units;
    in_plane.C -= in_plane.C.dot(score->axis) * score->axis;
    truth_in_plane.C -= truth_in_plane.C.dot(score->axis) * score->axis;
    const CalibrationError plane = CompareToTruth(in_plane, truth_in_plane);
    score->error.dir_deg = plane.dir_deg;
    score->error.dist_pct = plane.dist_pct;
  }
}

Expected<TruthComparison> CompareWithTruth(const RigCalibration& result, const TruthInput& input) {
  TruthComparison c;
  if (HasTrajectories(input) && input.unit != TruthUnit::kMaster) {
    if (const Status status = AlignPerSegment(input, &c); !status.ok())
      return Error{status.message()};
  } else {
    AlignFromMountings(result, input, &c);
  }
  for (size_t i = 0; i < result.slaves.size(); ++i) {
    const SlaveCalibration& slave = result.slaves[i];
    const auto truth = input.mountings.find(slave.name);
    if (truth == input.mountings.end()) continue;
    SlaveScore score;
    score.name = slave.name;
    score.usable = slave.usable();
    int segment = 0;
    ScoredScale(slave, &segment);
    score.truth_master_units = SlaveTruth(c, truth->second, i + 1, segment);
    ScoreSlave(slave, &score);
    c.truth_master_units[slave.name] = score.truth_master_units;
    c.slaves.push_back(score);
  }
  return c;
}

}  // namespace rigcal::io
