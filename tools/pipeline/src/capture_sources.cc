#include "rigcal/pipeline/capture_sources.h"

#include <chrono>

#include "rigcal/camera/camera_spec.h"
#include "rigcal/drivers/triggered_camera.h"

namespace rigcal::tools {

Expected<CaptureSources> OpenCaptureSources(const RigConfig& config, bool fast,
                                            const std::string& prefix, std::ostream& progress) {
  CaptureSources sources;
  const std::vector<std::string> names = config.CameraNames();
  if (config.simulated_source) {
    drivers::SimulatedRigSpec spec = *config.simulated_source;
    if (fast) spec.realtime = false;
    sources.realtime = spec.realtime;
    // `source.trigger`: a simulated trigger generator whose first pulse is frame 0.
    std::shared_ptr<drivers::SimulatedTriggerTimeline> trigger;
    if (spec.trigger.enabled) {
      const int64_t start_ns = spec.realtime
                                   ? std::chrono::duration_cast<std::chrono::nanoseconds>(
                                         std::chrono::steady_clock::now().time_since_epoch())
                                         .count()
                                   : spec.start_time_ns;
      auto made_trigger = drivers::MakeSimulatedRigTrigger(spec, start_ns);
      if (!made_trigger) return Error{config.path + ": source.trigger: " + made_trigger.error()};
      trigger = std::move(*made_trigger);
      if (!spec.realtime) spec.start_time_ns = trigger->first_tick_ns();
    }
    progress << prefix << "building the simulated rig (" << spec.names.size() << " cameras, "
             << drivers::ToString(spec.scene.type) << " scene)...\n";
    auto made = drivers::MakeSimulatedRig(spec);
    if (!made) return Error{config.path + ": " + made.error()};
    sources.rig = std::move(*made);
    sources.devices = sources.rig->MakeDevices();
    sources.models = spec.cameras;
    if (trigger) {
      if (spec.realtime) sources.rig->StartAt(trigger->first_tick_ns());
      for (size_t i = 0; i < sources.devices.size(); ++i) {
        sources.devices[i] = std::make_unique<drivers::TriggeredCamera>(
            std::move(sources.devices[i]), trigger,
            drivers::CameraTriggerSpec{static_cast<int>(i), 0, 0});
      }
      progress << prefix << "simulated hardware trigger: camera i on line i, frames carry the "
               << "pulse sequence and its mapped exposure centre\n";
    }
    progress << prefix << sources.rig->num_frames() << " frames per camera at "
             << sources.rig->frame_rate_hz() << " Hz"
             << (sources.realtime ? " (real time)" : " (as fast as possible)") << "\n";
    return sources;
  }
  if (!config.v4l2_devices.empty()) {
    sources.realtime = true;  // live cameras: never wait for the VO
    for (size_t i = 0; i < names.size(); ++i) {
      auto device =
          drivers::V4l2Device::Open(names[i], static_cast<int>(i), config.v4l2_devices[i]);
      if (!device) return Error{config.path + ": " + device.error()};
      auto model = camera::MakeCameraModel(*config.cameras[i].spec);
      if (!model) return Error{config.path + ": camera '" + names[i] + "': " + model.error()};
      const drivers::V4l2Negotiated& n = (*device)->negotiated();
      progress << prefix << "camera '" << names[i] << "': " << n.node << " (" << n.card << ", "
               << n.bus_info << ") " << drivers::FourccText(n.fourcc) << " " << n.layout.width
               << "x" << n.layout.height << " at " << (*device)->frame_rate_hz() << " Hz\n";
      sources.v4l2.push_back(device->get());
      sources.devices.push_back(std::move(*device));
      sources.models.push_back(std::shared_ptr<const camera::CameraModel>(std::move(*model)));
    }
    return sources;
  }
  if (!config.libcamera_devices.empty()) {
    sources.realtime = true;
    for (size_t i = 0; i < names.size(); ++i) {
      auto device = drivers::LibcameraDevice::Open(names[i], static_cast<int>(i),
                                                   config.libcamera_devices[i]);
      if (!device) return Error{config.path + ": " + device.error()};
      auto model = camera::MakeCameraModel(*config.cameras[i].spec);
      if (!model) return Error{config.path + ": camera '" + names[i] + "': " + model.error()};
      progress << prefix << "camera '" << names[i] << "': libcamera " << (*device)->camera_id()
               << " " << (*device)->configuration() << " (" << (*device)->validation() << ")\n";
      sources.devices.push_back(std::move(*device));
      sources.models.push_back(std::shared_ptr<const camera::CameraModel>(std::move(*model)));
    }
    return sources;
  }
  if (config.image_folders.empty()) {
    return Error{config.path +
                 ": no `source:` section (supported: simulated, image_folders, v4l2, libcamera)"};
  }
  for (size_t i = 0; i < names.size(); ++i) {
    auto device =
        drivers::ImageFolderDevice::Open(config.image_folders[i], names[i], static_cast<int>(i));
    if (!device) {
      return Error{config.path + ": camera '" + names[i] + "': " + device.error()};
    }
    auto model = camera::MakeCameraModel(*config.cameras[i].spec);
    if (!model) return Error{config.path + ": camera '" + names[i] + "': " + model.error()};
    progress << prefix << "camera '" << names[i] << "': " << (*device)->size()
             << " images listed in " << config.image_folders[i] << "\n";
    sources.folders.push_back(device->get());
    sources.devices.push_back(std::move(*device));
    sources.models.push_back(std::shared_ptr<const camera::CameraModel>(std::move(*model)));
  }
  return sources;
}

void ReportFolderProblems(const std::vector<drivers::ImageFolderDevice*>& folders,
                          const std::string& prefix, std::ostream& out) {
  for (const drivers::ImageFolderDevice* folder : folders) {
    const std::vector<std::string> skipped = folder->skipped_files();
    if (!skipped.empty()) {
      out << prefix << "camera '" << folder->name() << "': " << skipped.size()
          << " listed images missing or unreadable, skipped:\n";
      for (const std::string& file : skipped) out << "  " << file << "\n";
    }
    for (const std::string& problem : folder->csv_problems()) out << prefix << problem << "\n";
  }
}

void ReportCaptureStats(const std::vector<drivers::V4l2Device*>& devices, const std::string& prefix,
                        std::ostream& out) {
  for (const drivers::V4l2Device* device : devices) {
    const drivers::V4l2Stats s = device->stats();
    out << prefix << "camera '" << device->name() << "': " << s.frames << " frames, "
        << s.sequence_drops << " dropped by the driver, " << s.error_buffers
        << " erroneous buffers, " << s.device_losses << " device losses, " << s.reconnections
        << " reconnections" << (s.last_loss.empty() ? "" : " (last loss: " + s.last_loss + ")")
        << "\n";
  }
}

}  // namespace rigcal::tools
