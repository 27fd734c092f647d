// SPDX-License-Identifier: Apache-2.0
#include "support/real_mono_sequence.h"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <regex>
#include <sstream>

#include "rigcal/camera/camera_spec.h"
#include "rigcal/capture/image_folder_device.h"

namespace rigcal::support {
namespace {

namespace fs = std::filesystem;

Expected<std::string> ReadText(const std::string& path) {
  std::ifstream in(path);
  if (!in) return Error{"cannot open " + path};
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The number inside <tag>...</tag> of a ViSP XML file.
std::optional<double> XmlNumber(const std::string& xml, const std::string& tag) {
  const std::regex pattern("<" + tag + ">\\s*([-+0-9.eE]+)\\s*</" + tag + ">");
  std::smatch match;
  if (!std::regex_search(xml, match, pattern)) return std::nullopt;
  return std::stod(match[1].str());
}

Expected<std::shared_ptr<const camera::CameraModel>> Pinhole640x480(double px, double py, double u0,
                                                                    double v0) {
  camera::CameraSpec spec;
  spec.model = camera::CameraSpec::Model::kPinhole;
  spec.width = 640;
  spec.height = 480;
  spec.intrinsics = {px, py, u0, v0};
  auto model = camera::MakeCameraModel(spec);
  if (!model) return Error{model.error()};
  return std::shared_ptr<const camera::CameraModel>(std::move(*model));
}

// Intrinsics: cam.json (visp_rbt_sequence) or cube.xml's <camera> (visp_mbt_cube).
Expected<std::shared_ptr<const camera::CameraModel>> ReadIntrinsics(const std::string& folder) {
  if (fs::exists(folder + "/cam.json")) {
    auto text = ReadText(folder + "/cam.json");
    if (!text) return Error{text.error()};
    const auto j = nlohmann::json::parse(*text, nullptr, false);
    if (j.is_discarded()) return Error{folder + "/cam.json: not JSON"};
    return Pinhole640x480(j.value("px", 0.0), j.value("py", 0.0), j.value("u0", 0.0),
                          j.value("v0", 0.0));
  }
  auto text = ReadText(folder + "/cube.xml");
  if (!text) return Error{text.error()};
  const auto px = XmlNumber(*text, "px"), py = XmlNumber(*text, "py");
  const auto u0 = XmlNumber(*text, "u0"), v0 = XmlNumber(*text, "v0");
  if (!px || !py || !u0 || !v0) return Error{folder + "/cube.xml: no <camera> px py u0 v0"};
  return Pinhole640x480(*px, *py, *u0, *v0);
}

Expected<Eigen::Matrix4d> Matrix4(const nlohmann::json& rows) {
  if (!rows.is_array() || rows.size() != 4) return Error{"expected a 4x4 matrix"};
  Eigen::Matrix4d m;
  for (int r = 0; r < 4; ++r) {
    if (!rows[r].is_array() || rows[r].size() != 4) return Error{"expected a 4x4 matrix"};
    for (int c = 0; c < 4; ++c) m(r, c) = rows[r][c].get<double>();
  }
  return m;
}

// apriltag_data.json: "grid" (one cMo per frame) and "detections" (per frame, per tag id).
Status ReadTagPoses(const std::string& path, RealMonoSequence* sequence) {
  auto text = ReadText(path);
  if (!text) return Error{text.error()};
  const auto j = nlohmann::json::parse(*text, nullptr, false);
  if (j.is_discarded() || !j.contains("grid") || !j.contains("detections")) {
    return Error{path + ": no grid or detections"};
  }
  for (const auto& cmo : j["grid"]) {
    auto m = Matrix4(cmo);
    if (!m) return Error{path + ": grid: " + m.error()};
    sequence->grid_from_cam.push_back(PoseFromCameraFromObject(*m));
  }
  sequence->tag_size_m = j.value("tag_size", 0.0);
  for (const auto& frame : j["detections"]) {
    std::map<int, Pose> tags;
    std::map<int, std::array<Eigen::Vector2d, 4>> corners;
    for (const auto& [id, tag] : frame.items()) {
      auto m = Matrix4(tag["cMo"]);
      if (!m) return Error{path + ": detections: " + m.error()};
      tags[std::stoi(id)] = PoseFromCameraFromObject(*m);
      const auto& c = tag["tag_corners"];
      if (!c.is_array() || c.size() != 4) return Error{path + ": detections: 4 corners expected"};
      // The file holds each corner as (row, column).
      for (int k = 0; k < 4; ++k) {
        corners[std::stoi(id)][k] = Eigen::Vector2d(c[k][1].get<double>(), c[k][0].get<double>());
      }
    }
    sequence->tag_from_cam.push_back(std::move(tags));
    sequence->tag_corners_px.push_back(std::move(corners));
  }
  if (sequence->grid_from_cam.size() != sequence->grey.size() ||
      sequence->tag_from_cam.size() != sequence->grey.size()) {
    return Error{path + ": " + std::to_string(sequence->grid_from_cam.size()) + " poses for " +
                 std::to_string(sequence->grey.size()) + " frames"};
  }
  return Status::Ok();
}

}  // namespace

Pose PoseFromCameraFromObject(const Eigen::Matrix4d& cam_from_object) {
  const Eigen::Matrix3d r_cam_from_object = cam_from_object.block<3, 3>(0, 0);
  // Re-orthonormalise (the files hold 16-digit values of a rotation).
  const Eigen::Quaterniond q_cam_from_object = Eigen::Quaterniond(r_cam_from_object).normalized();
  Pose pose;
  pose.q = q_cam_from_object.conjugate();
  pose.C = -(pose.q * cam_from_object.block<3, 1>(0, 3));
  return pose;
}

std::array<Eigen::Vector3d, 4> RealMonoSequence::TagCornersInTag() const {
  const double h = 0.5 * tag_size_m;
  return {Eigen::Vector3d(-h, -h, 0), Eigen::Vector3d(h, -h, 0), Eigen::Vector3d(h, h, 0),
          Eigen::Vector3d(-h, h, 0)};
}

std::vector<double> TagGridResidualsPx(const RealMonoSequence& s) {
  // Each tag corner in the grid frame, averaged over the frames that saw the tag.
  std::map<int, std::array<Eigen::Vector3d, 4>> in_grid;
  std::map<int, int> seen;
  const auto in_tag = s.TagCornersInTag();
  for (size_t f = 0; f < s.tag_from_cam.size(); ++f) {
    for (const auto& [id, tag_from_cam] : s.tag_from_cam[f]) {
      const Pose grid_from_tag = s.grid_from_cam[f] * tag_from_cam.Inverse();
      auto& sum = in_grid.try_emplace(id).first->second;
      if (seen[id]++ == 0) sum.fill(Eigen::Vector3d::Zero());
      for (int k = 0; k < 4; ++k) sum[k] += grid_from_tag.q * in_tag[k] + grid_from_tag.C;
    }
  }
  std::vector<double> rms;
  for (size_t f = 0; f < s.tag_corners_px.size(); ++f) {
    const Pose cam_from_grid = s.grid_from_cam[f].Inverse();
    double sum2 = 0.0;
    int n = 0;
    for (const auto& [id, corners] : s.tag_corners_px[f]) {
      for (int k = 0; k < 4; ++k) {
        const Eigen::Vector3d p = cam_from_grid.q * (in_grid[id][k] / seen[id]) + cam_from_grid.C;
        const auto px = s.camera->Project(p);
        if (!px) continue;
        sum2 += (*px - corners[k]).squaredNorm();
        ++n;
      }
    }
    rms.push_back(n > 0 ? std::sqrt(sum2 / n) : 0.0);
  }
  return rms;
}

std::string RealMonoFolder(const std::string& name) {
  return std::string(RIGCAL_SHARED_DATA_DIR) + "/real_mono/" + name;
}

bool RealMonoAvailable(const std::string& name) {
  std::error_code ec;
  return fs::is_directory(RealMonoFolder(name) + "/images", ec);
}

Expected<RealMonoSequence> LoadRealMono(const std::string& name) {
  RealMonoSequence sequence;
  sequence.name = name;
  const std::string folder = RealMonoFolder(name);
  sequence.folder = folder + "/images";
  auto camera = ReadIntrinsics(folder);
  if (!camera) return Error{camera.error()};
  sequence.camera = *camera;
  auto device = capture::ImageFolderDevice::Open(sequence.folder, name, 0, kRealMonoRateHz);
  if (!device) return Error{device.error()};
  for (;;) {
    auto grabbed = (*device)->Grab();
    if (!grabbed) return Error{grabbed.error()};
    if (!grabbed->has_value()) break;
    sequence.t_ns.push_back((*grabbed)->t_ns);
    sequence.grey.push_back((*grabbed)->image);
  }
  if ((*device)->skipped_count() > 0) return Error{sequence.folder + ": unreadable images"};
  if (fs::exists(folder + "/apriltag_data.json")) {
    if (Status s = ReadTagPoses(folder + "/apriltag_data.json", &sequence); !s.ok()) {
      return Error{s.message()};
    }
  }
  return sequence;
}

}  // namespace rigcal::support
