// SPDX-License-Identifier: Apache-2.0
// The complete Kalibr camchain: intrinsics of every camera and the chain of extrinsics.
#include "rigcal/io/kalibr_camchain.h"

#include <yaml-cpp/yaml.h>

#include <sstream>

#include "rigcal/io/atomic_file.h"

namespace rigcal::io {
namespace {

using camera::CameraSpec;

Eigen::Matrix4d CamFromCam0(const Similarity& cam0_from_cam) {
  const Eigen::Matrix3d R = cam0_from_cam.q.toRotationMatrix();
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = R.transpose();
  T.topRightCorner<3, 1>() = -R.transpose() * cam0_from_cam.C;
  return T;
}

void EmitNumbers(YAML::Emitter& out, const double* values, int n) {
  out << YAML::Flow << YAML::BeginSeq;
  for (int i = 0; i < n; ++i) out << values[i];
  out << YAML::EndSeq;
}

// camera_model, intrinsics, distortion_model, distortion_coeffs, resolution, rostopic.
void EmitIntrinsics(YAML::Emitter& out, const CamchainEntry& camera) {
  const CameraSpec& spec = camera.spec;
  const std::optional<double>& xi = camera.omni_xi;
  out << YAML::Key << "camera_model" << YAML::Value << (xi ? "omni" : "pinhole");
  out << YAML::Key << "intrinsics" << YAML::Value;
  if (xi) {
    const double omni[5] = {*xi, spec.intrinsics[0], spec.intrinsics[1], spec.intrinsics[2],
                            spec.intrinsics[3]};
    EmitNumbers(out, omni, 5);
  } else {
    EmitNumbers(out, spec.intrinsics.data(), 4);
  }
  out << YAML::Key << "distortion_model" << YAML::Value
      << (spec.model == CameraSpec::Model::kFisheye ? "equidistant"
          : spec.distortion.empty()                 ? "none"
                                                    : "radtan");
  out << YAML::Key << "distortion_coeffs" << YAML::Value;
  EmitNumbers(out, spec.distortion.data(), static_cast<int>(spec.distortion.size()));
  out << YAML::Key << "resolution" << YAML::Value << YAML::Flow << YAML::BeginSeq << spec.width
      << spec.height << YAML::EndSeq;
  out << YAML::Key << "rostopic" << YAML::Value << "/" + spec.name + "/image_raw";
}

}  // namespace

Status WriteKalibrCamchain(const std::string& path, const std::vector<CamchainEntry>& cameras,
                           const std::string& comment) {
  const std::string where = "cannot write camchain '" + path + "': ";
  if (cameras.empty()) return Error{where + "no camera"};
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << YAML::BeginMap;
  Eigen::Matrix4d previous_from_cam0 = Eigen::Matrix4d::Identity();
  for (size_t n = 0; n < cameras.size(); ++n) {
    const CameraSpec& spec = cameras[n].spec;
    if (cameras[n].intrinsics_known && spec.model == CameraSpec::Model::kScaramuzza) {
      return Error{where + spec.name + ": the scaramuzza model has no Kalibr equivalent here"};
    }
    if (cameras[n].intrinsics_known && spec.distortion.size() != 4 && !spec.distortion.empty()) {
      return Error{where + spec.name + ": Kalibr's " +
                   (spec.model == CameraSpec::Model::kFisheye ? "equidistant" : "radtan") +
                   " model has 4 distortion coefficients, the camera has " +
                   std::to_string(spec.distortion.size())};
    }
    out << YAML::Key << "cam" + std::to_string(n) << YAML::Value << YAML::BeginMap;
    if (n > 0) {
      if (!cameras[n].cam0_from_cam) {
        return Error{where + spec.name + ": no extrinsics (pose in the first camera's frame)"};
      }
      const Eigen::Matrix4d cam_from_cam0 = CamFromCam0(*cameras[n].cam0_from_cam);
      const Eigen::Matrix4d cn_from_cnm1 = cam_from_cam0 * previous_from_cam0.inverse();
      out << YAML::Key << "T_cn_cnm1" << YAML::Value << YAML::BeginSeq;
      for (int r = 0; r < 4; ++r) {
        const double row[4] = {cn_from_cnm1(r, 0), cn_from_cnm1(r, 1), cn_from_cnm1(r, 2),
                               cn_from_cnm1(r, 3)};
        EmitNumbers(out, row, 4);
      }
      out << YAML::EndSeq;
      previous_from_cam0 = cam_from_cam0;
    }
    if (!cameras[n].translation_unit.empty()) {
      out << YAML::Key << "rigcal_translation_unit" << YAML::Value << cameras[n].translation_unit;
    }
    if (cameras[n].intrinsics_known) EmitIntrinsics(out, cameras[n]);
    out << YAML::Key << "rigcal_name" << YAML::Value << spec.name;
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  std::string text;
  std::istringstream lines(comment);
  for (std::string line; std::getline(lines, line);) text += "# " + line + "\n";
  text += out.c_str();
  text += "\n";
  return WriteFileAtomically(path, text);
}

}  // namespace rigcal::io
