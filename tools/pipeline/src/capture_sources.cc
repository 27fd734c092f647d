// SPDX-License-Identifier: Apache-2.0
#include "rigcal/pipeline/capture_sources.h"

#include <chrono>
#include <cmath>
#include <functional>
#include <memory>

#include "paced_replay_device.h"
#include "rigcal/camera/camera_spec.h"
#include "rigcal/capture/v4l2_timestamp.h"
#include "rigcal/sim/simulated_trigger_timeline.h"
#include "rigcal/trigger/tick_clock.h"
#include "rigcal/trigger/triggered_camera.h"

namespace rigcal::pipeline {
namespace {

// Frame 0 of a source paced from a live trigger (a simulated rig, an image-folder replay): the
// first pulse at least this far ahead, so the cameras are ready for it.
constexpr int64_t kPacedStartLeadNs = 300'000'000;
constexpr int64_t kTriggerSyncTimeoutNs = 5'000'000'000;

// The clock of a source paced from a live trigger (a simulated rig, an image-folder replay): the
// host time of a time since the trigger's next tick, on the generator's clock (TickClock).
Expected<std::function<int64_t(int64_t)>> PacedClock(const trigger::LiveTriggerTimeline& trigger) {
  Expected<trigger::LiveTriggerTimeline::Tick> tick =
      trigger.NextTick(capture::MonotonicNowNs() + kPacedStartLeadNs, kTriggerSyncTimeoutNs);
  if (!tick) return Error{tick.error()};
  auto clock =
      std::make_shared<const trigger::TickClock>(&trigger.matcher(), tick->mcu_us, tick->host_ns);
  return std::function<int64_t(int64_t)>(
      [clock](int64_t since_tick_ns) { return clock->HostNs(since_tick_ns); });
}

// The simulated rig of `source: {type: simulated}` (with its own simulated trigger when
// `source.trigger` asks for one); `live` is the started trigger generator (may be null).
Expected<CaptureSources> OpenSimulatedRig(const io::RigConfig& config, bool fast,
                                          const std::string& prefix, std::ostream& progress,
                                          const trigger::LiveTriggerTimeline* live) {
  CaptureSources sources;
  sim::SimulatedRigSpec spec = *config.simulated_source;
  if (fast) spec.realtime = false;
  sources.realtime = spec.realtime;
  // `source.trigger`: a simulated trigger generator whose first pulse is frame 0.
  std::shared_ptr<sim::SimulatedTriggerTimeline> trigger;
  if (spec.trigger.enabled) {
    const int64_t start_ns = spec.realtime
                                 ? std::chrono::duration_cast<std::chrono::nanoseconds>(
                                       std::chrono::steady_clock::now().time_since_epoch())
                                       .count()
                                 : spec.start_time_ns;
    auto made_trigger = sim::MakeSimulatedRigTrigger(spec, start_ns);
    if (!made_trigger) return Error{config.path + ": source.trigger: " + made_trigger.error()};
    trigger = std::move(*made_trigger);
    if (!spec.realtime) spec.start_time_ns = trigger->first_tick_ns();
  }
  progress << prefix << "building the simulated rig (" << spec.names.size() << " cameras, "
           << sim::ToString(spec.scene.type) << " scene)...\n";
  if (live) spec.realtime = sources.realtime = true;  // paced by the generator's pulses
  auto made = sim::MakeSimulatedRig(spec);
  if (!made) return Error{config.path + ": " + made.error()};
  sources.rig = std::move(*made);
  sources.devices = sources.rig->MakeDevices();
  sources.models = spec.cameras;
  if (live) {
    auto clock = PacedClock(*live);
    if (!clock) return Error{config.path + ": " + clock.error()};
    sources.rig->StartOn(std::move(*clock));
    progress << prefix << "simulated rig paced by the trigger generator: frame 0 at its pulse\n";
  }
  if (trigger) {
    if (spec.realtime) sources.rig->StartAt(trigger->first_tick_ns());
    for (size_t i = 0; i < sources.devices.size(); ++i) {
      sources.devices[i] = std::make_unique<trigger::TriggeredCamera>(
          std::move(sources.devices[i]), trigger,
          trigger::CameraTriggerSpec{static_cast<int>(i), 0, 0});
    }
    progress << prefix << "simulated hardware trigger: camera i on line i, frames carry the "
             << "pulse sequence and its mapped exposure centre\n";
  }
  progress << prefix << sources.rig->num_frames() << " frames per camera at "
           << sources.rig->frame_rate_hz() << " Hz"
           << (sources.realtime ? " (real time)" : " (as fast as possible)") << "\n";
  return sources;
}

// One V4L2 device per camera, live.
Expected<CaptureSources> OpenV4l2Cameras(const io::RigConfig& config, const std::string& prefix,
                                         std::ostream& progress) {
  CaptureSources sources;
  const std::vector<std::string> names = config.CameraNames();
  sources.realtime = true;  // live cameras: never wait for the VO
  for (size_t i = 0; i < names.size(); ++i) {
    auto device = capture::V4l2Device::Open(names[i], static_cast<int>(i), config.v4l2_devices[i]);
    if (!device) return Error{config.path + ": " + device.error()};
    auto model = camera::MakeCameraModel(*config.cameras[i].spec);
    if (!model) return Error{config.path + ": camera '" + names[i] + "': " + model.error()};
    const capture::V4l2Negotiated& n = (*device)->negotiated();
    progress << prefix << "camera '" << names[i] << "': " << n.node << " (" << n.card << ", "
             << n.bus_info << ") " << capture::FourccText(n.fourcc) << " " << n.layout.width << "x"
             << n.layout.height << " at " << (*device)->frame_rate_hz() << " Hz\n";
    sources.v4l2.push_back(device->get());
    sources.devices.push_back(std::move(*device));
    sources.models.push_back(std::shared_ptr<const camera::CameraModel>(std::move(*model)));
  }
  return sources;
}

// One libcamera camera per camera, live.
Expected<CaptureSources> OpenLibcameraCameras(const io::RigConfig& config,
                                              const std::string& prefix, std::ostream& progress) {
  CaptureSources sources;
  const std::vector<std::string> names = config.CameraNames();
  sources.realtime = true;
  for (size_t i = 0; i < names.size(); ++i) {
    auto device =
        capture::LibcameraDevice::Open(names[i], static_cast<int>(i), config.libcamera_devices[i]);
    if (!device) return Error{config.path + ": " + device.error()};
    auto model = camera::MakeCameraModel(*config.cameras[i].spec);
    if (!model) return Error{config.path + ": camera '" + names[i] + "': " + model.error()};
    progress << prefix << "camera '" << names[i] << "': libcamera " << (*device)->camera_id() << " "
             << (*device)->configuration() << " (" << (*device)->validation() << ")\n";
    sources.devices.push_back(std::move(*device));
    sources.models.push_back(std::shared_ptr<const camera::CameraModel>(std::move(*model)));
  }
  return sources;
}

// One image folder per camera: as fast as the VO takes them, or in real time from the live
// trigger's next pulse.
Expected<CaptureSources> OpenImageFolders(const io::RigConfig& config, const std::string& prefix,
                                          std::ostream& progress,
                                          const trigger::LiveTriggerTimeline* live) {
  CaptureSources sources;
  const std::vector<std::string> names = config.CameraNames();
  // With a live trigger the folders are replayed in real time from its next pulse.
  std::shared_ptr<ReplayClock> replay_clock;
  if (live) {
    auto clock = PacedClock(*live);
    if (!clock) return Error{config.path + ": " + clock.error()};
    replay_clock = std::make_shared<ReplayClock>(std::move(*clock));
    sources.realtime = true;
    progress << prefix << "image folders replayed in real time from the trigger's next pulse\n";
  }
  for (size_t i = 0; i < names.size(); ++i) {
    const capture::ImageFolderOptions options = i < config.image_folder_options.size()
                                                    ? config.image_folder_options[i]
                                                    : capture::ImageFolderOptions{};
    auto device = capture::ImageFolderDevice::Open(config.image_folders[i], names[i],
                                                   static_cast<int>(i), options);
    if (!device) {
      return Error{config.path + ": camera '" + names[i] + "': " + device.error()};
    }
    auto model = camera::MakeCameraModel(*config.cameras[i].spec);
    if (!model) return Error{config.path + ": camera '" + names[i] + "': " + model.error()};
    progress << prefix << "camera '" << names[i] << "': " << (*device)->size() << " images in "
             << config.image_folders[i] << " (" << (*device)->layout() << ")\n";
    const double rate = (*device)->frame_rate_hz();
    if (live && std::abs(rate - live->options().settings.rate_hz) > 0.01 * rate) {
      return Error{config.path + ": camera '" + names[i] + "': its images come at " +
                   std::to_string(rate) + " Hz, not at the trigger's rate_hz " +
                   std::to_string(live->options().settings.rate_hz)};
    }
    sources.folders.push_back(device->get());
    if (replay_clock) {
      sources.devices.push_back(
          std::make_unique<PacedReplayDevice>(std::move(*device), replay_clock));
    } else {
      sources.devices.push_back(std::move(*device));
    }
    sources.models.push_back(std::shared_ptr<const camera::CameraModel>(std::move(*model)));
  }
  return sources;
}

// The devices of the source; `live` is the started trigger generator (may be null).
Expected<CaptureSources> OpenDevices(const io::RigConfig& config, bool fast,
                                     const std::string& prefix, std::ostream& progress,
                                     const trigger::LiveTriggerTimeline* live) {
  if (config.simulated_source) return OpenSimulatedRig(config, fast, prefix, progress, live);
  if (!config.v4l2_devices.empty()) return OpenV4l2Cameras(config, prefix, progress);
  if (!config.libcamera_devices.empty()) return OpenLibcameraCameras(config, prefix, progress);
  if (config.image_folders.empty()) {
    return Error{config.path +
                 ": no `source:` section (supported: simulated, image_folders, v4l2, libcamera)"};
  }
  return OpenImageFolders(config, prefix, progress, live);
}

}  // namespace

Expected<CaptureSources> OpenCaptureSources(const io::RigConfig& config, bool fast,
                                            const std::string& prefix, std::ostream& progress) {
  std::shared_ptr<trigger::LiveTriggerTimeline> live;
  if (config.trigger && config.simulated_source && fast) {
    return Error{config.path +
                 ": trigger: a live generator paces the simulated rig: not with --fast"};
  }
  if (config.trigger) {
    // Started before the cameras: an externally triggered camera sees no frame without it.
    auto started = trigger::LiveTriggerTimeline::Start(*config.trigger);
    if (!started) return Error{config.path + ": trigger: " + started.error()};
    live = std::move(*started);
    progress << prefix << "trigger generator on " << live->port() << ": "
             << config.trigger->settings.rate_hz << " Hz, " << config.trigger->settings.lines.size()
             << " line(s)\n";
  }
  auto sources = OpenDevices(config, fast, prefix, progress, live.get());
  if (!sources) return sources;
  if (live) {
    const std::vector<std::string> names = config.CameraNames();
    for (size_t i = 0; i < sources->devices.size(); ++i) {
      if (!config.camera_triggers[i]) continue;
      auto camera = std::make_unique<trigger::TriggeredCamera>(std::move(sources->devices[i]), live,
                                                               *config.camera_triggers[i]);
      sources->triggered.push_back(camera.get());
      sources->devices[i] = std::move(camera);
      progress << prefix << "camera '" << names[i] << "': trigger line "
               << config.camera_triggers[i]->line << "\n";
    }
    sources->trigger = std::move(live);
  }
  return sources;
}

void ReportTrigger(const CaptureSources& sources, const std::string& prefix, std::ostream& out) {
  if (!sources.trigger) return;
  const trigger::TriggerMatcherStats s = sources.trigger->matcher().stats();
  out << prefix << "trigger generator on " << sources.trigger->port() << ": " << s.pulses
      << " pulses, " << s.heartbeats << " heartbeats, " << s.seq_gaps << " missing pulses, "
      << s.mcu_resets << " MCU resets, " << s.map_restarts << " clock-map restarts, clock drift "
      << s.drift_ppm << " ppm\n";
  if (const std::string problem = sources.trigger->problem(); !problem.empty()) {
    out << prefix << "trigger link failed: " << problem << "\n";
  }
  for (const trigger::TriggeredCamera* camera : sources.triggered) {
    out << prefix << "camera '" << camera->name() << "': " << camera->matched()
        << " frames with their trigger pulse, " << camera->unmatched() << " without";
    if (camera->late_reports() + camera->unsynced() > 0) {
      out << " (" << camera->late_reports() << " because the pulse report came more than "
          << camera->wait_ns() / 1'000'000 << " ms after the frame: a busy host or a slow link; "
          << camera->unsynced() << " while the clock map was not synced)";
    }
    out << "\n";
  }
}

void ReportFolderProblems(const std::vector<capture::ImageFolderDevice*>& folders,
                          const std::string& prefix, std::ostream& out) {
  for (const capture::ImageFolderDevice* folder : folders) {
    const std::vector<std::string> skipped = folder->skipped_files();
    if (!skipped.empty()) {
      out << prefix << "camera '" << folder->name() << "': " << skipped.size()
          << " listed images missing or unreadable, skipped:\n";
      for (const std::string& file : skipped) out << "  " << file << "\n";
    }
    for (const std::string& problem : folder->csv_problems()) out << prefix << problem << "\n";
  }
}

void ReportCaptureStats(const std::vector<capture::V4l2Device*>& devices, const std::string& prefix,
                        std::ostream& out) {
  for (const capture::V4l2Device* device : devices) {
    const capture::V4l2Stats s = device->stats();
    out << prefix << "camera '" << device->name() << "': " << s.frames << " frames, "
        << s.sequence_drops << " dropped by the driver, " << s.error_buffers
        << " erroneous buffers, " << s.device_losses << " device losses, " << s.reconnections
        << " reconnections" << (s.last_loss.empty() ? "" : " (last loss: " + s.last_loss + ")")
        << "\n";
  }
}

}  // namespace rigcal::pipeline
