// SPDX-License-Identifier: Apache-2.0
#pragma once
// Rig parameter files (YAML): truth files, solve results and Kalibr-style camera chains.
//
// Rig YAML, keyed by slave name (the slave trajectory's file stem):
//   master: cam0                       # optional metadata (scalar), ignored by the reader
//   cam1:
//     q_wxyz: [w, x, y, z]             # orientation of the slave in the master frame
//     C: [x, y, z]                     # slave camera centre in the master frame, master units
//     scale: s                         # slave odometry unit -> master unit (p_master = s R p + C)
//     scales: [{segment: id, scale: s}, ...]   # optional, one per scale segment
// i.e. the similarity dT = [s dR | dC] of the thesis (rigcal::Similarity). A result file has
// the same entries plus the estimate's uncertainty, motion counts, models and termination,
// so it can be read back as a rig file. Reserved top-level keys holding scalars (`master`,
// `pairs_selected`) are metadata; every other top-level key must be a slave map.

#include <Eigen/Core>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/calib/calibration_result.h"

namespace rigcal::io {

// Reads a rig YAML file (truth or result). Quaternions are normalised when their norm is
// within 1e-3 of 1 (hand-typed values with 4 decimals), else rejected. Errors start with
// `<path>:<line>: <slave>.<field>` and say what is wrong: unreadable file, YAML syntax,
// missing q_wxyz / C / scale, wrong length, non-numeric or non-finite entry, scale <= 0,
// malformed `scales` entries, no slaves.
// `expected_master` (when not empty): a file whose `master:` names another camera is an error
// naming the file and line (its poses are relative to another camera).
Expected<std::map<std::string, Similarity>> ReadRigYaml(const std::string& path,
                                                        const std::string& expected_master = "");

// Nominal mountings (CAD values) for `rigcal solve --prior`: a rig YAML as above (a truth or
// result file), or a rig config (docs/config.md; recognised by its `cameras` key) whose
// cameras[].nominal are taken, by camera name. Errors as ReadRigYaml / LoadRigConfig, or no
// camera with a nominal mounting.
Expected<std::map<std::string, Similarity>> ReadNominalMountings(const std::string& path);

// True mountings (`rigcal report --truth`): a rig YAML, or a rig config whose cameras[].truth are
// taken (simulated rigs). Errors as ReadNominalMountings.
Expected<std::map<std::string, Similarity>> ReadTrueMountings(
    const std::string& path, const std::string& expected_master = "");

// The rig YAML text of `rig` (slave name -> similarity), numbers in shortest round-trip form.
std::string RigToYaml(const std::map<std::string, Similarity>& rig);

// The rig YAML text of `slaves` (name, similarity) in their order, after `comment` (each line
// written as "# <line>") and, unless `master` is empty, the metadata `master: <master>`.
std::string RigToYaml(const std::vector<std::pair<std::string, Similarity>>& slaves,
                      const std::string& master, const std::string& comment);

// Writes RigToYaml(rig) atomically. The error names the path.
[[nodiscard]] Status WriteRigYaml(const std::string& path,
                                  const std::map<std::string, Similarity>& rig);

// The result YAML text of `result`: `master`, `pairs_selected`, and per slave the rig entry
// (the estimate; present even when unusable, so check `usable`) plus `usable`, `termination`,
// `message`, `std: {rot_deg, pos, axis[, scale]}` (scale: the σ of a single scale), `motions:
// {total, used, rejected, small_rotation, angle_mismatch, residual_outlier}`, `glitches: {dropped,
// position_jump, rotation_jump, angle_mismatch, in_master, in_slave}` (calibration_result.h),
// `models: {motion, scale}`, `position_observable`, `unobservable` (unit directions in the master
// frame), `unobservable_from_prior` and `observability` (the figures behind the model, keys as in
// the JSON schema of result_json.h). `scales` (with `std`) is written when the slave has several
// segment or partition scales. Non-finite numbers are written as .nan / .inf.
std::string ResultToYaml(const RigCalibration& result);

// Writes ResultToYaml(result) atomically. The error names the path.
[[nodiscard]] Status WriteResultYaml(const std::string& path, const RigCalibration& result);

// Writing a camchain of a result: result_camchain.h.

struct CamchainCamera {
  std::string name;  // rigcal_name, empty when absent
  // T_cn_cnm1 of camera n; identity for cam0.
  Eigen::Matrix4d cn_from_cnm1 = Eigen::Matrix4d::Identity();
};

// Reads the cameras cam0, cam1, ... of a camchain YAML (T_cn_cnm1 and rigcal_name only).
// Errors name the path, line and field (missing T_cn_cnm1, not 4x4, non-numeric, last row not
// 0 0 0 1, rotation block not orthonormal within 1e-6).
Expected<std::vector<CamchainCamera>> ReadCamchain(const std::string& path);

}  // namespace rigcal::io
