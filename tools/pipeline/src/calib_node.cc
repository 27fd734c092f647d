#include "rigcal/pipeline/calib_node.h"

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <sstream>

#include "rigcal/calib/format.h"
#include "rigcal/calib/logging.h"
#include "rigcal/io/atomic_file.h"
#include "rigcal/io/estimator_state_file.h"
#include "rigcal/io/rig_files.h"
#include "rigcal/io/yaml_fields.h"
#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/pose_message.h"
#include "rigcal/lcm/process_stats.h"
#include "rigcal/lcm/status_message.h"
#include "rigcal/pipeline/online_replay.h"

namespace rigcal::tools {
namespace {

using Clock = std::chrono::steady_clock;

int64_t MonotonicMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(Clock::now().time_since_epoch())
      .count();
}

// First rejections are warnings, later ones debug: a broken publisher must not flood the log.
constexpr int64_t kLoudRejections = 10;

void OnPoseMessage(const lcm::ReceiveBuffer* rbuf, const std::string& channel, CalibNode* node) {
  node->HandlePose(channel, rbuf->data, rbuf->data_size);
}

}  // namespace

Expected<rig_extrinsics_t> EstimateToLcm(const RigEstimate& estimate, int64_t utime) {
  auto msg = RigCalibrationToLcm(estimate.rig, utime, estimate.t_ns);
  if (!msg) return msg;
  for (size_t i = 0; i < msg->slaves.size() && i < estimate.online.size(); ++i) {
    const uint32_t online = estimate.online[i].flags;
    int32_t& flags = msg->slaves[i].flags;
    if (online & rigcal::kFlagPlanar) flags |= tools::kFlagPlanar;
    if (online & rigcal::kFlagTranslationalOnly) flags |= tools::kFlagTranslationalOnly;
    if (online & rigcal::kFlagRefined) flags |= tools::kFlagRefined;
  }
  return msg;
}

struct CalibNode::Impl {
  RigConfig config;
  CalibNodeOptions options;
  CameraNames names;
  std::shared_ptr<spdlog::logger> log = ModuleLogger("tools");
  lcm::LCM* bus = nullptr;  // input + output for live runs (owned or external)
  std::unique_ptr<lcm::LCM> owned_bus;
  std::unique_ptr<lcm::LCM> output;  // replay: optional output
  std::unique_ptr<lcm::LogFile> log_file;
  OnlineCalibrator calibrator;
  MessageValidator validator;
  CalibNodeSummary summary;
  std::string state_path;
  // Status bookkeeping (LCM thread only).
  std::vector<int64_t> received_at_last_status;
  std::vector<Clock::time_point> last_pose_wall;
  Clock::time_point last_status_wall = Clock::now();
  CpuMeter cpu;
  bool opened = false;
  std::atomic<int64_t> received_total{0};  // written by the LCM thread, read by ReceivedPoses
  long log_good_end = 0;  // file offset after the last complete event of the replayed log

  Impl(RigConfig c, CalibNodeOptions o)
      : config(std::move(c)),
        options(std::move(o)),
        names(config.CameraNames()),
        calibrator(names, config.online),
        validator(names) {
    summary.cameras.resize(names.size());
    received_at_last_status.assign(names.size(), 0);
    last_pose_wall.assign(names.size(), Clock::time_point::min());
    state_path = options.state_path.empty() ? config.state.path : options.state_path;
  }

  lcm::LCM* Output() { return options.log_path.empty() ? bus : output.get(); }

  int CameraOfChannel(const std::string& channel) const {
    for (size_t i = 0; i < names.size(); ++i) {
      if (channel == PoseChannel(names[i])) return static_cast<int>(i);
    }
    return -1;
  }

  void Reject(const std::string& what) {
    if (validator.stats().TotalRejected() + summary.unknown_channel <= kLoudRejections) {
      log->warn("rejected: {}", what);
    } else {
      log->debug("rejected: {}", what);
    }
  }

  void HandlePose(const std::string& channel, const void* data, int64_t size) {
    const int camera = CameraOfChannel(channel);
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
    CameraInputStats& stats = summary.cameras[camera];
    ++stats.received;
    received_total.fetch_add(1);
    stats.last_t_ns = pose->pose.t_ns;
    last_pose_wall[camera] = Clock::now();
    const PushResult result = calibrator.Push(pose->pose);
    if (result != PushResult::kAccepted) {
      log->debug("{}: pose at {} ns not buffered: {}", channel, pose->pose.t_ns, ToString(result));
    }
  }

  template <typename Message>
  void Publish(const std::string& channel, const Message& msg, int64_t* counter) {
    lcm::LCM* out = Output();
    if (out == nullptr) return;
    auto bytes = EncodeMessage(channel, names, msg);
    if (!bytes) {
      summary.errors.push_back(bytes.error());
      log->error("not published: {}", bytes.error());
      return;
    }
    if (out->publish(channel, bytes->data(), static_cast<unsigned int>(bytes->size())) != 0) {
      summary.errors.push_back(channel + ": LCM publish failed");
      log->error("{}: LCM publish failed", channel);
      return;
    }
    ++*counter;
  }

