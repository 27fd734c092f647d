// SPDX-License-Identifier: Apache-2.0
#include "rigcal/pipeline/calib_node.h"

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <sstream>
#include <utility>

#include "calib_node_impl.h"
#include "rigcal/base/format.h"
#include "rigcal/io/atomic_file.h"
#include "rigcal/io/estimator_state_file.h"
#include "rigcal/io/rig_files.h"
#include "rigcal/io/text_file.h"
#include "rigcal/lcm/bus_exposure.h"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/pose_message.h"
#include "rigcal/lcm/status_message.h"
#include "rigcal/pipeline/online_replay.h"

namespace rigcal::pipeline {
namespace {

using Clock = std::chrono::steady_clock;

int64_t MonotonicNanos() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch())
      .count();
}

// First rejections are warnings, later ones debug: a broken publisher must not flood the log.
constexpr int64_t kLoudRejections = 10;

void OnPoseMessage(const ::lcm::ReceiveBuffer* rbuf, const std::string& channel, CalibNode* node) {
  node->HandlePose(channel, rbuf->data, rbuf->data_size);
}

const char* VoStateShort(vo::VoState state) {
  switch (state) {
    case vo::VoState::kInitialising:
      return "init";
    case vo::VoState::kTracking:
      return "trk";
    case vo::VoState::kLost:
      return "lost";
  }
  return "?";
}

// "cam0 trk s0 12.3ms 240f drop2 reloc1 | cam1 DEAD" (drops and relocalisations when any): every
// camera of a capture, for the status line.
std::string CameraLine(const PipelineSnapshot& snapshot) {
  std::ostringstream line;
  for (const CameraHealth& h : snapshot.cameras) {
    if (line.tellp() > 0) line << " | ";
    if (h.dead) {
      line << h.name << " DEAD";
      continue;
    }
    char buf[128];
    std::snprintf(buf, sizeof(buf), "%s %s s%d %.1fms %lldf", h.name.c_str(),
                  VoStateShort(h.vo_state), h.segment, h.vo_ms_median,
                  static_cast<long long>(h.frames_processed));
    line << buf;
    if (h.dropped_backlog > 0) line << " drop" << h.dropped_backlog;
    if (h.relocalisations > 0) line << " reloc" << h.relocalisations;
  }
  return line.str();
}

int64_t PeriodNs(double rate_hz) { return rate_hz > 0.0 ? static_cast<int64_t>(1e9 / rate_hz) : 0; }

}  // namespace

CalibNode::Impl::Impl(io::RigConfig c, CalibNodeOptions o)
    : config(std::move(c)),
      options(std::move(o)),
      names(config.CameraNames()),
      validator(names),
      schedule(/*catch_up=*/!options.log_path.empty() || options.capture) {
  // A capture's calibrator is built once its source says whether it is lossless (OpenCapture).
  if (!capturing()) {
    calibrator = std::make_unique<OnlineCalibrator>(
        names, ProcessOnlineOptions(config.online, names.size(), /*lossless=*/replaying()));
  }
  summary.cameras.resize(names.size());
  rates.resize(names.size());
  last_pose_wall.assign(names.size(), Clock::time_point::min());
  state_path = options.state_path.empty() ? config.state.path : options.state_path;
  AddJobs();
}

void CalibNode::Impl::AddJobs() {
  job_extrinsics = schedule.Add(PeriodNs(config.publish.extrinsics_rate_hz));
  job_status = schedule.Add(PeriodNs(config.publish.status_rate_hz));
  job_state = schedule.Add(static_cast<int64_t>(config.state.save_interval_s * 1e9));
  job_report = schedule.Add(static_cast<int64_t>(options.report_every_s * 1e9));
}

int CalibNode::Impl::CameraOfChannel(const std::string& channel, bool images) const {
  for (size_t i = 0; i < names.size(); ++i) {
    if (channel == (images ? lcm::ImageChannel(names[i]) : lcm::PoseChannel(names[i]))) {
      return static_cast<int>(i);
    }
  }
  return -1;
}

