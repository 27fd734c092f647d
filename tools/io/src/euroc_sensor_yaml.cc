// SPDX-License-Identifier: Apache-2.0
// Camera intrinsics from a EuRoC / ASL sensor.yaml (camera_files.h).
#include "rigcal/io/camera_files.h"

#include <algorithm>
#include <string>
#include <vector>

#include "config_sections.h"
#include "yaml_fields.h"

namespace rigcal::io {

Expected<camera::CameraSpec> ReadEurocSensorYaml(const std::string& path, const std::string& name) {
  auto root = LoadYaml(path);
  if (!root) return Error{root.error()};
  const FieldReader r(path);
  if (!root->IsMap()) return r.Fail(*root, "(top level)", "expected a EuRoC sensor.yaml map");
  const auto text = [&](const std::string& key) -> Expected<std::string> {
    const YAML::Node node = (*root)[key];
    if (!node) return r.Fail(*root, key, "missing");
    return r.String(node, key);
  };
  auto model = text("camera_model");
  if (!model) return Error{model.error()};
  auto distortion_model = text("distortion_model");
  if (!distortion_model) return Error{distortion_model.error()};

  camera::CameraSpec spec;
  spec.name = name;
  if (*model != "pinhole") {
    return r.Fail((*root)["camera_model"], "camera_model",
                  "'" + *model + "' is not supported (pinhole)");
  }
  if (*distortion_model == "radial-tangential" || *distortion_model == "radtan") {
    spec.model = camera::CameraSpec::Model::kPinhole;
  } else if (*distortion_model == "equidistant") {
    spec.model = camera::CameraSpec::Model::kFisheye;
  } else {
    return r.Fail((*root)["distortion_model"], "distortion_model",
                  "'" + *distortion_model + "' is not supported (radial-tangential, equidistant)");
  }
  auto intrinsics = r.Numbers(*root, "intrinsics", "intrinsics", 4);
  if (!intrinsics) return Error{intrinsics.error()};
  std::copy(intrinsics->begin(), intrinsics->end(), spec.intrinsics.begin());
  auto resolution = r.Numbers(*root, "resolution", "resolution", 2);
  if (!resolution) return Error{resolution.error()};
  spec.width = static_cast<int>((*resolution)[0]);
  spec.height = static_cast<int>((*resolution)[1]);
  if (static_cast<double>(spec.width) != (*resolution)[0] ||
      static_cast<double>(spec.height) != (*resolution)[1]) {
    return r.Fail((*root)["resolution"], "resolution", "expected integer [width, height]");
  }
  if (const YAML::Node node = (*root)["distortion_coefficients"]) {
    auto coefficients = r.NumbersOf(node, "distortion_coefficients", 4);
    if (!coefficients) return Error{coefficients.error()};
    spec.distortion = std::move(*coefficients);
  }
  if (const Status status = spec.Check(); !status.ok()) {
    return Error{path + ": " + status.message()};
  }
  return spec;
}

}  // namespace rigcal::io