  void PublishExtrinsics(const RigEstimate& estimate) {
    auto msg = EstimateToLcm(estimate, MonotonicMicros());
    if (!msg) {
      log->error("RIGCAL_EXTRINSICS not published: {}", msg.error());
      summary.errors.push_back(msg.error());
      return;
    }
    Publish(kExtrinsicsChannel, *msg, &summary.extrinsics_published);
  }

  rig_status_t MakeStatus(const RigEstimate& estimate, const SyncStats& sync) {
    const Clock::time_point now = Clock::now();
    const double period_s = std::chrono::duration<double>(now - last_status_wall).count();
    last_status_wall = now;
    std::vector<CameraStatusInput> cameras;
    for (size_t i = 0; i < names.size(); ++i) {
      CameraStatusInput cam;
      const CameraInputStats& input = summary.cameras[i];
      cam.name = names[i];
      cam.frames_received = input.received;
      cam.fps = period_s > 0.0 ? (input.received - received_at_last_status[i]) / period_s : 0.0;
      received_at_last_status[i] = input.received;
      cam.dropped_invalid = input.invalid;
      // The VO runs elsewhere: its state is inferred from the pose stream.
      if (input.received > 0) {
        const double age_s = std::chrono::duration<double>(now - last_pose_wall[i]).count();
        cam.last_pose_age_ms = static_cast<int64_t>(age_s * 1e3);
        cam.vo_state = options.log_path.empty() && age_s > options.camera_timeout_s
                           ? camera_status_t::VO_DEAD
                           : camera_status_t::VO_TRACKING;
      }
      cameras.push_back(cam);
    }
    return MakeRigStatus(cameras, sync,
                         config.online.sync.capacity * static_cast<int32_t>(names.size()), estimate,
                         cpu.Sample(), MonotonicMicros());
  }

  void PublishStatus(const RigEstimate& estimate) {
    rig_status_t msg = MakeStatus(estimate, calibrator.sync_stats());
    Publish(kStatusChannel, msg, &summary.status_published);
  }

  void SaveState() {
    if (state_path.empty()) return;
    if (const Status status =
            WriteFileAtomically(state_path, FormatEstimatorState(calibrator.SaveState()));
        !status.ok()) {
      summary.errors.push_back(status.message());
      log->error("state not saved: {}", status.message());
      return;
    }
    ++summary.state_saves;
  }

  void ReportLine(const RigEstimate& estimate) {
    std::string state_message;
    EstimatorState(estimate, &state_message);
    std::ostringstream line;
    line << "sets " << estimate.sets << " | " << state_message;
    for (size_t i = 0; i < estimate.rig.slaves.size(); ++i) {
      const SlaveCalibration& slave = estimate.rig.slaves[i];
      line << " | " << slave.name << ": " << slave.motions.used << " motions";
      if (slave.solved()) {
        char buf[96];
        std::snprintf(buf, sizeof(buf), ", C=(%.3f %.3f %.3f) ±%s°", slave.estimate.C.x(),
                      slave.estimate.C.y(), slave.estimate.C.z(),
                      SigmaText(slave.rot_std_deg, 2).c_str());
        line << buf;
      }
      line << " ["
           << StateText(slave.state, i < estimate.online.size() ? estimate.online[i].flags : 0u)
           << "]";
    }
    log->info("{}", line.str());
  }

  // Reads the next event of the replayed log; false at its end.
  bool ReplayOne() {
    const lcm::LogEvent* event = log_file->readNextEvent();
    if (event == nullptr) {
      summary.end_of_log = true;
      // LCM reports a clean end and a damaged tail alike: compare where the last complete
      // event ended with the file size.
      std::error_code ec;
      const auto size = std::filesystem::file_size(options.log_path, ec);
      if (!ec && log_good_end >= 0 && static_cast<uintmax_t>(log_good_end) < size) {
        summary.log_problem = options.log_path + ": truncated or corrupt event after byte " +
                              std::to_string(log_good_end) + " of " + std::to_string(size) +
                              "; replay stopped there";
        log->warn("{}", summary.log_problem);
      }
      return false;
    }
    if (FILE* file = log_file->getFilePtr()) log_good_end = std::ftell(file);
    if (event->channel.rfind("RIGCAL_POSE_", 0) == 0) {
      HandlePose(event->channel, event->data, event->datalen);
    }
    return true;
  }
};

CalibNode::CalibNode(RigConfig config, CalibNodeOptions options, lcm::LCM* lcm)
    : impl_(std::make_unique<Impl>(std::move(config), std::move(options))) {
  impl_->bus = lcm;
}

CalibNode::~CalibNode() { impl_->calibrator.Stop(); }

void CalibNode::HandlePose(const std::string& channel, const void* data, int64_t size) {
  impl_->HandlePose(channel, data, size);
}

int64_t CalibNode::ReceivedPoses() const { return impl_->received_total.load(); }

