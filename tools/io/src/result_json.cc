// SPDX-License-Identifier: Apache-2.0
#include "rigcal/io/result_json.h"

#include <spdlog/fmt/fmt.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "rigcal/base/format.h"
#include "rigcal/base/quaternion.h"
#include "rigcal/calib/error_model.h"
#include "rigcal/io/truth_comparison.h"

namespace rigcal::io {
namespace {

// A number, or null when it is not finite (JSON has no NaN or infinity).
nlohmann::json JsonNumber(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
}

nlohmann::json Vec(const Eigen::Vector3d& v) {
  return nlohmann::json::array({JsonNumber(v.x()), JsonNumber(v.y()), JsonNumber(v.z())});
}

const Similarity* TruthOf(const std::map<std::string, Similarity>* truth, const std::string& name) {
  if (truth == nullptr) return nullptr;
  const auto it = truth->find(name);
  return it == truth->end() ? nullptr : &it->second;
}

// One table row: label, estimate and (when given) the truth in a column of its own.
std::string Row(const std::string& label, const std::string& estimate,
                const std::string& truth = "") {
  std::string row = truth.empty() ? fmt::format("  {:<22}{}", label, estimate)
                                  : fmt::format("  {:<22}{:<48}{}", label, estimate, truth);
  row.erase(row.find_last_not_of(' ') + 1);
  return row + "\n";
}

std::string Quat(const Eigen::Quaterniond& q) {
  return fmt::format("{:9.6f} {:9.6f} {:9.6f} {:9.6f}", q.w(), q.x(), q.y(), q.z());
}

std::string Vec3(const Eigen::Vector3d& v, int decimals = 4) {
  return fmt::format("{:10.{}f} {:10.{}f} {:10.{}f}", v.x(), decimals, v.y(), decimals, v.z(),
                     decimals);
}

// σ per axis, "unknown" when not computed.
std::string Sigma3(const Eigen::Vector3d& v) {
  if (!v.allFinite()) return "unknown";
  return Vec3(v);
}

std::string AxisAngleText(const Eigen::Quaterniond& q) {
  const AxisAngleDegrees a = AxisAngleDeg(q);
  return fmt::format("{:9.6f} {:9.6f} {:9.6f} {:9.4f}", a.axis.x(), a.axis.y(), a.axis.z(),
                     a.angle_deg);
}

// Within 1 degree of pitch ±90 roll and yaw are ill-defined (gimbal lock).
bool NearGimbalLock(const Eigen::Quaterniond& q) { return std::abs(RollPitchYawDeg(q).y()) > 89.0; }

nlohmann::json AxisAngleJson(const Eigen::Quaterniond& q) {
  const AxisAngleDegrees a = AxisAngleDeg(q);
  return {{"axis", Vec(a.axis)}, {"angle_deg", JsonNumber(a.angle_deg)}};
}

// The errors of `s` against `truth` (in master units), scored as every truth comparison does
// (truth_comparison.h: the newest segment's scale, C in the plane when its axis is unknown).
CalibrationError ScoreAgainst(const SlaveCalibration& s, const Similarity& truth) {
  SlaveScore score;
  score.truth_master_units = truth;
  ScoreSlave(s, &score);
  return score.error;
}

// Rotation and position, beside the truth when known.
std::string SlaveMountingRows(const SlaveCalibration& s, const Similarity* truth,
                              const TruthAlignment* alignment) {
  std::string out;
  out += Row("", "estimate", truth ? "truth" : "");
  out += Row("q (w, x, y, z)", Quat(s.estimate.q), truth ? Quat(truth->q) : "");
  out += Row("roll pitch yaw [deg]", Vec3(RollPitchYawDeg(s.estimate.q), 3),
             truth ? Vec3(RollPitchYawDeg(truth->q), 3) : "");
  out +=
      Row("axis, angle [deg]", AxisAngleText(s.estimate.q), truth ? AxisAngleText(truth->q) : "");
  if (NearGimbalLock(s.estimate.q) || (truth != nullptr && NearGimbalLock(truth->q))) {
    out += Row("", "pitch near ±90 deg: roll and yaw are not unique there (gimbal lock);");
    out += Row("", "compare q or the axis and angle");
  }
  out += Row("C [master units]",
             s.position_observable ? Vec3(s.estimate.C) : "not observable with this motion",
             truth ? Vec3(truth->C) : "");
  if (alignment != nullptr && alignment->applied && s.position_observable) {
    // The same in metres, beside it rather than only in the alignment line.
    const double k = alignment->metres_per_unit;
    out += Row("C [m], aligned unit", Vec3(s.estimate.C * k), truth ? Vec3(truth->C * k) : "");
  }
  return out;
}

// The scale of every odometry segment.
std::string SlaveScaleRows(const SlaveCalibration& s, const Similarity* truth) {
  std::string out;
  if (s.scales.size() > 1) {
    for (const SegmentScale& seg : s.scales) {
      out += Row(fmt::format("scale segment {}", seg.segment),
                 fmt::format("{:.6g} (std {})", seg.scale, SigmaText(seg.std, 2)));
    }
  } else {
    const double std =
        s.scales.empty() ? std::numeric_limits<double>::quiet_NaN() : s.scales.front().std;
    out +=
        Row("scale", fmt::format("{:.6g} (std {})", s.estimate.scale, SigmaText(std, 2)),
            truth ? (std::isfinite(truth->scale) ? fmt::format("{:.6g}", truth->scale) : "unknown")
                  : "");
  }
  return out;
}

// The mean rotation axis, the σ and the observability.
std::string SlaveObservabilityRows(const SlaveCalibration& s) {
  std::string out;
  const bool rotating = s.observability.planar_axis.norm() > 0.0;
  if (rotating && s.position_observable) {
    std::string along;
    if (!s.unobservable.empty()) {
      along = s.unobservable_from_prior ? "unobservable: the nominal mounting's value"
                                        : "unobservable: unknown (0 shown; give a nominal)";
    } else {
      along = "estimated, std " + SigmaText(s.axis_offset_std, 3);
    }
    out += Row("C along mean axis", Vec3(s.observability.planar_axis, 3) + "  " + along);
  }
  out += Row("std rotation [deg]", SigmaText(s.rot_std_deg, 3));
  out += Row("std C", Sigma3(s.pos_std));
  if (rotating && std::isfinite(s.axis_offset_std)) {
    out += Row("std C along axis", fmt::format("{:.3g}", s.axis_offset_std));
  }
  if (rotating) {
    const Observability& o = s.observability;
    out +=
        Row("observability",
            fmt::format("axis spread {:.3g} deg (slave {:.3g}), tilt SNR {:.3g}, axis/plane "
                        "std {:.3g}",
                        o.axis_spread_deg, o.slave_axis_spread_deg, o.tilt_snr, o.axis_std_ratio));
  }
  return out;
}

// Motions, glitches, time offset, models and unobservable directions.
std::string SlaveCountRows(const SlaveCalibration& s) {
  std::string out;
  const MotionCounts& m = s.motions;
  out += Row("motions",
             fmt::format("used {} of {}, rejected {} (small rotation {}, angle mismatch {}, "
                         "residual outlier {})",
                         m.used, m.total, m.rejected(), m.small_rotation, m.angle_mismatch,
                         m.residual_outlier));
  const GlitchCounts& g = s.glitches;
  if (g.dropped() > 0) {
    out += Row("glitches",
               fmt::format("{} poses dropped (position jump {}, rotation jump {}, angle mismatch "
                           "{}; in the master {}, in this camera {})",
                           g.dropped(), g.position_jump, g.rotation_jump, g.angle_mismatch,
                           g.in_master, g.in_slave));
  }
  if (std::isfinite(s.time_offset_s)) {
    out += Row("time offset [s]",
               fmt::format("{:.6g} (std {})", s.time_offset_s, SigmaText(s.time_offset_std_s, 2)));
  }
  out += Row("models",
             fmt::format("motion {}, scale {}", ToString(s.motion_model), ToString(s.scale_model)));
  for (const Eigen::Vector3d& d : s.unobservable) {
    out += Row("unobservable along", Vec3(d));
  }
  return out;
}

// The errors against the truth (in master units, and metres when the unit is aligned).
std::string SlaveErrorRows(const SlaveCalibration& s, const Similarity& truth,
                           const TruthAlignment* alignment) {
  std::string out;
  const CalibrationError e = ScoreAgainst(s, truth);
  out += Row("errors vs truth",
             fmt::format("rotation {:.3g} deg, C direction {:.3g} deg, C distance {:.3g} %,",
                         e.rot_deg, e.dir_deg, e.dist_pct));
  const bool metric = alignment != nullptr && alignment->applied;
  out += Row(
      "", fmt::format(
              "C error {:.3g} master units{}, scale {}", e.trans_err,
              metric ? fmt::format(" ({:.3g} m)", e.trans_err * alignment->metres_per_unit) : "",
              std::isfinite(e.scale_pct) ? fmt::format("{:.3g} %", e.scale_pct)
                                         : "not compared (the slave's odometry unit is unknown)"));
  if (std::isfinite(e.plane_err)) {
    out += Row("", fmt::format("C error in the plane {:.3g}, along the mean axis {:.3g}",
                               e.plane_err, e.axis_err));
  }
  return out;
}

std::string FormatSlave(const SlaveCalibration& s, const Similarity* truth,
                        const TruthAlignment* alignment) {
  std::string out = fmt::format("{}: {} ({}){}\n", s.name, ToString(s.state),
                                ToString(s.termination), s.usable() ? "" : " (NOT USABLE)");
  if (!s.message.empty()) out += fmt::format("  {}\n", s.message);
  out += SlaveMountingRows(s, truth, alignment);
  out += SlaveScaleRows(s, truth);
  out += SlaveObservabilityRows(s);
  out += SlaveCountRows(s);
  if (truth != nullptr && s.usable()) out += SlaveErrorRows(s, *truth, alignment);
  return out;
}

}  // namespace

Eigen::Vector3d RollPitchYawDeg(const Eigen::Quaterniond& q) {
  const Eigen::Matrix3d r = q.normalized().toRotationMatrix();
  const double pitch = std::asin(std::clamp(-r(2, 0), -1.0, 1.0));
  if (std::hypot(r(2, 1), r(2, 2)) < 1e-12) {
    // Gimbal lock: R = Rz(yaw) Ry(±90) with roll 0 gives r01 = -sin(yaw), r11 = cos(yaw).
    return Eigen::Vector3d(0.0, pitch, std::atan2(-r(0, 1), r(1, 1))) * kDegPerRad;
  }
  const double roll = std::atan2(r(2, 1), r(2, 2));
  const double yaw = std::atan2(r(1, 0), r(0, 0));
  return Eigen::Vector3d(roll, pitch, yaw) * kDegPerRad;
}

AxisAngleDegrees AxisAngleDeg(const Eigen::Quaterniond& q) {
  const Eigen::Quaterniond c = Canonical(q.normalized());
  AxisAngleDegrees a;
  a.angle_deg = RotationAngle(c) * kDegPerRad;
  a.axis = RotationAxis(c);
  return a;
}

nlohmann::json ResultToJson(const RigCalibration& result,
                            const std::map<std::string, Similarity>* truth,
                            const TruthAlignment* alignment) {
  nlohmann::json slaves = nlohmann::json::array();
  for (const SlaveCalibration& s : result.slaves) {
    nlohmann::json j;
    j["name"] = s.name;
    const Eigen::Quaterniond& q = s.estimate.q;
    j["q_wxyz"] = {JsonNumber(q.w()), JsonNumber(q.x()), JsonNumber(q.y()), JsonNumber(q.z())};
    j["roll_pitch_yaw_deg"] = Vec(RollPitchYawDeg(q));
    j["axis_angle"] = AxisAngleJson(q);
    j["C"] = Vec(s.estimate.C);
    if (s.scales.size() > 1) {
      nlohmann::json scales = nlohmann::json::array();
      for (const SegmentScale& seg : s.scales) {
        scales.push_back({{"segment", seg.segment},
                          {"scale", JsonNumber(seg.scale)},
                          {"std", JsonNumber(seg.std)}});
      }
      j["scales"] = scales;
    } else {
      j["scale"] = JsonNumber(s.estimate.scale);
    }
    // σ: null when unknown (the covariance was not computed or failed), never 0; the scale's
    // here when there is one (else in "scales").
    j["std"] = {{"rot_deg", JsonNumber(s.rot_std_deg)},
                {"pos", Vec(s.pos_std)},
                {"axis", JsonNumber(s.axis_offset_std)}};
    if (s.scales.size() <= 1) {
      j["std"]["scale"] = JsonNumber(s.scales.empty() ? std::numeric_limits<double>::quiet_NaN()
                                                      : s.scales.front().std);
    }
    if (std::isfinite(s.time_offset_s)) {
      j["time_offset_s"] = JsonNumber(s.time_offset_s);
      j["time_offset_std_s"] = JsonNumber(s.time_offset_std_s);
    }
    j["motions_used"] = s.motions.used;
    j["motions_rejected"] = s.motions.rejected();
    j["glitches"] = {
        {"dropped", s.glitches.dropped()},           {"position_jump", s.glitches.position_jump},
        {"rotation_jump", s.glitches.rotation_jump}, {"angle_mismatch", s.glitches.angle_mismatch},
        {"in_master", s.glitches.in_master},         {"in_slave", s.glitches.in_slave}};
    j["models"] = {{"motion", ToString(s.motion_model)}, {"scale", ToString(s.scale_model)}};
    j["state"] = std::string(ToString(s.state));
    j["termination"] = ToString(s.termination);
    j["message"] = s.message;
    nlohmann::json unobservable = nlohmann::json::array();
    for (const Eigen::Vector3d& d : s.unobservable) unobservable.push_back(Vec(d));
    j["unobservable"] = unobservable;
    j["unobservable_from_prior"] = s.unobservable_from_prior;
    const Observability& o = s.observability;
    const Eigen::Vector4d& ev = o.rotation_eigenvalues;
    j["observability"] = {
        {"rotation_eigenvalues",
         {JsonNumber(ev[0]), JsonNumber(ev[1]), JsonNumber(ev[2]), JsonNumber(ev[3])}},
        {"rotation_weak_std_deg", JsonNumber(o.rotation_weak_std_deg)},
        {"position_min_eigenvalue", JsonNumber(o.position_min_eigenvalue)},
        {"axis_spread_deg", JsonNumber(o.axis_spread_deg)},
        {"slave_axis_spread_deg", JsonNumber(o.slave_axis_spread_deg)},
        {"tilt_snr", JsonNumber(o.tilt_snr)},
        {"axis_std_ratio", JsonNumber(o.axis_std_ratio)},
        {"max_rotation_deg", JsonNumber(o.max_rotation_deg)},
        {"planar", o.planar},
        {"mean_axis", Vec(o.planar_axis)}};
    if (const Similarity* t = TruthOf(truth, s.name); t != nullptr && s.usable()) {
      const CalibrationError e = ScoreAgainst(s, *t);
      j["errors"] = {{"rot_deg", JsonNumber(e.rot_deg)},     {"dir_deg", JsonNumber(e.dir_deg)},
                     {"dist_pct", JsonNumber(e.dist_pct)},   {"trans_err", JsonNumber(e.trans_err)},
                     {"scale_pct", JsonNumber(e.scale_pct)}, {"plane_err", JsonNumber(e.plane_err)},
                     {"axis_err", JsonNumber(e.axis_err)}};
      if (alignment != nullptr && alignment->applied) {
        j["errors"]["trans_err_m"] = JsonNumber(e.trans_err * alignment->metres_per_unit);
      }
    }
    slaves.push_back(std::move(j));
  }
  nlohmann::json out = {{"master", result.master}, {"slaves", slaves}};
  if (alignment != nullptr) {
    const TruthAlignment& a = *alignment;
    out["truth_alignment"] = {
        {"mode", ToString(a.mode)},
        {"applied", a.applied},
        {"metres_per_master_unit", JsonNumber(a.metres_per_unit)},
        {"std", JsonNumber(a.std)},
        {"fit_rms_m", JsonNumber(a.fit_rms_m)},
        {"slaves_used", a.slaves_used},
        {"slave_excluded",
         a.slave_excluded.empty() ? nlohmann::json() : nlohmann::json(a.slave_excluded)},
        {"message", a.message}};
  }
  return out;
}

std::string FormatResultTable(const RigCalibration& result,
                              const std::map<std::string, Similarity>* truth,
                              const TruthAlignment* alignment) {
  // pairs_selected is the batch solve's; an online estimate has none (it pairs keyframes).
  std::string out = fmt::format(
      "master: {}  ({}C in master units, scale = slave unit -> master unit)\n", result.master,
      result.pairs_selected > 0 ? fmt::format("pairs of times used: {}; ", result.pairs_selected)
                                : std::string());
  if (alignment != nullptr && truth != nullptr) {
    out += "truth: " + alignment->message + "\n";
    if (alignment->applied) out += "truth columns: in master units (divided by the fitted unit)\n";
  }
  for (const SlaveCalibration& s : result.slaves) {
    out += '\n';
    out += FormatSlave(s, TruthOf(truth, s.name), alignment);
  }
  return out;
}

}  // namespace rigcal::io
