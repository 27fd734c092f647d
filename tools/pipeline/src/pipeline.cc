// SPDX-License-Identifier: Apache-2.0
#include "rigcal/pipeline/pipeline.h"

#include <algorithm>
#include <array>
#include <stdexcept>

#include "rigcal/base/logging.h"
#include "rigcal/base/robust_statistics.h"
#include "rigcal/calib/pose_merge.h"
#include "rigcal/camera_status_t.hpp"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/pose_message.h"
#include "rigcal/lcm/shared_bus.h"

namespace rigcal::pipeline {
namespace {

constexpr size_t kTimingWindow = 64;

}  // namespace

OnlineOptions ProcessOnlineOptions(OnlineOptions online, size_t cameras, bool lossless) {
  if (online.sync.required.empty() && cameras > 0) {
    online.sync.required.assign(cameras, false);
    online.sync.required[0] = true;
  }
  online.lossless = lossless;
  online.refine_on_stream_time = lossless;
  return online;
}

int8_t CameraStatusVoState(const CameraHealth& health) {
  if (health.dead) return camera_status_t::VO_DEAD;
  switch (health.vo_state) {
    case vo::VoState::kTracking:
      return camera_status_t::VO_TRACKING;
    case vo::VoState::kLost:
      return camera_status_t::VO_LOST;
    default:
      return camera_status_t::VO_INITIALISING;
  }
}

lcm::CameraStatusInput StatusInputOf(const CameraHealth& health) {
  lcm::CameraStatusInput c;
  c.name = health.name;
  c.frames_received = health.frames_captured;
  c.dropped_backlog = health.dropped_backlog;
  c.vo_state = CameraStatusVoState(health);
  c.relocalisations = health.relocalisations;
  if (health.last_pose_t_ns >= 0) {
    c.vo_segment = health.segment;
    if (health.last_frame_t_ns >= 0) {
      c.last_pose_age_ms =
          std::max<int64_t>(0, (health.last_frame_t_ns - health.last_pose_t_ns) / 1'000'000);
    }
  }
  return c;
}

Status PipelineOptions::Check() const {
  if (frame_queue_capacity < 1) return Error{"frame_queue_capacity: must be >= 1"};
  if (const Status vo_status = vo.Check(); !vo_status.ok()) {
    return Error{"vo." + vo_status.message()};
  }
  return Status::Ok();
}

// One camera's device, VO and threads. The capture thread owns `device` and pushes into
// `frames`; the VO thread pops `frames` and owns `vo`; they, Snapshot and RecordedPoses share
// the rest under `mutex`.
struct Pipeline::Camera {
  int index = 0;
  std::unique_ptr<capture::CameraDevice> device;
  vo::MonocularVo vo;
  BoundedQueue<capture::Frame> frames;
  std::thread capture_thread;
  std::thread vo_thread;

  mutable Mutex mutex;
  CameraHealth health RIGCAL_GUARDED_BY(mutex);
  std::array<double, kTimingWindow> timings RIGCAL_GUARDED_BY(mutex) = {};
  size_t timing_count RIGCAL_GUARDED_BY(mutex) = 0;
  std::vector<CameraPose> recorded RIGCAL_GUARDED_BY(mutex);

