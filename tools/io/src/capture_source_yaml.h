// SPDX-License-Identifier: Apache-2.0
#pragma once
// The `source:` sections of live capture devices (docs/config.md "Live sources"):
//   source: {type: v4l2 | libcamera, <defaults for every camera>}   and per camera
//   cameras[i]: {device: <path | bus:<bus info> | card:<card>>, capture: {<overrides>}}
// Keys (source level and `capture:`): pixel_formats, frame_rate_hz, buffers, exposure_us, gain,
// external_trigger, readout_us, controls, reconnect, reconnect_max_backoff_s, frame_timeout_s.
// Errors read "<path>:<line>: <field>: <what>".

#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/capture/image_folder_device.h"
#include "rigcal/capture/libcamera_device.h"
#include "rigcal/capture/v4l2_options.h"
#include "yaml_fields.h"

namespace rigcal::io {

// Reads the keys of `node` (a `source:` map, `type` allowed when `is_source`, or a camera's
// `capture:` map) into `options`; `field` prefixes the names in errors ("source" or
// "cam0.capture").
std::optional<Error> ParseV4l2Keys(const FieldReader& r, const YAML::Node& node,
                                   const std::string& field, bool is_source,
                                   capture::V4l2Options* options);

// The same for `source: {type: libcamera}` and a camera's `capture:` (the camera's `device` is
// the libcamera camera id or model). Keys: role, pixel_formats, buffers, reconnect,
// reconnect_max_backoff_s.
std::optional<Error> ParseLibcameraKeys(const FieldReader& r, const YAML::Node& node,
                                        const std::string& field, bool is_source,
                                        capture::LibcameraOptions* options);

// The same for `source: {type: image_folders}` and a camera's `capture:` (the camera's `device`
// is its folder). Keys: rate_hz, timestamps (a file, resolved against `base_dir` when
// relative); both only matter for plain folders (ImageFolderOptions).
std::optional<Error> ParseImageFolderKeys(const FieldReader& r, const YAML::Node& node,
                                          const std::string& field, bool is_source,
                                          const std::string& base_dir,
                                          capture::ImageFolderOptions* options);

}  // namespace rigcal::io