void CalibNode::Impl::Reject(const std::string& what) {
  if (validator.stats().TotalRejected() + summary.unknown_channel <= kLoudRejections) {
    log->warn("rejected: {}", what);
  } else {
    log->debug("rejected: {}", what);
  }
}

void CalibNode::Impl::HandlePose(const std::string& channel, const void* data, int64_t size) {
  const int camera = CameraOfChannel(channel, /*images=*/false);
  if (camera < 0) {
    ++summary.unknown_channel;
    Reject(channel + ": no camera of that name in the rig");
    return;
  }
  auto pose = validator.DecodeCameraPose(channel, data, size);
  if (!pose) {
    ++summary.cameras[camera].invalid;
    Reject(pose.error());
    return;
  }
  if (pose->pose.camera != camera) {
    ++summary.cameras[camera].invalid;
    Reject(channel + ": camera_pose_t.camera '" + names[pose->pose.camera] +
           "' does not match the channel");
    return;
  }
  if (replaying()) {
    AcceptOnLogTime(camera, pose->pose);
  } else {
    Accept(camera, pose->pose);
  }
}

bool CalibNode::Impl::IsLeap(int64_t t_ns) const {
  constexpr int64_t kLeapNs = 2'000'000'000;  // SyncBuffer: the glitch horizon is at least 2 s
  return clock_ns >= 0 && t_ns > clock_ns && t_ns - clock_ns > kLeapNs;
}

void CalibNode::Impl::AcceptOnLogTime(int camera, const CameraPose& pose) {
  if (IsLeap(pose.t_ns)) {
    if (Accept(camera, pose)) AdvanceLogTime(pose.t_ns);
    return;
  }
  AdvanceLogTime(pose.t_ns);
  Accept(camera, pose);
}

void CalibNode::Impl::AddError(const std::string& error) {
  log->error("{}", error);
  MutexLock lock(output_mutex);
  errors.push_back(error);
}

bool CalibNode::Impl::Accept(int camera, const CameraPose& given) {
  CameraPose pose = given;
  if (!segment_offset.empty()) pose.segment += segment_offset[static_cast<size_t>(camera)];
  CameraInputStats& stats = summary.cameras[camera];
  ++stats.received;
  received_total.fetch_add(1);
  const PushResult result = calibrator->Push(pose);
  // A stamp rejected as a clock glitch moves no clock, not even the camera's newest stamp (the
  // age of its newest pose in RIGCAL_STATUS).
  if (result != PushResult::kClockGlitch) {
    stats.last_t_ns = pose.t_ns;
    stats.last_segment = pose.segment;
    last_pose_wall[camera] = Clock::now();
  }
  if (result != PushResult::kAccepted) {
    ++stats.sync_rejected;
    log->debug("{}: pose at {} ns not buffered: {}", names[camera], pose.t_ns, ToString(result));
    return false;
  }
  return true;
}

void CalibNode::Impl::AcceptVoPose(const CameraPose& pose) {
  const bool leap = stream_timers() && IsLeap(pose.t_ns);
  if (stream_timers() && !leap) AdvanceLogTime(pose.t_ns);
  if (auto msg = lcm::CameraPoseToLcm(pose, names, pose.t_ns / 1000)) {
    int64_t published = 0;
    Publish(lcm::PoseChannel(names[pose.camera]), *msg, &published, /*record=*/true);
  }
  if (Accept(pose.camera, pose) && leap) AdvanceLogTime(pose.t_ns);
}

