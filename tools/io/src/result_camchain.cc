// SPDX-License-Identifier: Apache-2.0
// The camchain of a result: the slaves' estimates chained, in metres when the unit is known.
#include "rigcal/io/result_camchain.h"

#include <algorithm>
#include <cmath>

#include "rigcal/io/kalibr_camchain.h"

namespace rigcal::io {
namespace {

// The cameras to write, master first.
Expected<std::vector<std::string>> Order(const RigCalibration& result,
                                         const std::vector<std::string>& requested) {
  std::vector<std::string> order = requested;
  if (order.empty()) {
    order.push_back(result.master);
    for (const SlaveCalibration& s : result.slaves) {
      if (s.usable()) order.push_back(s.name);
    }
  }
  if (order.front() != result.master) {
    return Error{"the first camera must be the master '" + result.master + "', got '" +
                 order.front() + "'"};
  }
  return order;
}

std::string Comment(const CamchainOptions& options, bool metric,
                    const std::vector<std::string>& no_intrinsics) {
  std::string comment =
      "Kalibr camchain written by rigcal: cam0 is the master, T_cn_cnm1 takes points from\n"
      "camera n-1 to camera n.\n";
  comment += metric ? "Translations in metres (" + options.unit_source + ").\n"
                    : "Translations in the master odometry's unit, not metres "
                      "(rigcal_translation_unit): give a metric master, a target reference or "
                      "--metric-* for metres.\n";
  if (!no_intrinsics.empty()) {
    std::string names;
    for (const std::string& name : no_intrinsics) names += (names.empty() ? "" : ", ") + name;
    comment += "No intrinsics in the rig config for " + names +
               ": extrinsics only for them (not loadable by Kalibr).\n";
  }
  return comment;
}

}  // namespace

Expected<CamchainWritten> WriteCamchain(const std::string& path, const RigCalibration& result,
                                        const CamchainOptions& options) {
  const std::string where = "cannot write camchain '" + path + "': ";
  auto order = Order(result, options.camera_order);
  if (!order) return Error{where + order.error()};
  CamchainWritten written;
  written.metric = std::isfinite(options.metres_per_unit) && options.metres_per_unit > 0.0;
  const double to_metres = written.metric ? options.metres_per_unit : 1.0;
  std::vector<CamchainEntry> entries;
  for (size_t n = 0; n < order->size(); ++n) {
    const std::string& name = (*order)[n];
    CamchainEntry entry;
    entry.translation_unit = written.metric ? "m" : "master_odometry_unit";
    if (n > 0) {
      const auto it = std::find_if(result.slaves.begin(), result.slaves.end(),
                                   [&](const SlaveCalibration& s) { return s.name == name; });
      if (it == result.slaves.end()) return Error{where + "unknown camera '" + name + "'"};
      if (!it->usable()) {
        return Error{where + "camera '" + name + "' has no usable estimate (" +
                     ToString(it->termination) + ")"};
      }
      Similarity master_from_cam = it->estimate;
      master_from_cam.C *= to_metres;
      entry.cam0_from_cam = master_from_cam;
    }
    const auto spec = options.intrinsics.find(name);
    entry.intrinsics_known = spec != options.intrinsics.end();
    if (entry.intrinsics_known) {
      entry.spec = spec->second;
    } else {
      written.no_intrinsics.push_back(name);
    }
    entry.spec.name = name;
    entries.push_back(entry);
  }
  const Status status =
      WriteKalibrCamchain(path, entries, Comment(options, written.metric, written.no_intrinsics));
  if (!status.ok()) return Error{status.message()};
  return written;
}

}  // namespace rigcal::io
