// SPDX-License-Identifier: Apache-2.0
#pragma once
// The capture devices of a rig config's `source:` section, shared by `rigcal run` and
// `rigcal record`: the simulated rig (paced in real time unless `fast`) or one EuRoC image folder
// per camera, with the camera model of every camera.

#include <memory>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/camera/camera_model.h"
#include "rigcal/capture/capture_device.h"
#include "rigcal/capture/image_folder_device.h"
#include "rigcal/capture/v4l2_device.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/sim/simulated_rig.h"
#include "rigcal/trigger/live_trigger_timeline.h"
#include "rigcal/trigger/triggered_camera.h"

namespace rigcal::pipeline {

struct CaptureSources {
  // One device and one model per camera, camera index order (config.CameraNames()).
  std::vector<std::unique_ptr<capture::CameraDevice>> devices;
  std::vector<std::shared_ptr<const camera::CameraModel>> models;
  std::vector<capture::ImageFolderDevice*> folders;  // not owned: the image-folder devices
  std::vector<capture::V4l2Device*> v4l2;            // not owned: the V4L2 devices
  std::optional<sim::SimulatedRig> rig;              // the simulated source, when it is one
  bool realtime = false;  // the devices pace themselves in real time (a live source)
  // The config's `trigger:` generator, started before the devices were opened; the caller stops
  // it after the devices (Stop), and reports its problem() (ReportTrigger).
  std::shared_ptr<trigger::LiveTriggerTimeline> trigger;
  std::vector<trigger::TriggeredCamera*> triggered;  // not owned: the triggered cameras
};

// Opens the devices of `config`'s source. `fast`: do not pace a simulated rig in real time.
// With a `trigger:` section the generator is started first (an error names its port) and every
// camera with a `trigger:` entry is wrapped in a TriggeredCamera (frames carry the pulse's
// sequence and mapped exposure centre); a simulated rig then runs in real time with frame 0 at
// the next pulse (not with `fast`; its frame rate must be the trigger's).
// What is opened goes to `progress` as lines starting with `prefix` ("rigcal run: camera 'cam0':
// 95 images in ... (ASL data.csv)"). Errors name the config file and the camera; a config without a
// source says which sources exist.
Expected<CaptureSources> OpenCaptureSources(const io::RigConfig& config, bool fast,
                                            const std::string& prefix, std::ostream& progress);

// The end-of-run report of the image folders: skipped images and CSV problems, as lines
// starting with `prefix`.
void ReportFolderProblems(const std::vector<capture::ImageFolderDevice*>& folders,
                          const std::string& prefix, std::ostream& out);

// The end-of-run report of the trigger generator: pulses, MCU resets, sequence gaps and the
// drift of its clock, the link's problem if it failed, and per triggered camera the frames that
// got their pulse and those that did not; lines starting with `prefix`. Nothing without one.
void ReportTrigger(const CaptureSources& sources, const std::string& prefix, std::ostream& out);

// The end-of-run report of live V4L2 devices: frames, sequence drops, erroneous buffers, device
// losses and reconnections, one line per camera starting with `prefix`.
void ReportCaptureStats(const std::vector<capture::V4l2Device*>& devices, const std::string& prefix,
                        std::ostream& out);

}  // namespace rigcal::pipeline