template <typename Message>
void CalibNode::Impl::Publish(const std::string& channel, const Message& msg, int64_t* counter,
                              bool record) {
  ::lcm::LCM* out = Output();
  record = record && recorder != nullptr;
  if (out == nullptr && !record) return;
  auto bytes = lcm::EncodeMessage(channel, names, msg);
  if (!bytes) {
    AddError("not published: " + bytes.error());
    return;
  }
  if (record) recorder->Record(channel, msg.utime, *bytes);
  if (out == nullptr) return;
  int rc = 0;
  {
    MutexLock lock(output_mutex);
    out = Output();  // again under the lock: CloseOutput may have closed it meanwhile
    if (out == nullptr) return;
    rc = out->publish(channel, bytes->data(), static_cast<unsigned int>(bytes->size()));
    if (rc == 0 && published_file && out == output.get()) {
      published_file->Count(channel, static_cast<int64_t>(bytes->size()));
    }
  }
  if (rc != 0) {
    AddError(channel + ": LCM publish failed" +
             (options.publish_url.empty() ? std::string() : " on " + options.publish_url));
    return;
  }
  ++*counter;
}

void CalibNode::Impl::RunJob(int job, int64_t utime) {
  if (job == job_extrinsics) PublishExtrinsics(calibrator->Estimate(), utime);
  if (job == job_status) PublishStatus(calibrator->Estimate(), utime);
  if (job == job_state) SaveState();
  if (job == job_report) ReportLine(calibrator->Estimate());
}

void CalibNode::Impl::PublishExtrinsics(const RigEstimate& estimate, int64_t utime) {
  auto msg = lcm::EstimateToLcm(estimate, utime);
  if (!msg) {
    AddError("RIGCAL_EXTRINSICS not published: " + msg.error());
    return;
  }
  // A recording holds the estimate once there is one.
  Publish(lcm::kExtrinsicsChannel, *msg, &summary.extrinsics_published,
          /*record=*/estimate.sets > 0);
}

std::vector<lcm::CameraStatusInput> CalibNode::Impl::CameraInputs() {
  std::vector<lcm::CameraStatusInput> cameras;
  const int64_t start = first_stamp_ns;
  if (pipeline) {
    // Image replay: the VO's view of every camera, rates from the frame stamps.
    const PipelineSnapshot snapshot = pipeline->Snapshot();
    for (size_t i = 0; i < names.size(); ++i) {
      const CameraHealth& h = snapshot.cameras[i];
      lcm::CameraStatusInput cam = StatusInputOf(h);
      cam.name = names[i];
      cam.fps = rates[i].Update(h.frames_processed, h.last_frame_t_ns, start);
      if (images_invalid) cam.dropped_invalid = images_invalid[i].load();
      cameras.push_back(cam);
    }
    return cameras;
  }
  const Clock::time_point now = Clock::now();
  for (size_t i = 0; i < names.size(); ++i) {
    lcm::CameraStatusInput cam;
    const CameraInputStats& input = summary.cameras[i];
    cam.name = names[i];
    cam.frames_received = input.received;
    cam.fps = rates[i].Update(input.received, input.last_t_ns, start);
    cam.dropped_invalid = input.invalid;
    // The VO runs elsewhere: its state is inferred from the pose stream.
    if (input.received > 0) {
      const double age_s = replaying()
                               ? static_cast<double>(clock_ns - input.last_t_ns) * 1e-9
                               : std::chrono::duration<double>(now - last_pose_wall[i]).count();
      cam.last_pose_age_ms = static_cast<int64_t>(age_s * 1e3);
      cam.vo_segment = input.last_segment;
      cam.vo_state = !replaying() && age_s > options.camera_timeout_s
                         ? camera_status_t::VO_DEAD
                         : camera_status_t::VO_TRACKING;
    }
    cameras.push_back(cam);
  }
  return cameras;
}

void CalibNode::Impl::PublishStatus(const RigEstimate& estimate, int64_t utime) {
  const rig_status_t msg =
      lcm::MakeRigStatus(CameraInputs(), calibrator->sync_stats(),
                         config.online.sync.capacity * static_cast<int32_t>(names.size()), estimate,
                         cpu.Sample(), utime);
  Publish(lcm::kStatusChannel, msg, &summary.status_published);
}