  Camera(int i, std::string name, std::unique_ptr<capture::CameraDevice> d,
         std::shared_ptr<const camera::CameraModel> model, const PipelineOptions& options)
      : index(i),
        device(std::move(d)),
        vo(std::move(model), i, options.vo),
        frames(static_cast<size_t>(options.frame_queue_capacity)) {
    health.name = std::move(name);
  }
};

Pipeline::Pipeline(std::vector<std::string> names,
                   std::vector<std::unique_ptr<capture::CameraDevice>> devices,
                   std::vector<std::shared_ptr<const camera::CameraModel>> cameras,
                   OnlineOptions online, PipelineOptions options, lcm::SharedBus* bus)
    : names_(std::move(names)),
      options_(std::move(options)),
      bus_(bus),
      vo_threads_running_(static_cast<int>(names_.size())) {
  if (names_.size() < 2 || devices.size() != names_.size() || cameras.size() != names_.size()) {
    throw std::invalid_argument("Pipeline: need one device and one camera model per camera (>= 2)");
  }
  // Checked before any camera's MonocularVo is built from options_.vo.
  RequireValid(options_.Check(), "PipelineOptions");
  for (size_t i = 0; i < names_.size(); ++i) {
    if (!devices[i] || !cameras[i]) {
      throw std::invalid_argument("Pipeline: camera '" + names_[i] + "' has no device or model");
    }
  }
  online = ProcessOnlineOptions(std::move(online), names_.size(), options_.lossless);
  const int64_t lead_ns = online.sync.EffectiveMaxWaitNs() / 3;
  if (!options_.pose_sink) calibrator_ = std::make_unique<OnlineCalibrator>(names_, online);
  if (options_.lossless) {
    merge_ = std::make_unique<PoseMerge>(static_cast<int>(names_.size()), lead_ns,
                                         [this](const CameraPose& pose) { Forward(pose); });
  }
  for (size_t i = 0; i < names_.size(); ++i) {
    cameras_.push_back(std::make_unique<Camera>(
        static_cast<int>(i), names_[i], std::move(devices[i]), std::move(cameras[i]), options_));
  }
}

Pipeline::~Pipeline() { Stop(); }

void Pipeline::Start() {
  MutexLock lock(stop_mutex_);
  if (started_) return;
  started_ = true;
  if (calibrator_) calibrator_->Start();
  for (auto& camera : cameras_) {
    const int i = camera->index;
    camera->vo_thread = std::thread([this, i] { VoLoop(i); });
    camera->capture_thread = std::thread([this, i] { CaptureLoop(i); });
  }
}

void Pipeline::CaptureLoop(int index) {
  Camera& camera = *cameras_[static_cast<size_t>(index)];
  auto log = ModuleLogger("drivers");
  while (true) {
    Expected<std::optional<capture::Frame>> grabbed = camera.device->Grab();
    if (!grabbed) {
      {
        MutexLock lock(camera.mutex);
        camera.health.dead = true;
        camera.health.dead_reason = grabbed.error();
      }
      log->error("camera '{}' died: {}", names_[static_cast<size_t>(index)], grabbed.error());
      break;
    }
    if (!grabbed->has_value()) {
      MutexLock lock(camera.mutex);
      camera.health.ended = true;
      break;
    }
    capture::Frame frame = std::move(**grabbed);
    frame.camera = index;
    if (!frame.progress_mark) {
      MutexLock lock(camera.mutex);
      ++camera.health.frames_captured;
      camera.health.last_frame_t_ns = frame.t_ns;
    }
    const uint64_t dropped_before = camera.frames.dropped();
    const bool pushed = options_.lossless ? camera.frames.PushWait(std::move(frame))
                                          : camera.frames.Push(std::move(frame));
    if (!pushed) break;  // stopped
    const uint64_t dropped = camera.frames.dropped() - dropped_before;
    if (dropped > 0) {
      MutexLock lock(camera.mutex);
      camera.health.dropped_backlog += static_cast<int64_t>(dropped);
    }
  }
  camera.frames.Stop();  // the VO thread drains what is queued, then ends
}

void Pipeline::Forward(const CameraPose& pose) {
  const auto index = static_cast<size_t>(pose.camera);
  if (options_.pose_sink) {
    options_.pose_sink(pose);
    return;
  }
  const PushResult pushed = calibrator_->Push(pose);
  if (pushed != PushResult::kAccepted) {
    Camera& camera = *cameras_[index];
    MutexLock lock(camera.mutex);
    ++camera.health.sync_rejected;
  }
  if (bus_ != nullptr) {
    auto msg = lcm::CameraPoseToLcm(pose, names_, pose.t_ns / 1000);
    if (msg) {
      const std::string channel = lcm::PoseChannel(names_[index]);
      auto bytes = lcm::EncodeMessage(channel, names_, *msg);
      if (bytes) bus_->Publish(channel, *bytes);
    }
  }
}

void Pipeline::VoLoop(int index) {
  Camera& camera = *cameras_[static_cast<size_t>(index)];
  while (std::optional<capture::Frame> frame = camera.frames.Pop()) {
    if (frame->progress_mark) {
      if (merge_) merge_->Deliver(index, frame->t_ns, {});
      continue;
    }
    const vo::VoResult result = camera.vo.Process(frame->t_ns, frame->image);
    std::vector<CameraPose> poses;
    if (result.segment_start) poses.push_back(*result.segment_start);
    if (result.pose) {
      poses.push_back(*result.pose);
      poses.back().trigger_seq = frame->seq;
    }
    for (CameraPose& pose : poses) pose.camera = index;
    {
      MutexLock lock(camera.mutex);
      CameraHealth& h = camera.health;
      ++h.frames_processed;
      h.poses += static_cast<int64_t>(poses.size());
      h.vo_state = result.state;
      h.segment = camera.vo.segment();
      h.relocalisations = camera.vo.relocalisations();
      h.vo_message = result.message;
      if (result.pose) h.last_pose_t_ns = result.pose->t_ns;
      camera.timings[camera.timing_count++ % kTimingWindow] = result.processing_ms;
      if (options_.record_poses) {
        for (const CameraPose& pose : poses) camera.recorded.push_back(pose);
      }
    }
    if (merge_) {
      merge_->Deliver(index, frame->t_ns, std::move(poses));
    } else {
      for (const CameraPose& pose : poses) Forward(pose);
    }
  }
  if (merge_) merge_->End(index);
  --vo_threads_running_;
}

PipelineSnapshot Pipeline::Snapshot() const {
  PipelineSnapshot snapshot;
  for (const auto& camera : cameras_) {
    MutexLock lock(camera->mutex);
    CameraHealth h = camera->health;
    const size_t n = std::min(camera->timing_count, kTimingWindow);
    h.vo_ms_median = UpperMedian(std::vector<double>(
        camera->timings.begin(), camera->timings.begin() + static_cast<std::ptrdiff_t>(n)));
    snapshot.cameras.push_back(std::move(h));
  }
  if (calibrator_) {
    snapshot.sync = calibrator_->sync_stats();
    snapshot.estimate = calibrator_->Estimate();
  }
  snapshot.finished = Finished();
  return snapshot;
}

bool Pipeline::Finished() const { return vo_threads_running_.load() == 0; }

void Pipeline::Stop() {
  MutexLock lock(stop_mutex_);
  if (!started_ || stopped_) return;
  stopped_ = true;
  // Devices stop delivering; queued frames are still processed (Pop drains a stopped queue).
  for (auto& camera : cameras_) {
    camera->device->Interrupt();
    camera->frames.Stop();
  }
  if (merge_) merge_->Stop();
  for (auto& camera : cameras_) {
    if (camera->capture_thread.joinable()) camera->capture_thread.join();
    if (camera->vo_thread.joinable()) camera->vo_thread.join();
  }
  if (calibrator_) {
    calibrator_->Flush();
    calibrator_->RefineNow(/*final=*/true);
    calibrator_->Stop();
  }
}

std::vector<CameraPose> Pipeline::RecordedPoses(int camera) const {
  const Camera& c = *cameras_.at(static_cast<size_t>(camera));
  MutexLock lock(c.mutex);
  return c.recorded;
}

}  // namespace rigcal::pipeline
