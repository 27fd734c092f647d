// SPDX-License-Identifier: Apache-2.0
// `rigcal reference-compare`: the motion-based calibration against the target-based reference
// on the same recording, in the columns of the thesis's Table 5.2.
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "exit_codes.h"
#include "rigcal/pattern/reference_compare.h"
#include "target_args.h"

namespace rigcal::cli {
namespace {

constexpr int kExitUnusable = 3;

struct CompareArgs {
  TargetArgs target;
  std::string reference = "auto";
  double tolerance_ms = 1.0;
  bool json = false;
};

int RunCompare(const CompareArgs& args) {
  if (args.target.cameras.size() < 2) {
    return PrintCommandError("reference-compare",
                             "--camera: give the master and at least one slave");
  }
  auto cameras = CalibrateCameras(args.target);
  if (!cameras) return PrintCommandError("reference-compare", cameras.error());
  std::vector<pattern::CameraInput> inputs;
  for (CameraCalibration& c : *cameras) inputs.push_back({c.views, c.intrinsics});
  const pattern::ReferenceKind kind = args.reference == "stereo"   ? pattern::ReferenceKind::kStereo
                                     : args.reference == "global" ? pattern::ReferenceKind::kGlobal
                                                                  : pattern::ReferenceKind::kAuto;
  const auto tolerance_ns = static_cast<int64_t>(std::llround(args.tolerance_ms * 1e6));
  auto comparisons = pattern::CompareWithReference(inputs, kind, tolerance_ns);
  if (!comparisons) return PrintCommandError("reference-compare", comparisons.error());

  const std::string& master = inputs.front().views.camera;
  bool all_usable = true;
  nlohmann::json json = {{"master", master},
                         {"unit", "the target's (chessboard --square, AprilGrid metres)"},
                         {"cameras", nlohmann::json::array()},
                         {"slaves", nlohmann::json::array()}};
  for (const pattern::CameraInput& c : inputs) {
    const auto& s = c.intrinsics.spec;
    json["cameras"].push_back({{"name", s.name},
                               {"intrinsics", s.intrinsics},
                               {"distortion", s.distortion},
                               {"rms_px", c.intrinsics.rms_px},
                               {"views_used", c.intrinsics.views_used},
                               {"views_rejected", c.intrinsics.views_rejected}});
  }
  for (const pattern::SlaveComparison& cmp : *comparisons) {
    nlohmann::json rows = nlohmann::json::array();
    for (const pattern::ComparisonRow& row : cmp.rows) {
      const Similarity& s = row.estimate;
      all_usable = all_usable && row.usable;
      rows.push_back({{"method", row.method},
                      {"q_wxyz", {s.q.w(), s.q.x(), s.q.y(), s.q.z()}},
                      {"C", {s.C.x(), s.C.y(), s.C.z()}},
                      {"baseline", s.C.norm()},
                      {"usable", row.usable},
                      {"rot_err_deg", row.error.rot_deg},
                      {"dir_err_deg", row.error.dir_deg},
                      {"length_err_pct", row.error.dist_pct},
                      {"note", row.note}});
    }
    json["slaves"].push_back({{"name", cmp.slave}, {"reference", cmp.reference}, {"rows", rows}});
  }
  if (args.json) {
    std::cout << json.dump(2) << "\n";
  } else {
    for (const pattern::CameraInput& c : inputs) {
      std::cout << pattern::FormatIntrinsics(c.intrinsics, false);
    }
    for (const pattern::SlaveComparison& cmp : *comparisons) {
      std::cout << pattern::FormatComparison(cmp, master);
    }
  }
  return all_usable ? kExitOk : kExitUnusable;
}

}  // namespace

void RegisterReferenceCompare(CLI::App& app, int* exit_code) {
  auto args = std::make_shared<CompareArgs>();
  CLI::App* cmd = app.add_subcommand(
      "reference-compare",
      "Motion-based calibration against the target-based reference on one recording with\n"
      "target views (thesis 5.5): intrinsics per camera, target poses (PnP), then the\n"
      "reference (OpenCV stereoCalibrate and the global reference pose model) and the\n"
      "motion-based calibration from each camera's camera-local poses (no shared\n"
      "observation), side by side with the errors of Table 5.2.");
  AddTargetOptions(cmd, &args->target);
  cmd->add_option("--reference", args->reference,
                  "What the errors are measured against. stereo: OpenCV stereoCalibrate\n"
                  "(intrinsics fixed); global: the mean of the per-instant relative poses\n"
                  "(thesis 4.2); auto: stereo for pinhole cameras, else global.")
      ->check(CLI::IsMember({"auto", "stereo", "global"}))
      ->capture_default_str();
  cmd->add_option("--tolerance-ms", args->tolerance_ms,
                  "Views of two cameras are simultaneous when their keys differ by at most this")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_flag("--json", args->json, "Print the table as one JSON object on stdout");
  cmd->footer(
      "Columns: rot_deg, the angle of the rotation between estimate and reference; dir_deg,\n"
      "the angle between their position vectors C; len_pct, | |C| - |C_ref| | / |C_ref|.\n"
      "Exit status: 0 every row usable; 1 bad input; 3 a motion-based estimate not usable.");
  cmd->callback([args, exit_code]() {
    try {
      *exit_code = RunCompare(*args);
    } catch (const std::exception& e) {
      *exit_code = PrintCommandError("reference-compare", e.what());
    }
  });
}

}  // namespace rigcal::cli
