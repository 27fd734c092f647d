// SPDX-License-Identifier: Apache-2.0
// The printed table of a truth comparison.
#include <cmath>
#include <cstdio>
#include <sstream>

#include "rigcal/base/format.h"
#include "rigcal/io/truth_comparison.h"

namespace rigcal::io {
namespace {

std::string Figure(double v, bool known) {
  if (!known) return "unobs";
  if (!std::isfinite(v)) return "-";
  return FixedText(v, 4);
}

std::string Row(const SlaveScore& e, double mm_per_unit) {
  char line[200];
  if (!e.usable) {
    std::snprintf(line, sizeof(line), "%-10s %10s %10s %10s %10s %10s %10s  no usable estimate\n",
                  e.name.c_str(), "-", "-", "-", "-", "-", "-");
    return line;
  }
  const bool position = e.position_observable;
  std::snprintf(line, sizeof(line), "%-10s %10.4f %10s %10s %10s %10s %10s  (segment %d)\n",
                e.name.c_str(), e.error.rot_deg, Figure(e.error.dir_deg, position).c_str(),
                Figure(e.error.dist_pct, position).c_str(), Figure(e.error.scale_pct, true).c_str(),
                Figure(e.error.plane_err * mm_per_unit, position).c_str(),
                Figure(e.error.axis_err * mm_per_unit, position && !e.axis_unknown).c_str(),
                e.segment);
  return line;
}

}  // namespace

std::string FormatTruthComparison(const TruthComparison& comparison) {
  std::ostringstream out;
  const bool metric = comparison.alignment.applied;
  // Position errors in mm when the master unit is known in metres, else in master units.
  const double per_unit = metric ? 1000.0 * comparison.master_metres_per_unit : 1.0;
  char line[200];
  std::snprintf(line, sizeof(line), "%-10s %10s %10s %10s %10s %10s %10s\n", "slave", "rot[deg]",
                "dir[deg]", "dist[%]", "scale[%]", metric ? "plane[mm]" : "plane[u]",
                metric ? "axis[mm]" : "axis[u]");
  out << "Errors against the truth (thesis 5.1.1):\n" << line;
  bool any_in_plane = false;
  bool any_unknown_scale = false;
  for (const SlaveScore& e : comparison.slaves) {
    out << Row(e, per_unit);
    any_in_plane = any_in_plane || (e.usable && e.axis_unknown);
    any_unknown_scale = any_unknown_scale || (e.usable && !std::isfinite(e.error.scale_pct));
  }
  out << comparison.alignment.message << "\n";
  if (any_unknown_scale) out << "scale[%] -: the slave's odometry unit is not known\n";
  if (any_in_plane) {
    out << "planar motion: dir and dist compare C in the plane orthogonal to the rotation axis "
           "(the offset along it is unobservable without a nominal mounting)\n";
  }
  if (!comparison.note.empty()) out << "note: " << comparison.note << "\n";
  return out.str();
}

}  // namespace rigcal::io
