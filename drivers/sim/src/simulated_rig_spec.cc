// SPDX-License-Identifier: Apache-2.0
// SimulatedRigSpec: scene types, waypoint orientations, defaults in use and the spec's check.
#include "rigcal/sim/simulated_rig_spec.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

namespace rigcal::sim {
namespace {

bool IsUnit(const Eigen::Quaterniond& q) {
  return q.coeffs().allFinite() && std::abs(q.norm() - 1.0) <= 1e-6;
}

// The steps of SimulatedRigSpec::Check, in its order; each the first violated constraint of
// its part as "<field>: <constraint>".

// Names, models, resolutions and mountings; the master's mounting is the identity.
Status CheckCameras(const SimulatedRigSpec& spec) {
  const std::vector<std::string>& names = spec.names;
  std::ostringstream e;
  if (names.empty()) {
    e << "names: no cameras";
    return Error{e.str()};
  }
  if (spec.cameras.size() != names.size() || spec.master_from_camera.size() != names.size()) {
    e << "cameras: " << names.size() << " names, " << spec.cameras.size() << " camera models and "
      << spec.master_from_camera.size() << " mountings; need one of each per camera";
    return Error{e.str()};
  }
  std::set<std::string> unique;
  for (size_t i = 0; i < names.size(); ++i) {
    const std::shared_ptr<const camera::CameraModel>& model = spec.cameras[i];
    if (names[i].empty() || !unique.insert(names[i]).second) {
      e << "names[" << i << "]: empty or duplicate camera name '" << names[i] << "'";
      return Error{e.str()};
    }
    if (!model) {
      e << names[i] << ": no camera model";
      return Error{e.str()};
    }
    if (model->width() < 8 || model->height() < 8 || model->width() > 8192 ||
        model->height() > 8192) {
      e << names[i] << ": resolution " << model->width() << " x " << model->height()
        << " outside [8, 8192]";
      return Error{e.str()};
    }
    const Pose& m = spec.master_from_camera[i];
    if (!IsUnit(m.q) || !m.C.allFinite()) {
      e << names[i] << ".truth: mounting must have a unit quaternion and a finite centre";
      return Error{e.str()};
    }
  }
  if (Eigen::AngleAxisd(spec.master_from_camera[0].q).angle() > 1e-9 ||
      spec.master_from_camera[0].C.norm() > 1e-12) {
    e << names[0] << ".truth: the master defines the rig frame; its mounting must be the identity";
    return Error{e.str()};
  }
  return Status::Ok();
}

// Frame rate, and at most one of num_frames and duration_s.
Status CheckTiming(const SimulatedRigSpec& spec) {
  std::ostringstream e;
  if (!(spec.frame_rate_hz > 0 && spec.frame_rate_hz <= 1000)) {
    e << "frame_rate_hz: " << spec.frame_rate_hz << " outside (0, 1000]";
    return Error{e.str()};
  }
  if (spec.num_frames < 0 || !(spec.duration_s >= 0)) {
    e << "num_frames/duration_s: must not be negative";
    return Error{e.str()};
  }
  if (spec.num_frames > 0 && spec.duration_s > 0) {
    e << "num_frames, duration_s: give at most one of them";
    return Error{e.str()};
  }
  return Status::Ok();
}

// Waypoints or a trajectory file, exactly one of them, and each well-formed.
Status CheckTrajectory(const SimulatedRigSpec& spec) {
  std::ostringstream e;
  const bool has_file = !spec.trajectory_t_ns.empty() || !spec.trajectory_world_from_body.empty();
  if (spec.waypoints.empty() == !has_file) {
    e << "trajectory: give either waypoints or a trajectory file";
    return Error{e.str()};
  }
  if (!spec.waypoints.empty()) {
    if (spec.waypoints.size() < 2) {
      e << "trajectory.waypoints: need at least 2 waypoints, got " << spec.waypoints.size();
      return Error{e.str()};
    }
    if (!(spec.waypoint_interval_s > 0 && std::isfinite(spec.waypoint_interval_s))) {
      e << "trajectory.waypoint_interval_s: must be > 0";
      return Error{e.str()};
    }
    for (size_t i = 0; i < spec.waypoints.size(); ++i) {
      const SimulatedRigSpec::Waypoint& w = spec.waypoints[i];
      if (!w.position.allFinite() || !IsUnit(w.world_from_master)) {
        e << "trajectory.waypoints[" << i << "]: position must be finite, orientation unit";
        return Error{e.str()};
      }
    }
    return Status::Ok();
  }
  const std::vector<int64_t>& t_ns = spec.trajectory_t_ns;
  if (t_ns.size() != spec.trajectory_world_from_body.size() || t_ns.size() < 2) {
    e << "trajectory.file: need at least 2 poses with one stamp each, got "
      << spec.trajectory_world_from_body.size() << " poses and " << t_ns.size() << " stamps";
    return Error{e.str()};
  }
  for (size_t i = 1; i < t_ns.size(); ++i) {
    if (t_ns[i] <= t_ns[i - 1]) {
      e << "trajectory.file: stamps must increase strictly (pose " << i << ")";
      return Error{e.str()};
    }
  }
  if (!IsUnit(spec.body_from_master.q) || !spec.body_from_master.C.allFinite()) {
    e << "trajectory.body_from_master: needs a unit quaternion and a finite centre";
    return Error{e.str()};
  }
  return Status::Ok();
}

// At least one frame, and the last one inside the trajectory.
Status CheckFrames(const SimulatedRigSpec& spec) {
  std::ostringstream e;
  const int64_t frames = spec.FrameCount();
  const double duration = spec.TrajectoryDuration();
  const double last = static_cast<double>(frames - 1) / spec.frame_rate_hz;
  if (frames < 1) {
    e << "num_frames: no frames";
    return Error{e.str()};
  }
  if (last > duration + 1e-6) {
    e << (spec.num_frames > 0 ? "num_frames" : "duration_s") << ": " << frames << " frames at "
      << spec.frame_rate_hz << " Hz last " << last << " s, longer than the trajectory (" << duration
      << " s)";
    return Error{e.str()};
  }
  return Status::Ok();
}

// Moving objects: count, size and speed in range; none in a pipe.
Status CheckMovingObjects(const SimulatedRigSpec& spec) {
  const SimulatedRigSpec::Scene::MovingObjects& m = spec.scene.moving_objects;
  std::ostringstream e;
  if (m.count < 0 || m.count > 64) {
    e << "scene.moving_objects.count: " << m.count << " outside [0, 64]";
    return Error{e.str()};
  }
  if (m.count > 0 && spec.scene.type == SimulatedRigSpec::SceneType::kPipe) {
    e << "scene.moving_objects: only in a room, yard or street, not in a pipe";
    return Error{e.str()};
  }
  if (!(m.size_m.allFinite() && m.size_m.minCoeff() > 0 && m.size_m.maxCoeff() <= 100)) {
    e << "scene.moving_objects.size: every extent must be in (0, 100] m";
    return Error{e.str()};
  }
  if (!(m.speed_mps > 0 && m.speed_mps <= 100)) {
    e << "scene.moving_objects.speed_mps: " << m.speed_mps << " outside (0, 100] m/s";
    return Error{e.str()};
  }
  return Status::Ok();
}

Status CheckScene(const SimulatedRigSpec& spec) {
  const SimulatedRigSpec::Scene& scene = spec.scene;
  std::ostringstream e;
  if (scene.type != SimulatedRigSpec::SceneType::kPipe) {
    const Eigen::Vector3d size = spec.SceneSize();
    if (!(size.minCoeff() > 0) || !size.allFinite() || size.maxCoeff() > 100000) {
      e << "scene.size: every extent must be in (0, 100000] m";
      return Error{e.str()};
    }
  }
  if (scene.boxes < 0 || scene.boxes > 64) {
    e << "scene.boxes: " << scene.boxes << " outside [0, 64]";
    return Error{e.str()};
  }
  if (!(scene.pipe_diameter > 0 && scene.pipe_diameter <= 1000)) {
    e << "scene.diameter: must be in (0, 1000] m";
    return Error{e.str()};
  }
  if (!(scene.pipe_length > 0 && scene.pipe_length <= 100000)) {
    e << "scene.length: must be in (0, 100000] m";
    return Error{e.str()};
  }
  if (!(scene.texel_m >= 0 && scene.texel_m <= 10)) {
    e << "scene.texel_m: must be in (0, 10] m";
    return Error{e.str()};
  }
  if (Status moving = CheckMovingObjects(spec); !moving.ok()) return moving;
  for (size_t i = 0; i < scene.textures.size(); ++i) {
    const SimulatedRigSpec::GreyImage& t = scene.textures[i];
    if (t.width < kMinTextureImagePx || t.height < kMinTextureImagePx ||
        t.pixels.size() != static_cast<size_t>(t.width) * static_cast<size_t>(t.height)) {
      e << "scene.textures[" << i << "] (" << t.name << "): " << t.width << "x" << t.height
        << " with " << t.pixels.size() << " pixels; needs at least " << kMinTextureImagePx << "x"
        << kMinTextureImagePx;
      return Error{e.str()};
    }
  }
  return Status::Ok();
}

// Image noise, motion blur, rolling shutter and light.
Status CheckImaging(const SimulatedRigSpec& spec) {
  std::ostringstream e;
  const double period = 1.0 / spec.frame_rate_hz;
  if (!(spec.noise_sigma >= 0 && spec.noise_sigma <= 100)) {
    e << "noise_sigma: " << spec.noise_sigma << " outside [0, 100]";
    return Error{e.str()};
  }
  if (!(spec.blur_exposure_s >= 0 && spec.blur_exposure_s < period)) {
    e << "motion_blur.exposure_ms: " << spec.blur_exposure_s * 1e3
      << " must be >= 0 and shorter than the frame period (" << period * 1e3 << " ms)";
    return Error{e.str()};
  }
  if (spec.blur_exposure_s > 0 && (spec.blur_samples < 2 || spec.blur_samples > 32)) {
    e << "motion_blur.samples: " << spec.blur_samples << " outside [2, 32]";
    return Error{e.str()};
  }
  if (!(spec.rolling_shutter_s >= 0 && spec.rolling_shutter_s < period)) {
    e << "rolling_shutter_ms: " << spec.rolling_shutter_s * 1e3
      << " must be >= 0 and shorter than the frame period (" << period * 1e3 << " ms)";
    return Error{e.str()};
  }
  if (!(spec.vignetting >= 0 && spec.vignetting < 1)) {
    e << "vignetting: " << spec.vignetting << " outside [0, 1)";
    return Error{e.str()};
  }
  if (!(spec.exposure_steps.interval_s >= 0 && std::isfinite(spec.exposure_steps.interval_s))) {
    e << "exposure_steps.interval_s: " << spec.exposure_steps.interval_s << " must be >= 0";
    return Error{e.str()};
  }
  if (!(spec.exposure_steps.max_factor >= 1 && spec.exposure_steps.max_factor <= 8)) {
    e << "exposure_steps.max_factor: " << spec.exposure_steps.max_factor << " outside [1, 8]";
    return Error{e.str()};
  }
  return Status::Ok();
}

// Drops, stamp jitter and camera failures.
Status CheckDevices(const SimulatedRigSpec& spec) {
  std::ostringstream e;
  const double period = 1.0 / spec.frame_rate_hz;
  if (!(spec.drop_probability >= 0 && spec.drop_probability < 1)) {
    e << "drop_probability: " << spec.drop_probability << " outside [0, 1)";
    return Error{e.str()};
  }
  if (!(spec.timestamp_jitter_s >= 0 && 3 * spec.timestamp_jitter_s < 0.5 * period)) {
    e << "timestamp_jitter_ms: " << spec.timestamp_jitter_s * 1e3
      << " must be >= 0 with 3 sigma below half a frame period (" << period * 0.5e3 << " ms)";
    return Error{e.str()};
  }
  for (const auto& [name, span] : spec.blackout_s) {
    if (std::find(spec.names.begin(), spec.names.end(), name) == spec.names.end()) {
      e << "blackout_s." << name << ": no camera of that name";
      return Error{e.str()};
    }
    if (!(span.first >= 0 && span.first < span.second && std::isfinite(span.second))) {
      e << "blackout_s." << name << ": must be [from, to) with 0 <= from < to (s)";
      return Error{e.str()};
    }
  }
  for (const auto& [name, span] : spec.blur_burst_s) {
    if (std::find(spec.names.begin(), spec.names.end(), name) == spec.names.end()) {
      e << "blur_burst_s." << name << ": no camera of that name";
      return Error{e.str()};
    }
    if (!(span.first >= 0 && span.first < span.second && std::isfinite(span.second))) {
      e << "blur_burst_s." << name << ": must be [from, to) with 0 <= from < to (s)";
      return Error{e.str()};
    }
  }
  for (const auto& [name, t] : spec.fail_after_s) {
    if (std::find(spec.names.begin(), spec.names.end(), name) == spec.names.end()) {
      e << "fail_after_s." << name << ": no camera of that name";
      return Error{e.str()};
    }
    if (!(t >= 0 && std::isfinite(t))) {
      e << "fail_after_s." << name << ": must be >= 0 s";
      return Error{e.str()};
    }
  }
  return Status::Ok();
}

Status CheckTrigger(const SimulatedRigSpec& spec) {
  const SimulatedRigSpec::Trigger& trigger = spec.trigger;
  if (!trigger.enabled) return Status::Ok();
  std::ostringstream e;
  if (spec.names.size() > 8) {
    e << "trigger: at most 8 cameras (trigger lines), not " << spec.names.size();
  } else if (spec.frame_rate_hz > 400) {
    e << "trigger: frame_rate_hz above the generator's 400 Hz";
  } else if (!(std::abs(trigger.drift_ppm) <= 1000)) {
    e << "trigger.drift_ppm: outside [-1000, 1000]";
  } else if (!(trigger.link_jitter_ms >= 0 && trigger.link_jitter_ms <= 20)) {
    e << "trigger.link_jitter_ms: outside [0, 20]";
  } else if (!(trigger.exposure_ms >= 0 && trigger.exposure_ms * 1e-3 * spec.frame_rate_hz < 1)) {
    e << "trigger.exposure_ms: must be in [0, frame period)";
  } else if (!(trigger.corrupt_probability >= 0 && trigger.corrupt_probability <= 0.01)) {
    e << "trigger.corrupt_probability: outside [0, 0.01]";
  }
  if (!e.str().empty()) return Error{e.str()};
  return Status::Ok();
}

Status CheckRenderBlock(const SimulatedRigSpec& spec) {
  if (spec.render_block < 1 || spec.render_block > 32) {
    std::ostringstream e;
    e << "render_block: " << spec.render_block << " outside [1, 32]";
    return Error{e.str()};
  }
  return Status::Ok();
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
  for (Status (*check)(const SimulatedRigSpec&) :
       {CheckCameras, CheckTiming, CheckTrajectory, CheckFrames, CheckScene, CheckImaging,
        CheckDevices, CheckTrigger, CheckRenderBlock}) {
    if (Status status = check(*this); !status.ok()) return status;
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
