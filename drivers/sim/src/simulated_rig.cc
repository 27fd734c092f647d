// SPDX-License-Identifier: Apache-2.0
// SimulatedRig: building a simulated rig from its spec (trajectory, scene, free-space check,
// render tables, noise table), its devices, ground-truth poses and renders (the ground truth as
// data: sim_ground_truth.cc).
#include "rigcal/sim/simulated_rig.h"

#include <chrono>
#include <cmath>
#include <sstream>

#include "rigcal/base/logging.h"
#include "sim_random.h"
#include "sim_rig_clock.h"
#include "sim_rig_data.h"

namespace rigcal::sim {

const SimulatedRigSpec& SimulatedRig::spec() const { return data_->spec; }
int SimulatedRig::num_cameras() const { return static_cast<int>(data_->spec.names.size()); }
int64_t SimulatedRig::num_frames() const { return data_->num_frames; }
double SimulatedRig::frame_rate_hz() const { return data_->spec.frame_rate_hz; }

std::unique_ptr<SimulatedCamera> SimulatedRig::MakeDevice(int camera) const {
  if (camera < 0 || camera >= num_cameras()) return nullptr;
  return std::unique_ptr<SimulatedCamera>(new SimulatedCamera(data_, clock_, camera));
}

std::vector<std::unique_ptr<capture::CameraDevice>> SimulatedRig::MakeDevices() const {
  std::vector<std::unique_ptr<capture::CameraDevice>> devices;
  for (int i = 0; i < num_cameras(); ++i) devices.push_back(MakeDevice(i));
  return devices;
}

void SimulatedRig::Start() const {
  if (data_->spec.realtime) clock_->StartOnce();
}

void SimulatedRig::StartAt(int64_t epoch_ns) const {
  if (data_->spec.realtime) clock_->StartAt(epoch_ns);
}

void SimulatedRig::StartOn(std::function<int64_t(int64_t)> host_ns_since) const {
  if (data_->spec.realtime) clock_->StartOn(std::move(host_ns_since));
}

int64_t SimulatedRig::epoch_ns() const {
  return data_->spec.realtime ? clock_->Epoch() : data_->spec.start_time_ns;
}

int64_t SimulatedRig::FrameTimeNs(int64_t k) const {
  return data_->spec.realtime ? clock_->HostNs(data_->OffsetNs(k))
                              : data_->spec.start_time_ns + data_->OffsetNs(k);
}

double SimulatedRig::FrameStreamTime(int64_t k) const { return data_->StreamTime(k); }

Pose SimulatedRig::WorldFromMasterAt(double t_s) const { return data_->trajectory.At(t_s); }

Pose SimulatedRig::WorldFromCameraAt(int camera, double t_s) const {
  return data_->WorldFromCamera(camera, t_s);
}

std::vector<Similarity> SimulatedRig::TrueRig() const {
  std::vector<Similarity> rig;
  for (size_t i = 1; i < data_->spec.master_from_camera.size(); ++i) {
    Similarity s;
    s.q = data_->spec.master_from_camera[i].q;
    s.C = data_->spec.master_from_camera[i].C;
    s.scale = 1.0;
    rig.push_back(s);
  }
  return rig;
}

cv::Mat SimulatedRig::RenderFrame(int camera, int64_t k, RenderKernel kernel) const {
  std::vector<float> acc;
  std::vector<internal::Hit> hits;
  return data_->Render(camera, k, &acc, &hits, kernel);
}

cv::Mat SimulatedRig::RenderView(int camera, const Pose& world_from_camera, int block,
                                 RenderKernel kernel) const {
  const internal::CameraTables& tables = data_->cameras[camera];
  if (block <= 0) block = data_->spec.render_block;
  std::optional<internal::NodeGrid> own_grid;
  const internal::NodeGrid* grid = nullptr;
  if (block >= 2) {
    if (block == data_->spec.render_block) {
      grid = &data_->grids[camera];
    } else {
      own_grid = internal::MakeNodeGrid(tables, block);
      grid = &*own_grid;
    }
  }
  std::vector<float> acc(static_cast<size_t>(tables.width) * tables.height, 0.f);
  std::vector<internal::Hit> hits;
  internal::RenderAccumulate(data_->scene, tables, grid, world_from_camera, 1.f, acc.data(), &hits,
                             kernel);
  cv::Mat image(tables.height, tables.width, CV_8UC1);
  for (int y = 0; y < tables.height; ++y) {
    for (int x = 0; x < tables.width; ++x) {
      image.at<uint8_t>(y, x) =
          cv::saturate_cast<uint8_t>(acc[static_cast<size_t>(y) * tables.width + x]);
    }
  }
  return image;
}

std::vector<Eigen::AlignedBox3d> SimulatedRig::MovingObjectsAt(double t_s) const {
  const internal::MovingObjects& moving = data_->moving;
  std::vector<Eigen::AlignedBox3d> boxes;
  boxes.reserve(static_cast<size_t>(moving.size()));
  for (int i = 0; i < moving.size(); ++i) {
    const Eigen::Vector3d centre = moving.CentreAt(i, t_s);
    boxes.emplace_back(centre - moving.half_size(), centre + moving.half_size());
  }
  return boxes;
}

std::optional<double> SimulatedRig::CastRay(const Eigen::Vector3d& origin,
                                            const Eigen::Vector3d& direction) const {
  return data_->scene.Distance(origin, direction);
}

namespace {

// The moving objects' paths, kept kMovingObjectClearance away from every camera centre from
// frame 0 to one frame period after the last frame (the last rows of a rolling shutter), taken
// a quarter frame period apart.
Expected<internal::MovingObjects> BuildMovingObjects(const internal::SimulatedRigData& data) {
  const SimulatedRigSpec& s = data.spec;
  if (s.scene.moving_objects.count <= 0) return internal::MovingObjects();
  const double step_s = 0.25 / s.frame_rate_hz;
  std::vector<internal::TimedPoint> cameras;
  cameras.reserve(static_cast<size_t>(4 * data.num_frames + 1) * s.names.size());
  for (int64_t q = 0; q <= 4 * data.num_frames; ++q) {
    const double t_s = static_cast<double>(q) * step_s;
    for (size_t c = 0; c < s.names.size(); ++c) {
      cameras.push_back({t_s, data.WorldFromCamera(static_cast<int>(c), t_s).C});
    }
  }
  return internal::MovingObjects::Build(s, cameras, step_s, kMovingObjectClearance);
}

}  // namespace

Expected<SimulatedRig> MakeSimulatedRig(SimulatedRigSpec spec) {
  if (Status status = spec.Check(); !status.ok()) return status;
  const auto start = std::chrono::steady_clock::now();
  for (Pose& m : spec.master_from_camera) m.q.normalize();
  for (auto& w : spec.waypoints) w.world_from_master.normalize();
  auto data = std::make_shared<internal::SimulatedRigData>();
  data->num_frames = spec.FrameCount();
  if (!spec.waypoints.empty()) {
    std::vector<Pose> waypoints;
    for (const auto& w : spec.waypoints) {
      Pose p;
      p.q = w.world_from_master;
      p.C = w.position;
      waypoints.push_back(p);
    }
    data->trajectory = internal::Trajectory::FromWaypoints(waypoints, spec.waypoint_interval_s);
  } else {
    for (Pose& p : spec.trajectory_world_from_body) p.q.normalize();
    spec.body_from_master.q.normalize();
    data->trajectory = internal::Trajectory::FromSamples(
        spec.trajectory_t_ns, spec.trajectory_world_from_body, spec.body_from_master);
  }
  data->fail_after_s.assign(spec.names.size(), std::nullopt);
  for (size_t i = 0; i < spec.names.size(); ++i) {
    const auto it = spec.fail_after_s.find(spec.names[i]);
    if (it != spec.fail_after_s.end()) data->fail_after_s[i] = it->second;
  }
  data->spec = std::move(spec);
  const SimulatedRigSpec& s = data->spec;
  data->scene = internal::Scene::Build(s);

  // Every camera must stay in free space.
  for (int64_t k = 0; k < data->num_frames; ++k) {
    for (size_t c = 0; c < s.names.size(); ++c) {
      const Eigen::Vector3d p = data->WorldFromCamera(static_cast<int>(c), data->StreamTime(k)).C;
      if (const Status free = data->scene.CheckFree(p, kMinClearance); !free.ok()) {
        std::ostringstream msg;
        msg << "trajectory: camera " << s.names[c] << " at stream time " << data->StreamTime(k)
            << " s (frame " << k << ") is at (" << p.x() << ", " << p.y() << ", " << p.z()
            << ") and " << free.message();
        return Error{msg.str()};
      }
    }
  }

  auto moving = BuildMovingObjects(*data);
  if (!moving.ok()) return Error{moving.error()};
  data->moving = std::move(*moving);

  for (size_t c = 0; c < s.cameras.size(); ++c) {
    data->cameras.push_back(internal::MakeCameraTables(s.cameras[c]));
    data->grids.push_back(s.render_block >= 2
                              ? internal::MakeNodeGrid(data->cameras.back(), s.render_block)
                              : internal::NodeGrid{});
  }
  internal::Rng noise_rng(internal::HashKey(s.seed, internal::kPurposeNoiseTable));
  data->noise.resize(internal::kNoiseTableSize);
  for (float& n : data->noise) n = static_cast<float>(noise_rng.Gaussian());

  const double build_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  ModuleLogger("sim")->info(
      "simulated rig: {} cameras, {} frames at {} Hz, {}; textures {:.1f} MB; built in {:.0f} ms",
      s.names.size(), data->num_frames, s.frame_rate_hz, data->scene.Describe(),
      static_cast<double>(data->scene.TextureBytes()) / 1e6, build_ms);

  SimulatedRig rig;
  rig.data_ = std::move(data);
  rig.clock_ = std::make_shared<internal::RigClock>();
  return rig;
}

}  // namespace rigcal::sim
