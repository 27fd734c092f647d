// SPDX-License-Identifier: Apache-2.0
#pragma once
// The rig configuration file (schema: docs/config.md): cameras, nominal mounting, estimator,
// sync, publishing and state options, and the capture source of `rigcal run`. This is the one
// place where a rig config YAML is read; every module gets plain option structs.

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/calib/online_calibrator.h"
#include "rigcal/camera/camera_spec.h"
#include "rigcal/capture/image_folder_device.h"
#include "rigcal/capture/libcamera_device.h"
#include "rigcal/capture/v4l2_options.h"
#include "rigcal/sim/simulated_rig.h"
#include "rigcal/trigger/live_trigger_timeline.h"

namespace rigcal::io {

struct PublishOptions {
  double extrinsics_rate_hz = 2.0;  // RIGCAL_EXTRINSICS messages per second, in (0, 1000]
  double status_rate_hz = 1.0;      // RIGCAL_STATUS messages per second, in (0, 1000]
};

struct StateOptions {
  std::string path;             // empty: no state file
  double save_interval_s = 30;  // > 0; the state is also saved on a clean stop
};

struct CameraConfig {
  std::string name;
  // Intrinsics; absent for a camera entry that has only a name (and nominal/truth/device),
  // which is enough for `rigcal calib` where VO runs elsewhere.
  std::optional<camera::CameraSpec> spec;
  std::optional<Similarity> nominal;  // mounting from CAD, master frame (slaves only)
  std::optional<Similarity> truth;    // simulated sources: true mounting, master frame
  std::string device;                 // capture device path (real sources), may be empty
  // `metric: true`: this camera's poses (RIGCAL_POSE_<name>) are metric (wheel odometry, INS as
  // the master); master only. Sets online.estimator.master_metric.
  bool metric = false;
};

struct RigConfig {
  std::string path;  // the file it was read from
  std::string name;
  // Camera index order: the master first, then the other cameras in file order. This is the
  // camera id of CameraPose and the order of OnlineOptions and SimulatedRigSpec.
  std::vector<CameraConfig> cameras;
  OnlineOptions online;  // estimator options incl. nominal per slave; sync.num_cameras set
  PublishOptions publish;
  StateOptions state;
  std::optional<sim::SimulatedRigSpec> simulated_source;  // `source: {type: simulated}`
  // `source: {type: image_folders}`: one folder per camera (its `device`, resolved against the
  // config file's directory; an ASL camera folder or a plain folder of images), camera index
  // order, and its options (`source:` keys rate_hz, timestamps, overridden by the camera's
  // `capture:`).
  std::vector<std::string> image_folders;
  std::vector<capture::ImageFolderOptions> image_folder_options;
  // `source: {type: v4l2}`: one device per camera (camera index order): the source's keys,
  // the camera's `device`, its resolution and its `capture:` keys.
  std::vector<capture::V4l2Options> v4l2_devices;
  // `source: {type: libcamera}`: the same with the camera's `device` as the libcamera camera.
  std::vector<capture::LibcameraOptions> libcamera_devices;
  // `trigger:`: a trigger generator on a serial port, with one line per line named by the
  // cameras' `trigger:` entries (docs/config.md "Hardware trigger"); unset without one.
  std::optional<trigger::LiveTriggerOptions> trigger;
  // With `trigger:`, camera index order: how each camera hangs on the generator (its line, that
  // line's phase offset, where its source stamps a frame relative to the exposure centre);
  // nullopt for a camera without a `trigger:` entry (free-running).
  std::vector<std::optional<trigger::CameraTriggerSpec>> camera_triggers;

  // Lines (1-based) of the keys whose values are checked only against this computer, for
  // errors that name them like the loader's: "cameras[<i>].device", "trigger.port". A config
  // built in code has none.
  std::map<std::string, int> key_lines;

  std::vector<std::string> CameraNames() const;
  const std::string& master() const { return cameras.front().name; }
  // "<path>:<line>: " of a key of key_lines, "<path>: " when its line is not known.
  std::string Where(const std::string& key) const;
};

// Reads and checks a rig config. Errors read "<path>:<line>: <key>: <what>" (unknown keys,
// wrong types, out-of-range values, unknown master, duplicate camera names, a nominal on the
// master, a simulated source with cameras lacking intrinsics or truth, ...).
Expected<RigConfig> LoadRigConfig(const std::string& path);

// Writes a rig config that LoadRigConfig reads back: `rig: {name, master: cameras[0].name}` and
// per camera its name and, when it has a spec, model, resolution, the model's parameters
// (intrinsics and distortion; scaramuzza: poly, inverse_poly when given, center, affine) and
// max_field_angle_deg when not automatic, with 17 significant digits. `comment` (may be empty,
// may have several lines) goes first as "# " lines. Nominal, truth, device and the other
// sections are not written. Atomic. Errors: no camera, or the write failing (naming the path).
[[nodiscard]] Status WriteRigConfig(const std::string& path, const std::string& rig_name,
                                    const std::vector<CameraConfig>& cameras,
                                    const std::string& comment);

}  // namespace rigcal::io
