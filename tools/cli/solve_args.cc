// SPDX-License-Identifier: Apache-2.0
// The option table of `rigcal solve` and the parsers of its values.
#include "solve_args.h"

#include <algorithm>

namespace rigcal::cli {
namespace {

// Parses the positive integer after `prefix` in `text` ("partitions:4" -> 4), else 0.
int CountAfter(const std::string& text, const std::string& prefix) {
  if (text.rfind(prefix, 0) != 0 || text.size() == prefix.size()) return 0;
  const std::string digits = text.substr(prefix.size());
  if (digits.find_first_not_of("0123456789") != std::string::npos || digits.size() > 6) return 0;
  return std::stoi(digits);
}

// One --time-offset value: nullopt for auto, else seconds; sets *error on a bad value.
std::optional<double> ParseTimeOffset(const std::string& text, std::string* error = nullptr) {
  if (text == "auto") return std::nullopt;
  const auto ns = io::ParseSecondsToNs(text);
  if (!ns && error != nullptr) *error = "expected auto or a number of seconds, got '" + text + "'";
  return ns ? static_cast<double>(*ns) * 1e-9 : 0.0;
}

CLI::Validator ValueCheck(std::string (*apply)(const std::string&), const std::string& desc) {
  return CLI::Validator([apply](std::string& value) { return apply(value); }, desc);
}

}  // namespace

// --scale value -> options; returns an error text or "".
std::string ApplyScale(const std::string& text, CalibrationOptions* options) {
  if (text == "auto") {
    options->scale_model = ScaleModel::kAuto;
  } else if (text == "fixed") {
    options->scale_model = ScaleModel::kFixed;
  } else if (text == "segments") {
    options->scale_model = ScaleModel::kSegments;
  } else if (const int n = CountAfter(text, "partitions:"); n > 0) {
    options->scale_model = ScaleModel::kPartitions;
    options->partitions = n;
  } else {
    return "expected auto, fixed, segments or partitions:N with N >= 1, got '" + text + "'";
  }
  return "";
}

// --pairs value -> options; returns an error text or "".
std::string ApplyPairs(const std::string& text, PairOptions* pairs) {
  if (text == "auto") {
    pairs->policy = PairOptions::Policy::kAuto;
  } else if (text == "start") {
    pairs->policy = PairOptions::Policy::kSinceStart;
  } else if (text == "walk") {
    pairs->policy = PairOptions::Policy::kWalk;
  } else if (text == "gls") {
    pairs->policy = PairOptions::Policy::kGls;
  } else if (const int step = CountAfter(text, "relative:"); step > 0) {
    pairs->policy = PairOptions::Policy::kRelative;
    pairs->step = step;
  } else {
    return "expected auto, gls, start, walk or relative:STEP with STEP >= 1, got '" + text + "'";
  }
  return "";
}

// --time-offset: "auto" or SECONDS for every slave, or per slave "NAME=auto|SECONDS,..."
// (slaves not named: 0). `slaves` empty: the syntax only. Sets *error (naming the entry).
std::vector<std::optional<double>> ParseTimeOffsets(const std::string& text,
                                                    const std::vector<std::string>& slaves,
                                                    std::string* error) {
  if (text.find('=') == std::string::npos) {
    return std::vector<std::optional<double>>(slaves.size(), ParseTimeOffset(text, error));
  }
  std::vector<std::optional<double>> out(slaves.size(), 0.0);
  std::vector<bool> named(slaves.size(), false);
  size_t start = 0;
  while (start <= text.size()) {
    const size_t end = std::min(text.find(',', start), text.size());
    const std::string entry = text.substr(start, end - start);
    start = end + 1;
    const size_t eq = entry.find('=');
    if (eq == std::string::npos || eq == 0) {
      *error = "per-slave offsets read NAME=auto|SECONDS, got '" + entry + "'";
      return out;
    }
    const std::string name = entry.substr(0, eq);
    std::string value_error;
    const std::optional<double> value = ParseTimeOffset(entry.substr(eq + 1), &value_error);
    if (!value_error.empty()) {
      *error = name + ": " + value_error;
      return out;
    }
    if (slaves.empty()) continue;
    const auto it = std::find(slaves.begin(), slaves.end(), name);
    if (it == slaves.end()) {
      *error = "'" + name + "' is not a slave camera";
      return out;
    }
    const auto i = static_cast<size_t>(it - slaves.begin());
    if (named[i]) {
      *error = "'" + name + "' is given twice";
      return out;
    }
    named[i] = true;
    out[i] = value;
  }
  return out;
}

namespace {

// The trajectories, and how their poses are read.
void AddSolveInputOptions(CLI::App* cmd, SolveArgs* args) {
  cmd->add_option("--master", args->master,
                  "Trajectory file of the master camera. It defines the rig frame\n"
                  "and the unit of every position in the result. NAME=FILE names the\n"
                  "camera NAME (default: the file name without directory and extension).")
      ->type_name("[NAME=]FILE")
      ->required();
  cmd->add_option("--slave", args->slaves,
                  "Trajectory file of a slave camera; repeat for every slave. A\n"
                  "camera's name is its file name without directory and extension,\n"
                  "or NAME with NAME=FILE (EuRoC: --master cam0=mav0/cam0/data.csv\n"
                  "--slave cam1=mav0/cam1/data.csv).")
      ->type_name("[NAME=]FILE")
      ->required();
}

// The method, motion, scale and pair models.
void AddSolveModelOptions(CLI::App* cmd, SolveArgs* args) {
  cmd->add_option("--method", args->method,
                  "lls: linear least squares only (thesis 4.3); nl: the linear\n"
                  "estimate refined by non-linear least squares, with standard\n"
                  "deviations (4.26-4.27).")
      ->check(CLI::IsMember({"lls", "nl"}))
      ->capture_default_str();
  cmd->add_option("--motion", args->motion,
                  "Motion model. general: the rig rotates about varying axes; rotation,\n"
                  "position and scale are estimated. planar: every rotation is about one\n"
                  "axis (a car on a road); rotation, scale and the position in the plane\n"
                  "are estimated, the offset along the axis comes from --prior or is\n"
                  "reported unknown. translational: it (almost) does not rotate; only\n"
                  "rotation and scale are determined. auto: translational when no\n"
                  "motion rotates beyond the thesis's equal-error boundary (10 deg at\n"
                  "1 deg of rotation noise, scaled by sqrt(noise / 1 deg) for the noise\n"
                  "measured from the master/slave rotation-angle differences), else\n"
                  "general or planar from how much the rotation axes tilt beyond the\n"
                  "noise and how well the offset along the mean axis is determined (the\n"
                  "result's `observability`).")
      ->check(CLI::IsMember({"auto", "general", "planar", "translational"}))
      ->capture_default_str();
  cmd->add_option("--scale", args->scale,
                  "Scale model. A slave's scale maps its odometry unit to the\n"
                  "master's (p_master = scale * R * p_slave + C): monocular odometry\n"
                  "has its own unit per camera and per re-initialisation.\n"
                  "fixed: one scale per slave; segments: one per segment id of the\n"
                  "slave file (9th column); partitions:N: one per N equal parts of\n"
                  "the drive (drifting scale); auto: segments when the file has\n"
                  "several, partitions when the measured scale drifts, else fixed.")
      ->check(ValueCheck(
          [](const std::string& v) {
            CalibrationOptions o;
            return ApplyScale(v, &o);
          },
          "auto|fixed|segments|partitions:N"))
      ->capture_default_str();
  cmd->add_option("--pairs", args->pairs,
                  "Which pairs of times (a, b) become motions. gls (default):\n"
                  "auto's result refined by GLS on chains of auto's span, whitened\n"
                  "by the pose noise fitted to them; when one span determines the\n"
                  "rotation best and another C, the rotation from the first's\n"
                  "chains and C and scale from the second's (docs/method.md); auto: per slave the\n"
                  "span N of (k, k + N) whose estimate has the smallest σ (spans\n"
                  "1, 2, 3, 5, 8, ... up to 1/8 of the recording are solved);\n"
                  "start: (first pose, k) for every k; relative:STEP: (k, k + STEP)\n"
                  "for every k; walk: from spread anchors to a target rotation.")
      ->check(ValueCheck(
          [](const std::string& v) {
            PairOptions p;
            return ApplyPairs(v, &p);
          },
          "auto|gls|start|walk|relative:STEP"))
      ->capture_default_str();
}

// Matching in time: the stamp tolerance, clock offsets, the config that gives them, and the
// quaternion check of the input.
void AddSolveTimingOptions(CLI::App* cmd, SolveArgs* args) {
  cmd->add_option("--tolerance-ms", args->tolerance_ms,
                  "Largest time difference in milliseconds between a master pose\n"
                  "and the slave pose matched to it (mutually nearest stamps).\n"
                  "Master poses without a match in every slave are dropped.")
      ->type_name("MS")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option(
         "--time-offset", args->time_offset,
         "Clock offset of the slaves: a slave's stamp minus the master clock at the\n"
         "same instant, seconds (the same for every slave), or auto: estimated per\n"
         "slave, first by cross-correlating the angular speeds of master and slave\n"
         "within --time-offset-window, then by minimising the rotation residuals of\n"
         "a calibration over the offset; the result gives time_offset_s and its σ\n"
         "time_offset_std_s. Slave stamps are moved to the master clock; a slave\n"
         "whose stamps then coincide with the master's (90 % within 1/50 frame) is\n"
         "matched by stamp, any other (free-running camera) interpolated at the\n"
         "master's instants (cubic, SLERP/linear at the ends; not across gaps of more than 3\n"
         "frame intervals nor across scale segments).\n"
         "Per slave: NAME=auto|SECONDS,... (slaves not named: 0).\n"
         "Given, it overrides --config's estimator.time_offset.")
      ->type_name("auto|SECONDS|NAME=auto|SECONDS,...")
      ->check(CLI::Validator(
          [](std::string& v) {
            std::string error;
            ParseTimeOffsets(v, {}, &error);
            return error;
          },
          "auto|SECONDS|NAME=auto|SECONDS,..."))
      ->capture_default_str();
  cmd->add_option("--config", args->config,
                  "Rig config YAML (as for rigcal calib): its estimator.time_offset\n"
                  "(auto, SECONDS, or per slave NAME: auto|SECONDS; absent: 0) gives the\n"
                  "slaves' clock offsets, unless --time-offset is given (the flag\n"
                  "overrides the config). Every --slave must be a camera of the rig.")
      ->type_name("FILE");
  cmd->add_option("--time-offset-window", args->time_offset_window_s,
                  "With --time-offset auto: the offset is searched within ± this many seconds")
      ->type_name("S")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->add_option("--max-quaternion-norm-error", args->max_quaternion_norm_error,
                  "Quaternions whose norm differs from 1 by at most this, or by\n"
                  "at most the rounding of their printed digits, are normalised\n"
                  "(with a warning); larger deviations are an error. EuRoC's\n"
                  "ground truth is off by up to 1.5e-4.")
      ->type_name("X")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
}

// A truth to compare with, and nominal mountings.
void AddSolveTruthOptions(CLI::App* cmd, SolveArgs* args) {
  auto* truth =
      cmd->add_option("--truth", args->truth,
                      "Rig YAML with the true parameters of every slave (see below):\n"
                      "prints the errors of thesis 5.1.1 (rotation: geodesic angle) and adds\n"
                      "\"errors\" to the JSON. Its unit may differ from the master odometry's\n"
                      "(metres against monocular VO): see --truth-unit.");
  truth->type_name("FILE");
  cmd->add_option("--truth-unit", args->truth_unit,
                  "Unit of the --truth file's C. metric: metres, while the master odometry\n"
                  "has its own unit: that unit is fitted (least squares of the truth's C on\n"
                  "the estimated C over the usable slaves, the in-plane part for planar\n"
                  "ones; with 3 or more, one slave that disagrees with the others is left\n"
                  "out) and the truth's C and scales (then slave unit -> metres) are divided\n"
                  "by it before comparing; the output says so and gives the unit. With one\n"
                  "slave the fit absorbs its distance error. master: the truth is in the\n"
                  "master's unit, compared as given. auto: master when the fitted unit is 1\n"
                  "within 3 sigma (or 2 %), else metric.")
      ->check(CLI::IsMember({"auto", "metric", "master"}))
      ->needs(truth)
      ->capture_default_str();
  auto* prior =
      cmd->add_option("--prior", args->prior,
                      "Nominal mountings (e.g. from CAD): a rig YAML as for --truth, or a rig\n"
                      "config whose cameras[].nominal are used. Fills in what the motion\n"
                      "cannot determine (C along the rotation axis of planar motion); the\n"
                      "result says so (`unobservable_from_prior`).");
  prior->type_name("FILE");
  cmd->add_option("--prior-sigma", args->prior_sigma,
                  "Standard deviation of the nominal C along the mean rotation axis,\n"
                  "master units.\n"
                  "> 0: combined with what the data determine as a weighted term (also\n"
                  "for nearly planar drives, where the offset is determined poorly);\n"
                  "0: the nominal is used only where the motion determines nothing.")
      ->type_name("S")
      ->check(CLI::NonNegativeNumber)
      ->needs(prior)
      ->capture_default_str();
}

// σ's time blocks and the files written.
void AddSolveOutputOptions(CLI::App* cmd, SolveArgs* args) {
  cmd->add_option("--time-blocks", args->time_blocks,
                  "Standard deviations: the motions' errors are taken as shared within this\n"
                  "many contiguous time blocks and independent between them (cluster-robust\n"
                  "covariance): odometry drift, overlapping pairs and correlated pose errors\n"
                  "make motions close in time err alike. 0: every motion independent\n"
                  "(optimistic on real odometry). Needs 4 motions per block.")
      ->type_name("N")
      ->check(CLI::Range(0, 10000))
      ->capture_default_str();
  cmd->add_option("-o,--out", args->out,
                  "Write the result YAML here (atomically): the rig entries plus\n"
                  "standard deviations, motion counts, models and termination.")
      ->type_name("FILE");
  cmd->add_option("--camchain", args->camchain,
                  "Write a Kalibr camchain YAML here: cam0 = master, cam1.. = the usable\n"
                  "slaves in --slave order, each with T_cn_cnm1 and, with --config, its\n"
                  "camera_model, intrinsics, distortion and resolution. Translations in\n"
                  "metres when the unit is known (--master-metric, --metric-*, a target\n"
                  "reference), else in master units (rigcal_translation_unit says which).")
      ->type_name("FILE");
}

// Other paths through the data (online, pattern references, metric scale) and JSON output.
void AddSolveModeOptions(CLI::App* cmd, SolveArgs* args) {
  // Options that would have no effect together are usage errors naming both.
  auto* online =
      cmd->add_flag("--online", args->online,
                    "Feed the trajectories through the online path instead (sync buffer and "
                    "recursive estimator, as `rigcal calib` does live) and print how the "
                    "estimate converges over time (errors too with --truth). --method/--pairs/"
                    "--scale do not apply (the online estimator picks keyframe pairs and segment "
                    "scales): giving one of them is a usage error.")
          ->excludes("--method")
          ->excludes("--pairs")
          ->excludes("--scale");
  cmd->add_option("--report-every", args->report_every_s,
                  "With --online: seconds of stream time between convergence lines")
      ->default_val(10.0)
      ->check(CLI::PositiveNumber)
      ->needs(online);
  cmd->add_option("--reference", args->reference,
                  "motion: calibrate from the cameras' motions (hand-eye with scale). target:\n"
                  "the trajectories are target poses (each camera's pose in one shared target\n"
                  "frame at the same instants, e.g. `rigcal intrinsics --poses-out`); the\n"
                  "slave's pose in the master frame is the mean of the per-instant relative\n"
                  "poses (global reference pose model, thesis 4.2), with σ of the mean.")
      ->check(CLI::IsMember({"motion", "target"}))
      ->excludes(online)
      ->capture_default_str();
  cmd->add_option("--pose-model", args->pose_model,
                  "With --reference target. global: one target shared by the cameras (above).\n"
                  "individual: each camera sees its own fixed target (two-pattern setup), the\n"
                  "poses are each camera's pose in its own target's frame; the slave's pose and\n"
                  "the targets' relative pose are fitted to T_0^k dT = W T_i^k over the instants\n"
                  "(individual reference pose model, thesis 4.2), with σ. The rig must rotate\n"
                  "about two different axes.")
      ->check(CLI::IsMember({"global", "individual"}))
      ->capture_default_str();
  auto* metric_target =
      cmd->add_option("--metric-target", args->metric_target,
                      "The master camera's target poses (TUM, camera centre in the frame of a\n"
                      "target of known size, metres; `rigcal intrinsics --poses-out`) in some\n"
                      "master frames: lambda_world, metres per master unit, is fitted to the\n"
                      "master odometry at those frames (thesis 5.5) and every position and\n"
                      "scale of the result is converted to metres; the output says so.");
  metric_target->type_name("FILE");
  cmd->add_flag("--master-metric", args->master_metric,
                "The master odometry is metric (wheel odometry, INS): its scale is 1, every\n"
                "position is in metres and the output says so. Planar driving leaves the\n"
                "mounting height (C along the rotation axis) unobservable: it is reported,\n"
                "and taken from --prior (nominal mounting) when given.")
      ->excludes(metric_target);
  cmd->add_flag("--json", args->json,
                "Print only the result, as one JSON object, on stdout (logs stay\n"
                "on stderr).");
}

// The formats of the files, and the exit status.
void AddSolveFooter(CLI::App* cmd) {
  cmd->footer(
      "Trajectory files: one pose per line, '#' comments; the format is detected:\n"
      "  TUM:         t tx ty tz qx qy qz qw [segment]   t in seconds\n"
      "  EuRoC CSV:   t_ns,p_x,p_y,p_z,q_w,q_x,q_y,q_z[,...]   further columns ignored\n"
      "  rigcal:      t_ns qw qx qy qz Cx Cy Cz [segment]   with a '# rigcal poses' header,\n"
      "               or integer stamps >= 1e12 ns\n"
      "Each pose is the camera centre in that camera's own odometry frame and unit, and the\n"
      "rotation world_from_camera. segment: integer scale segment id (a VO re-initialisation\n"
      "starts a new one).\n"
      "Rig YAML (--truth, --prior, and the rig part of --out), per slave name:\n"
      "  cam1: {q_wxyz: [w, x, y, z], C: [x, y, z], scale: s}\n"
      "  the slave's orientation and centre in the master frame (master units), and the\n"
      "  scale: the factor from slave odometry units to master units. A metric truth\n"
      "  (--truth-unit) has C in metres and scales from slave units to metres.\n"
      "Exit status: 0 every slave calibrated; 1 bad input or output error (message\n"
      "'rigcal solve: <file>:<line>: <what>' on stderr); 3 the solve ran but at least one\n"
      "slave has no usable estimate (too little motion, degenerate motion); the result is\n"
      "still printed and written.");
}

}  // namespace

void AddSolveOptions(CLI::App* cmd, SolveArgs* args) {
  AddSolveInputOptions(cmd, args);
  AddSolveModelOptions(cmd, args);
  AddSolveTimingOptions(cmd, args);
  AddSolveTruthOptions(cmd, args);
  AddSolveOutputOptions(cmd, args);
  AddSolveModeOptions(cmd, args);
  AddSolveFooter(cmd);
}

}  // namespace rigcal::cli
