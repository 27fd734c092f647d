// SPDX-License-Identifier: Apache-2.0
// The `source:` section of a rig config (docs/config.md "source"): which devices `rigcal run`
// captures from, or the simulated rig it renders.
#include <filesystem>

#include "capture_source_yaml.h"
#include "config_sections.h"
#include "rig_config_yaml.h"

namespace rigcal::io {
namespace {

std::optional<Error> ParseImageFolders(const FieldReader& r, const YAML::Node& source,
                                       const std::vector<YAML::Node>& entries, RigConfig* config) {
  const std::filesystem::path base = std::filesystem::path(config->path).parent_path();
  capture::ImageFolderOptions defaults;
  if (auto e = ParseImageFolderKeys(r, source, "source", true, base.string(), &defaults)) {
    return *e;
  }
  for (size_t i = 0; i < config->cameras.size(); ++i) {
    const CameraConfig& camera = config->cameras[i];
    if (camera.device.empty()) {
      return r.Fail(entries[i], camera.name + ".device",
                    "missing: image_folders needs the camera's folder (e.g. mav0/cam0)");
    }
    if (!camera.spec) {
      return r.Fail(entries[i], camera.name,
                    "a camera of image_folders needs a model and intrinsics");
    }
    const std::filesystem::path folder(camera.device);
    config->image_folders.push_back(folder.is_absolute() ? folder.string()
                                                         : (base / folder).string());
    capture::ImageFolderOptions options = defaults;
    if (const YAML::Node capture = entries[i]["capture"]) {
      if (auto e = ParseImageFolderKeys(r, capture, camera.name + ".capture", false, base.string(),
                                        &options)) {
        return *e;
      }
    }
    config->image_folder_options.push_back(std::move(options));
  }
  return std::nullopt;
}

std::optional<Error> ParseV4l2Source(const FieldReader& r, const YAML::Node& source,
                                     const std::vector<YAML::Node>& entries, RigConfig* config) {
  capture::V4l2Options defaults;
  if (auto e = ParseV4l2Keys(r, source, "source", true, &defaults)) return *e;
  for (size_t i = 0; i < config->cameras.size(); ++i) {
    const CameraConfig& camera = config->cameras[i];
    if (camera.device.empty()) {
      return r.Fail(entries[i], camera.name + ".device",
                    "missing: a v4l2 camera needs its device (/dev/videoN, "
                    "/dev/v4l/by-id/..., bus:<bus info> or card:<card name>)");
    }
    if (!camera.spec) {
      return r.Fail(entries[i], camera.name, "a v4l2 camera needs a model and intrinsics");
    }
    capture::V4l2Options options = defaults;
    options.device = camera.device;
    options.width = camera.spec->width;
    options.height = camera.spec->height;
    if (const YAML::Node capture = entries[i]["capture"]) {
      if (auto e = ParseV4l2Keys(r, capture, camera.name + ".capture", false, &options)) {
        return *e;
      }
    }
    config->v4l2_devices.push_back(std::move(options));
  }
  return std::nullopt;
}

std::optional<Error> ParseLibcameraSource(const FieldReader& r, const YAML::Node& source,
                                          const std::vector<YAML::Node>& entries,
                                          RigConfig* config) {
  capture::LibcameraOptions defaults;
  if (auto e = ParseLibcameraKeys(r, source, "source", true, &defaults)) return *e;
  for (size_t i = 0; i < config->cameras.size(); ++i) {
    const CameraConfig& camera = config->cameras[i];
    if (camera.device.empty()) {
      return r.Fail(entries[i], camera.name + ".device",
                    "missing: a libcamera camera needs its camera id or model (cam --list)");
    }
    if (!camera.spec) {
      return r.Fail(entries[i], camera.name, "a libcamera camera needs a model and intrinsics");
    }
    capture::LibcameraOptions options = defaults;
    options.camera = camera.device;
    options.width = camera.spec->width;
    options.height = camera.spec->height;
    if (const YAML::Node capture = entries[i]["capture"]) {
      if (auto e = ParseLibcameraKeys(r, capture, camera.name + ".capture", false, &options)) {
        return *e;
      }
    }
    config->libcamera_devices.push_back(std::move(options));
  }
  return std::nullopt;
}

// The simulated rig: the section's own keys, then every camera's model and true mounting.
std::optional<Error> ParseSimulated(const FieldReader& r, const YAML::Node& source,
                                    const std::vector<YAML::Node>& entries, RigConfig* config) {
  auto spec = ParseSimulatedSource(source, config->path);
  if (!spec) return Error{spec.error()};
  for (size_t i = 0; i < config->cameras.size(); ++i) {
    const CameraConfig& camera = config->cameras[i];
    if (!camera.spec) {
      return r.Fail(entries[i], camera.name, "a simulated camera needs a model and intrinsics");
    }
    Similarity truth;  // the master is the rig frame
    if (i > 0) {
      if (!camera.truth) {
        return r.Fail(entries[i], camera.name + ".truth",
                      "missing: a simulated camera needs its true mounting");
      }
      truth = *camera.truth;
    }
    auto model = camera::MakeCameraModel(*camera.spec);
    if (!model) return r.Fail(entries[i], camera.name, model.error());
    spec->names.push_back(camera.name);
    spec->cameras.push_back(std::shared_ptr<const camera::CameraModel>(std::move(*model)));
    Pose master_from_camera;
    master_from_camera.q = truth.q;
    master_from_camera.C = truth.C;
    spec->master_from_camera.push_back(master_from_camera);
  }
  if (const Status status = spec->Check(); !status.ok()) {
    return Error{status.Prefixed(config->path + ": source").message()};
  }
  config->simulated_source = std::move(*spec);
  return std::nullopt;
}

}  // namespace

Expected<std::string> ParseSourceSection(const FieldReader& r, const YAML::Node& root,
                                         const std::vector<YAML::Node>& entries,
                                         RigConfig* config) {
  const YAML::Node source = root["source"];
  if (!source) return std::string();
  if (!source.IsMap() || !source["type"]) return r.Fail(source, "source.type", "missing");
  auto type = r.String(source["type"], "source.type");
  if (!type) return Error{type.error()};
  std::optional<Error> problem;
  if (*type == "image_folders") {
    problem = ParseImageFolders(r, source, entries, config);
  } else if (*type == "v4l2") {
    problem = ParseV4l2Source(r, source, entries, config);
  } else if (*type == "libcamera") {
    problem = ParseLibcameraSource(r, source, entries, config);
  } else {
    const YAML::Node cameras = root["cameras"];
    for (size_t i = 0; i < cameras.size(); ++i) {
      if (cameras[i].IsMap() && cameras[i]["capture"]) {
        return r.Fail(cameras[i]["capture"], "cameras[" + std::to_string(i) + "].capture",
                      "only for a live source (source.type: v4l2 or libcamera)");
      }
    }
    if (*type != "simulated") {
      return r.Fail(source["type"], "source.type",
                    "'" + *type +
                        "' is not supported (supported: simulated, image_folders, v4l2, "
                        "libcamera)");
    }
    problem = ParseSimulated(r, source, entries, config);
  }
  if (problem) return *problem;
  return *type;
}

}  // namespace rigcal::io
