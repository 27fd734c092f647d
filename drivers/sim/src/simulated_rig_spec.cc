// SimulatedRigSpec: scene types, waypoint orientations, defaults in use and the spec's check.
#include "rigcal/sim/simulated_rig_spec.h"

#include <cmath>
#include <set>
#include <sstream>

namespace rigcal::sim {
namespace {

bool IsUnit(const Eigen::Quaterniond& q) {
  return q.coeffs().allFinite() && std::abs(q.norm() - 1.0) <= 1e-6;
}

}  // namespace

std::string ToString(SimulatedRigSpec::SceneType type) {
  switch (type) {
    case SimulatedRigSpec::SceneType::kRoom:
      return "room";
    case SimulatedRigSpec::SceneType::kYard:
      return "yard";
    case SimulatedRigSpec::SceneType::kStreet:
      return "street";
    case SimulatedRigSpec::SceneType::kPipe:
      return "pipe";
  }
  return "?";
}

std::optional<SimulatedRigSpec::SceneType> SceneTypeFromString(const std::string& name) {
  for (auto type : {SimulatedRigSpec::SceneType::kRoom, SimulatedRigSpec::SceneType::kYard,
                    SimulatedRigSpec::SceneType::kStreet, SimulatedRigSpec::SceneType::kPipe}) {
    if (ToString(type) == name) return type;
  }
  return std::nullopt;
}

Eigen::Quaterniond WaypointOrientationFromYpr(double yaw_deg, double pitch_deg, double roll_deg) {
  constexpr double kDeg = M_PI / 180.0;
  // Level camera looking along +x: camera z -> world x, camera x -> world -y, camera y ->
  // world -z.
  Eigen::Matrix3d level;
  level << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(yaw_deg * kDeg, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(pitch_deg * kDeg, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(roll_deg * kDeg, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix() *
                            level;
  return Eigen::Quaterniond(r).normalized();
}

Eigen::Vector3d SimulatedRigSpec::SceneSize() const {
  if (scene.size.x() > 0 && scene.size.y() > 0 && scene.size.z() > 0) return scene.size;
  switch (scene.type) {
    case SceneType::kYard:
      return {60, 60, 8};
    case SceneType::kStreet:
      return {200, 16, 10};
    case SceneType::kRoom:
    case SceneType::kPipe:
      break;
  }
  return {20, 16, 6};
}

double SimulatedRigSpec::TexelSize() const {
  if (scene.texel_m > 0) return scene.texel_m;
  switch (scene.type) {
    case SceneType::kPipe:
      return 0.002;
    case SceneType::kYard:
    case SceneType::kStreet:
      return 0.02;
    case SceneType::kRoom:
      break;
  }
  return 0.01;
}

Status SimulatedRigSpec::Check() const {
  std::ostringstream e;
  auto fail = [&]() -> Status { return Error{e.str()}; };
  // Cameras.
  if (names.empty()) {
    e << "names: no cameras";
    return fail();
  }
  if (cameras.size() != names.size() || master_from_camera.size() != names.size()) {
    e << "cameras: " << names.size() << " names, " << cameras.size() << " camera models and "
      << master_from_camera.size() << " mountings; need one of each per camera";
    return fail();
  }
  std::set<std::string> unique;
  for (size_t i = 0; i < names.size(); ++i) {
    if (names[i].empty() || !unique.insert(names[i]).second) {
      e << "names[" << i << "]: empty or duplicate camera name '" << names[i] << "'";
      return fail();
    }
    if (!cameras[i]) {
      e << names[i] << ": no camera model";
      return fail();
    }
    if (cameras[i]->width() < 8 || cameras[i]->height() < 8 || cameras[i]->width() > 8192 ||
        cameras[i]->height() > 8192) {
      e << names[i] << ": resolution " << cameras[i]->width() << " x " << cameras[i]->height()
        << " outside [8, 8192]";
      return fail();
    }
    const Pose& m = master_from_camera[i];
    if (!IsUnit(m.q) || !m.C.allFinite()) {
      e << names[i] << ".truth: mounting must have a unit quaternion and a finite centre";
      return fail();
    }
  }
  if (Eigen::AngleAxisd(master_from_camera[0].q).angle() > 1e-9 ||
      master_from_camera[0].C.norm() > 1e-12) {
    e << names[0] << ".truth: the master defines the rig frame; its mounting must be the identity";
    return fail();
  }
  // Timing.
  if (!(frame_rate_hz > 0 && frame_rate_hz <= 1000)) {
    e << "frame_rate_hz: " << frame_rate_hz << " outside (0, 1000]";
    return fail();
  }
  if (num_frames < 0 || !(duration_s >= 0)) {
    e << "num_frames/duration_s: must not be negative";
    return fail();
  }
  if (num_frames > 0 && duration_s > 0) {
    e << "num_frames, duration_s: give at most one of them";
    return fail();
  }
  // Trajectory.
  const bool has_file = !trajectory_t_ns.empty() || !trajectory_poses.empty();
  if (waypoints.empty() == !has_file) {
    e << "trajectory: give either waypoints or a trajectory file";
    return fail();
  }
  if (!waypoints.empty()) {
    if (waypoints.size() < 2) {
      e << "trajectory.waypoints: need at least 2 waypoints, got " << waypoints.size();
      return fail();
    }
    if (!(waypoint_interval_s > 0 && std::isfinite(waypoint_interval_s))) {
      e << "trajectory.waypoint_interval_s: must be > 0";
      return fail();
    }
    for (size_t i = 0; i < waypoints.size(); ++i) {
      if (!waypoints[i].position.allFinite() || !IsUnit(waypoints[i].world_from_master)) {
        e << "trajectory.waypoints[" << i << "]: position must be finite, orientation unit";
        return fail();
      }
    }
  } else {
    if (trajectory_t_ns.size() != trajectory_poses.size() || trajectory_t_ns.size() < 2) {
      e << "trajectory.file: need at least 2 poses with one stamp each, got "
        << trajectory_poses.size() << " poses and " << trajectory_t_ns.size() << " stamps";
      return fail();
    }
    for (size_t i = 1; i < trajectory_t_ns.size(); ++i) {
      if (trajectory_t_ns[i] <= trajectory_t_ns[i - 1]) {
        e << "trajectory.file: stamps must increase strictly (pose " << i << ")";
        return fail();
      }
    }
    if (!IsUnit(body_from_master.q) || !body_from_master.C.allFinite()) {
      e << "trajectory.body_from_master: needs a unit quaternion and a finite centre";
      return fail();
    }
  }
  const int64_t frames = FrameCount();
  const double duration = TrajectoryDuration();
  const double last = static_cast<double>(frames - 1) / frame_rate_hz;
  if (frames < 1) {
    e << "num_frames: no frames";
    return fail();
  }
  if (last > duration + 1e-6) {
    e << (num_frames > 0 ? "num_frames" : "duration_s") << ": " << frames << " frames at "
      << frame_rate_hz << " Hz last " << last << " s, longer than the trajectory (" << duration
      << " s)";
    return fail();
  }
  // Scene.
  if (scene.type != SceneType::kPipe) {
    const Eigen::Vector3d size = SceneSize();
    if (!(size.minCoeff() > 0) || !size.allFinite() || size.maxCoeff() > 100000) {
      e << "scene.size: every extent must be in (0, 100000] m";
      return fail();
    }
  }
  if (scene.boxes < 0 || scene.boxes > 64) {
    e << "scene.boxes: " << scene.boxes << " outside [0, 64]";
    return fail();
  }
  if (!(scene.pipe_diameter > 0 && scene.pipe_diameter <= 1000)) {
    e << "scene.diameter: must be in (0, 1000] m";
    return fail();
  }
  if (!(scene.pipe_length > 0 && scene.pipe_length <= 100000)) {
    e << "scene.length: must be in (0, 100000] m";
    return fail();
  }
  if (!(scene.texel_m >= 0 && scene.texel_m <= 10)) {
    e << "scene.texel_m: must be in (0, 10] m";
    return fail();
  }
  // Imaging and device behaviour.
  const double period = 1.0 / frame_rate_hz;
  if (!(noise_sigma >= 0 && noise_sigma <= 100)) {
    e << "noise_sigma: " << noise_sigma << " outside [0, 100]";
    return fail();
  }
  if (!(blur_exposure_s >= 0 && blur_exposure_s < period)) {
    e << "motion_blur.exposure_ms: " << blur_exposure_s * 1e3
      << " must be >= 0 and shorter than the frame period (" << period * 1e3 << " ms)";
    return fail();
  }
  if (blur_exposure_s > 0 && (blur_samples < 2 || blur_samples > 32)) {
    e << "motion_blur.samples: " << blur_samples << " outside [2, 32]";
    return fail();
  }
  if (!(drop_probability >= 0 && drop_probability < 1)) {
    e << "drop_probability: " << drop_probability << " outside [0, 1)";
    return fail();
  }
  if (!(timestamp_jitter_s >= 0 && 3 * timestamp_jitter_s < 0.5 * period)) {
    e << "timestamp_jitter_ms: " << timestamp_jitter_s * 1e3
      << " must be >= 0 with 3 sigma below half a frame period (" << period * 0.5e3 << " ms)";
    return fail();
  }
  for (const auto& [name, t] : fail_after_s) {
    if (unique.count(name) == 0) {
      e << "fail_after_s." << name << ": no camera of that name";
      return fail();
    }
    if (!(t >= 0 && std::isfinite(t))) {
      e << "fail_after_s." << name << ": must be >= 0 s";
      return fail();
    }
  }
  if (trigger.enabled) {
    if (names.size() > 8)
      e << "trigger: at most 8 cameras (trigger lines), not " << names.size();
    else if (frame_rate_hz > 400)
      e << "trigger: frame_rate_hz above the generator's 400 Hz";
    else if (!(std::abs(trigger.drift_ppm) <= 1000))
      e << "trigger.drift_ppm: outside [-1000, 1000]";
    else if (!(trigger.link_jitter_ms >= 0 && trigger.link_jitter_ms <= 20)) {
      e << "trigger.link_jitter_ms: outside [0, 20]";
    } else if (!(trigger.exposure_ms >= 0 && trigger.exposure_ms * 1e-3 * frame_rate_hz < 1)) {
      e << "trigger.exposure_ms: must be in [0, frame period)";
    } else if (!(trigger.corrupt_probability >= 0 && trigger.corrupt_probability <= 0.01)) {
      e << "trigger.corrupt_probability: outside [0, 0.01]";
    }
    if (!e.str().empty()) return fail();
  }
  if (render_block < 1 || render_block > 32) {
    e << "render_block: " << render_block << " outside [1, 32]";
    return fail();
  }
  return Status::Ok();
}

double SimulatedRigSpec::TrajectoryDuration() const {
  if (!waypoints.empty()) {
    return static_cast<double>(waypoints.size() - 1) * waypoint_interval_s;
  }
  if (trajectory_t_ns.size() >= 2) {
    return static_cast<double>(trajectory_t_ns.back() - trajectory_t_ns.front()) * 1e-9;
  }
  return 0.0;
}

int64_t SimulatedRigSpec::FrameCount() const {
  if (num_frames > 0) return num_frames;
  if (duration_s > 0) return std::llround(duration_s * frame_rate_hz);
  return static_cast<int64_t>(std::floor(TrajectoryDuration() * frame_rate_hz + 1e-6)) + 1;
}

}  // namespace rigcal::sim