void CalibNode::Impl::ReportLine(const RigEstimate& estimate) {
  std::string state_message;
  lcm::EstimatorState(estimate, &state_message);
  std::ostringstream line;
  if (capturing() && pipeline) line << CameraLine(pipeline->Snapshot()) << " | ";
  line << "sets " << estimate.sets << " | " << state_message;
  for (size_t i = 0; i < estimate.rig.slaves.size(); ++i) {
    const SlaveCalibration& slave = estimate.rig.slaves[i];
    line << " | " << slave.name << ": " << slave.motions.used << " motions";
    if (slave.solved()) {
      // Each σ beside its quantity; C in the master odometry's unit (u).
      char buf[128];
      std::snprintf(buf, sizeof(buf), ", C=(%.3f %.3f %.3f) u ±%s, rotation ±%s°",
                    slave.estimate.C.x(), slave.estimate.C.y(), slave.estimate.C.z(),
                    SigmaText(slave.pos_std.maxCoeff(), 2).c_str(),
                    SigmaText(slave.rot_std_deg, 2).c_str());
      line << buf;
    }
    line << " ["
         << StateText(slave.state, i < estimate.online.size() ? estimate.online[i].flags : 0u)
         << "]";
  }
  log->info("{}", line.str());
}

void CalibNode::Impl::CloseOutput() {
  std::optional<PublishedFileCheck> check;
  {
    MutexLock lock(output_mutex);
    if (!output) return;
    output.reset();  // LCM's file provider flushes and closes its file here
    check = std::exchange(published_file, std::nullopt);
  }
  if (!check) return;
  if (const Status status = check->Verify(); !status.ok()) {
    summary.publish_failed = true;
    AddError("publishing failed: " + status.message());
  }
}

void CalibNode::Impl::Finish(int64_t utime, bool interrupted) {
  // Clean stop: everything received is estimated, published, saved and written. After a
  // signal, a periodic refinement in flight (a history refinement takes seconds) ends early and
  // none follows, so that neither Flush nor the final refinement waits for one.
  if (interrupted) calibrator->CancelRefinements();
  calibrator->Flush();
  if (interrupted) {
    // Within 2 s of a signal: the final history refinement where the last one's duration says
    // it ends within a second (a live run's, which always ends this way: SIGTERM from systemd,
    // SIGINT at the terminal), else the window refinement of the sets taken since the last one
    // (tens of ms). Either way the result is refined and has every σ.
    calibrator->RefineFinalBefore(std::chrono::steady_clock::now() + std::chrono::seconds(1));
  } else {
    calibrator->RefineNow(/*final=*/true);
  }
  calibrator->Stop();
  const RigEstimate estimate = calibrator->Estimate();
  PublishExtrinsics(estimate, utime);
  PublishStatus(estimate, utime);
  CloseOutput();
  SaveState();
  ReportStateSaves();
  // A run that calibrated nothing leaves the files of an earlier run as they are.
  for (const std::string& path : {state_path, options.result_path}) {
    if (!path.empty() && CalibratedNothing() && std::filesystem::exists(path)) {
      summary.kept_files.push_back(path);
    }
  }
  for (const std::string& path : summary.kept_files) {
    log->warn("calibrated nothing (no synchronised pose set): {} left as it was", path);
  }
  if (!options.result_path.empty() &&
      !(CalibratedNothing() && std::filesystem::exists(options.result_path))) {
    if (const Status status = io::WriteFileAtomically(
            options.result_path, io::ResultToYaml(estimate.rig) + options.result_provenance);
        !status.ok()) {
      AddError("result not written: " + status.message());
    } else {
      summary.result_written = true;
    }
  }
  ReportLine(estimate);
  summary.estimate = estimate;
  summary.sync = calibrator->sync_stats();
  summary.decode = validator.stats();
  MutexLock lock(output_mutex);
  summary.errors.insert(summary.errors.end(), errors.begin(), errors.end());
}

CalibNode::CalibNode(io::RigConfig config, CalibNodeOptions options, ::lcm::LCM* lcm)
    : impl_(std::make_unique<Impl>(std::move(config), std::move(options))) {
  impl_->bus = lcm;
}

