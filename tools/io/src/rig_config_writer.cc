// SPDX-License-Identifier: Apache-2.0
// WriteRigConfig (rig_config.h): the camera part of a rig config, for configs made by tools
// (`rigcal import`, `rigcal intrinsics`): every camera model, numbers with 17 digits.
#include <iomanip>
#include <sstream>
#include <vector>

#include "rigcal/io/atomic_file.h"
#include "rigcal/io/rig_config.h"

namespace rigcal::io {
namespace {

template <typename Container>
std::string List(const Container& values) {
  std::ostringstream out;
  out << std::setprecision(17) << "[";
  bool first = true;
  for (const auto& v : values) {
    out << (first ? "" : ", ") << v;
    first = false;
  }
  out << "]";
  return out.str();
}

}  // namespace

Status WriteRigConfig(const std::string& path, const std::string& rig_name,
                      const std::vector<CameraConfig>& cameras, const std::string& comment) {
  if (cameras.empty()) return Error{"cannot write '" + path + "': a rig config needs a camera"};
  std::ostringstream out;
  std::istringstream comment_lines(comment);
  for (std::string line; std::getline(comment_lines, line);) out << "# " << line << "\n";
  out << "rig:\n  name: \"" << rig_name << "\"\n  master: \"" << cameras.front().name
      << "\"\n\ncameras:\n";
  for (const CameraConfig& camera : cameras) {
    out << "  - name: \"" << camera.name << "\"\n";
    if (!camera.spec) continue;
    const camera::CameraSpec& spec = *camera.spec;
    out << "    model: " << camera::ModelName(spec.model) << "\n"
        << "    resolution: [" << spec.width << ", " << spec.height << "]\n";
    if (spec.model == camera::CameraSpec::Model::kScaramuzza) {
      out << "    poly: " << List(spec.poly) << "\n";
      if (!spec.inverse_poly.empty()) {
        out << "    inverse_poly: " << List(spec.inverse_poly) << "\n";
      }
      out << "    center: " << List(spec.center) << "\n"
          << "    affine: " << List(spec.affine) << "\n";
    } else {
      out << "    intrinsics: " << List(spec.intrinsics) << "\n";
      if (!spec.distortion.empty()) out << "    distortion: " << List(spec.distortion) << "\n";
    }
    if (spec.max_field_angle_deg != 0.0) {
      std::ostringstream angle;
      angle << std::setprecision(17) << spec.max_field_angle_deg;
      out << "    max_field_angle_deg: " << angle.str() << "\n";
    }
    if (spec.rolling_shutter_s != 0.0) {
      std::ostringstream readout;
      readout << std::setprecision(17) << spec.rolling_shutter_s * 1e3;
      out << "    rolling_shutter_ms: " << readout.str() << "\n";
    }
  }
  return WriteFileAtomically(path, out.str());
}

}  // namespace rigcal::io