Status CalibNode::Open() {
  Impl& m = *impl_;
  if (m.opened) return Error{"CalibNode::Open called twice"};
  if (!m.options.log_path.empty()) {
    m.log_file = std::make_unique<lcm::LogFile>(m.options.log_path, "r");
    if (!m.log_file->good()) return Error{m.options.log_path + ": cannot open the LCM log"};
    if (!m.options.publish_url.empty()) {
      m.output = std::make_unique<lcm::LCM>(m.options.publish_url);
      if (!m.output->good()) return Error{m.options.publish_url + ": cannot open the LCM URL"};
    }
  } else if (m.bus == nullptr) {
    m.owned_bus = std::make_unique<lcm::LCM>(m.options.lcm_url);
    if (!m.owned_bus->good()) {
      return Error{
          (m.options.lcm_url.empty() ? std::string("the default LCM URL") : m.options.lcm_url) +
          ": cannot open LCM (udpm:// needs a multicast route, e.g. on lo: "
          "ip route add 224.0.0.0/4 dev lo)"};
    }
    m.bus = m.owned_bus.get();
  }
  if (m.bus != nullptr) {
    m.bus->subscribeFunction("RIGCAL_POSE_.*", &OnPoseMessage, this);
  }
  if (m.options.resume) {
    if (m.state_path.empty()) {
      m.log->warn("--resume: no state file configured (state.path or --state); starting afresh");
    } else {
      auto text = ReadWholeFile(m.state_path);
      Status restored;
      if (text) {
        const Expected<RigEstimatorState> state = ParseEstimatorState(*text);
        restored = state ? m.calibrator.RestoreState(*state) : state.status();
      }
      if (!text) {
        m.log->warn("--resume: {}; starting afresh", text.error());
      } else if (!restored.ok()) {
        m.log->warn("--resume: {}: {}; ignored, starting afresh", m.state_path, restored.message());
      } else {
        m.summary.resumed = true;
        m.log->info("resumed from {}", m.state_path);
      }
    }
  }
  m.calibrator.Start();
  m.opened = true;
  return Status::Ok();
}

CalibNodeSummary CalibNode::Run(const std::atomic<bool>& stop) {
  Impl& m = *impl_;
  if (!m.opened) {
    m.summary.errors.push_back("CalibNode::Run before a successful Open");
    return m.summary;
  }
  const Clock::time_point start = Clock::now();
  auto every = [](double rate_hz) {
    return std::chrono::duration_cast<Clock::duration>(
        std::chrono::duration<double>(1.0 / rate_hz));
  };
  const Clock::duration extrinsics_period = every(m.config.publish.extrinsics_rate_hz);
  const Clock::duration status_period = every(m.config.publish.status_rate_hz);
  const Clock::duration state_period = every(1.0 / m.config.state.save_interval_s);
  const Clock::duration report_period =
      m.options.report_every_s > 0 ? every(1.0 / m.options.report_every_s) : Clock::duration::max();
  Clock::time_point next_extrinsics = start + extrinsics_period;
  Clock::time_point next_status = start + status_period;
  Clock::time_point next_state = start + state_period;
  Clock::time_point next_report =
      report_period == Clock::duration::max() ? Clock::time_point::max() : start + report_period;

  while (!stop.load()) {
    if (m.log_file) {
      // Replay: a batch of events between housekeeping checks.
      bool more = true;
      for (int i = 0; i < 256 && more; ++i) more = m.ReplayOne();
      if (!more) break;
    } else {
      errno = 0;
      const int rc = m.bus->handleTimeout(50);
      // A signal interrupts the wait (EINTR): the loop condition decides.
      if (rc < 0 && errno != EINTR && !stop.load()) {
        m.summary.errors.push_back("LCM receive failed; stopping");
        m.log->error("LCM receive failed; stopping");
        break;
      }
    }
    const Clock::time_point now = Clock::now();
    if (now >= next_extrinsics) {
      m.PublishExtrinsics(m.calibrator.Estimate());
      next_extrinsics = now + extrinsics_period;
    }
    if (now >= next_status) {
      m.PublishStatus(m.calibrator.Estimate());
      next_status = now + status_period;
    }
    if (now >= next_state) {
      m.SaveState();
      next_state = now + state_period;
    }
    if (now >= next_report) {
      m.ReportLine(m.calibrator.Estimate());
      next_report = now + report_period;
    }
    if (m.options.duration_s > 0 &&
        std::chrono::duration<double>(now - start).count() >= m.options.duration_s) {
      break;
    }
  }

  // Clean stop: everything received is estimated, published, saved and written.
  m.calibrator.Flush();
  m.calibrator.RefineNow(/*final=*/true);
  m.calibrator.Stop();
  const RigEstimate estimate = m.calibrator.Estimate();
  m.PublishExtrinsics(estimate);
  m.PublishStatus(estimate);
  m.SaveState();
  if (!m.options.result_path.empty()) {
    if (const Status status = WriteResultYaml(m.options.result_path, estimate.rig); !status.ok()) {
      m.summary.errors.push_back(status.message());
      m.log->error("result not written: {}", status.message());
    }
  }
  m.ReportLine(estimate);
  m.summary.estimate = estimate;
  m.summary.sync = m.calibrator.sync_stats();
  m.summary.decode = m.validator.stats();
  return m.summary;
}

}  // namespace rigcal::tools