CalibNode::~CalibNode() {
  if (impl_->pipeline) impl_->pipeline->Stop();
  if (impl_->sources && impl_->sources->trigger) impl_->sources->trigger->Stop();
  if (impl_->calibrator) impl_->calibrator->Stop();
}

void CalibNode::HandlePose(const std::string& channel, const void* data, int64_t size) {
  impl_->HandlePose(channel, data, size);
}

int64_t CalibNode::ReceivedPoses() const { return impl_->received_total.load(); }

OnlineCalibrator::RefinementPasses CalibNode::RefinementPasses() const {
  if (!impl_->calibrator) return {};
  return impl_->calibrator->refinement_passes();
}

Status CalibNode::Open() {
  Impl& m = *impl_;
  if (m.opened) return Error{"CalibNode::Open called twice"};
  // Before anything is opened: a state path rigcal may not read or replace is refused.
  if (const Status status = m.CheckStatePath(); !status.ok()) return status;
  if (m.replaying()) {
    if (const Status status = m.OpenLog(); !status.ok()) return status;
  } else if (m.capturing()) {
    if (const Status status = m.OpenCapture(); !status.ok()) return status;
  } else if (m.bus == nullptr) {
    m.owned_bus = std::make_unique<::lcm::LCM>(m.options.lcm_url);
    if (!m.owned_bus->good()) {
      return Error{
          (m.options.lcm_url.empty() ? std::string("the default LCM URL") : m.options.lcm_url) +
          ": cannot open LCM (udpm:// needs a multicast route, e.g. on lo: "
          "ip route add 224.0.0.0/4 dev lo)"};
    }
    if (!m.options.lcm_network) {
      if (Status status = lcm::CheckBusStaysOnHost(m.options.lcm_url); !status.ok()) return status;
    }
    m.bus = m.owned_bus.get();
  }
  if (m.bus != nullptr && !m.replaying() && !m.capturing()) {
    m.bus->subscribeFunction("RIGCAL_POSE_.*", &OnPoseMessage, this);
  }
  if (m.options.resume) m.RestoreState();
  m.calibrator->Start();
  m.opened = true;
  return Status::Ok();
}

CalibNodeSummary CalibNode::Run(const std::atomic<bool>& stop) {
  Impl& m = *impl_;
  if (!m.opened) {
    m.summary.errors.push_back("CalibNode::Run before a successful Open");
    return m.summary;
  }
  // A wait of the input thread for the estimator (a lossless push, a drain on log time) that
  // sees the stop cancels a periodic refinement in flight; the flag is the caller's, so it is
  // let go before Run returns.
  m.calibrator->CancelRefinementsWhen(&stop);
  if (m.capturing()) {
    m.RunCapture(stop);
  } else if (m.replaying()) {
    m.ReplayLog(stop);
    m.Finish(std::max<int64_t>(m.clock_ns, 0) / 1000, stop.load());
    if (m.options.on_progress) {
      ReplayProgress progress = m.Progress();
      progress.done = true;
      m.options.on_progress(progress);
    }
  } else {
    m.RunLcm(stop);
  }
  m.calibrator->CancelRefinementsWhen(nullptr);
  return m.summary;
}

void CalibNode::Impl::RunLcm(const std::atomic<bool>& stop) {
  const int64_t start = MonotonicNanos();
  while (!stop.load()) {
    errno = 0;
    const int rc = bus->handleTimeout(50);
    // A signal interrupts the wait (EINTR): the loop condition decides.
    if (rc < 0 && errno != EINTR && !stop.load()) {
      AddError("LCM receive failed; stopping");
      break;
    }
    const int64_t now = MonotonicNanos();
    int job = 0;
    int64_t deadline = 0;
    while (schedule.NextDue(now, &job, &deadline)) RunJob(job, now / 1000);
    if (options.on_tick) options.on_tick();
    if (options.duration_s > 0 && static_cast<double>(now - start) * 1e-9 >= options.duration_s) {
      break;
    }
  }
  Finish(MonotonicNanos() / 1000, stop.load());
}

}  // namespace rigcal::pipeline
