// SPDX-License-Identifier: Apache-2.0
// CalibNode's live capture input (calib_node.h): the config's source through the pipeline, whose
// pose sink feeds the node; the capture loop owns the timers of a live source and the watchdog.
#include <chrono>
#include <sstream>
#include <thread>

#include "calib_node_impl.h"
#include "flow_watch.h"
#include "rigcal/capture/v4l2_timestamp.h"
#include "rigcal/io/ground_truth_files.h"
#include "rigcal/lcm/bus_exposure.h"
#include "rigcal/lcm/process_stats.h"

namespace rigcal::pipeline {
namespace {

constexpr auto kLoopPeriod = std::chrono::milliseconds(20);

}  // namespace

Status CalibNode::Impl::OpenCapture() {
  if (!options.truth_dir.empty() && !config.simulated_source) {
    return Error{"a ground truth (--truth-out) needs a simulated source"};
  }
  if (!options.publish_url.empty() && bus == nullptr) {
    if (!options.lcm_network) {
      if (Status status = lcm::CheckBusStaysOnHost(options.publish_url); !status.ok()) {
        return status;
      }
    }
    if (Status status = CheckOutputUrl(options.publish_url); !status.ok()) return status;
    output = std::make_unique<::lcm::LCM>(options.publish_url);
    if (!output->good()) return Error{options.publish_url + ": cannot open LCM"};
    MutexLock lock(output_mutex);
    published_file = PublishedFileCheck::ForUrl(options.publish_url);
  }
  std::ostringstream opened_text;
  auto opened = OpenCaptureSources(config, options.fast, "", opened_text);
  std::istringstream lines(opened_text.str());
  for (std::string line; std::getline(lines, line);) log->info("{}", line);
  if (!opened) return opened.status();
  sources = std::make_unique<CaptureSources>(std::move(*opened));
  lossless_capture = !sources->realtime;
  // A live source's timers run on the wall clock of its stamps, once per period.
  schedule = PeriodicSchedule(/*catch_up=*/lossless_capture);
  AddJobs();
  calibrator = std::make_unique<OnlineCalibrator>(
      names, ProcessOnlineOptions(config.online, names.size(), lossless_capture));
  if (sources->rig && !options.truth_dir.empty()) {
    if (Status status = io::WriteGroundTruth(sources->rig->GroundTruth(), options.truth_dir);
        !status.ok()) {
      return status;
    }
  }
  std::vector<std::unique_ptr<capture::CameraDevice>> devices = std::move(sources->devices);
  if (!options.record_path.empty()) {
    if (Status status = OpenRecording(&devices); !status.ok()) return status;
    if (options.record_no_vo) return Status::Ok();
  }
  PipelineOptions pipeline_options;
  pipeline_options.lossless = lossless_capture;
  pipeline_options.record_poses = options.evaluate || !options.poses_dir.empty();
  pipeline_options.pose_sink = [this](const CameraPose& pose) { AcceptVoPose(pose); };
  pipeline = std::make_unique<Pipeline>(names, std::move(devices), sources->models, config.online,
                                        pipeline_options);
  return Status::Ok();
}

Status CalibNode::Impl::OpenRecording(
    std::vector<std::unique_ptr<capture::CameraDevice>>* devices) {
  RecorderOptions recorder_options = options.recorder;
  recorder_options.lossless = lossless_capture;
  auto opened = LogRecorder::Open(options.record_path, names, recorder_options);
  if (!opened) return opened.status();
  recorder = std::move(*opened);
  for (size_t i = 0; i < devices->size(); ++i) {
    (*devices)[i] = recorder->Tap(std::move((*devices)[i]), static_cast<int>(i));
  }
  if (options.record_no_vo) capture_loops = std::make_unique<CaptureLoops>(std::move(*devices));
  return Status::Ok();
}

bool CalibNode::Impl::CaptureFinished() const {
  return pipeline ? pipeline->Finished() : capture_loops->Finished();
}

void CalibNode::Impl::StopCapture() {
  if (pipeline) pipeline->Stop();  // the cameras and their VO; every pose handed over
  if (capture_loops) capture_loops->Stop();
  if (sources->trigger) sources->trigger->Stop();  // after the cameras it exposes
}

bool CalibNode::Impl::CapturePass(int64_t now_ns, FlowWatch* flow) {
  int job = 0;
  int64_t deadline = 0;
  while (!lossless_capture && schedule.NextDue(now_ns, &job, &deadline)) {
    RunJob(job, now_ns / 1000);
  }
  if (sources->trigger && !trigger_failure_told) {
    if (const std::string problem = sources->trigger->problem(); !problem.empty()) {
      log->error("trigger link failed: {} (frames now come without trigger pulses)", problem);
      trigger_failure_told = true;
    }
  }
  if (recorder) {
    const RecorderStats recorded = recorder->Stats();
    if (options.on_recording) options.on_recording(recorded);
    if (!recorded.error.empty()) return false;  // the disk failed: reported at the end
  }
  if (!pipeline) return true;
  std::vector<int64_t> frames;
  for (const CameraHealth& h : pipeline->Snapshot().cameras) frames.push_back(h.frames_processed);
  // Consumed first: sets matched meanwhile make `waiting` larger, never a stall out of nothing.
  const uint64_t consumed = calibrator->sets_consumed();
  const SyncStats sync = calibrator->sync_stats();
  const uint64_t matched = sync.sets_emitted - sync.consumer_overflow;
  const bool healthy =
      flow->Update(now_ns, frames, consumed, matched > consumed ? matched - consumed : 0);
  if (healthy != flow_healthy) {
    if (healthy) log->info("frames flow again from every camera into the estimator");
    if (!healthy) log->error("{}: the service watchdog is no longer fed", flow->problem());
    flow_healthy = healthy;
  }
  if (healthy && options.on_tick) options.on_tick();
  return true;
}

void CalibNode::Impl::RunCapture(const std::atomic<bool>& stop) {
  const int64_t start_ns = capture::MonotonicNowNs();
  FlowWatch flow(names, start_ns, static_cast<int64_t>(options.camera_timeout_s * 1e9));
  if (pipeline) pipeline->Start();
  if (capture_loops) capture_loops->Start();
  log->info("capturing {} cameras; SIGINT / SIGTERM stop cleanly", names.size());
  while (!stop.load() && !CaptureFinished()) {
    std::this_thread::sleep_for(kLoopPeriod);
    const int64_t now_ns = capture::MonotonicNowNs();
    if (!CapturePass(now_ns, &flow)) break;
    if (options.duration_s > 0 &&
        static_cast<double>(now_ns - start_ns) * 1e-9 >= options.duration_s) {
      break;
    }
  }
  StopCapture();
  Finish((lossless_capture ? std::max<int64_t>(clock_ns, 0) : capture::MonotonicNowNs()) / 1000,
         stop.load());
  FinishCapture();
  log->info("{:.1f} s, {} sets; RSS {:.0f} MB",
            static_cast<double>(capture::MonotonicNowNs() - start_ns) * 1e-9, summary.estimate.sets,
            static_cast<double>(lcm::ResidentSetBytes()) / (1 << 20));
}

}  // namespace rigcal::pipeline
