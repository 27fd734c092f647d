// SPDX-License-Identifier: Apache-2.0
// Calibrates a synthetic two-camera drive with the installed rigcal::calib, checks VO options
// (rigcal::vo), makes a Frame (rigcal::capture) and encodes an LCM pose message
// (rigcal::lcmtypes). Exit 0 when the estimate matches the truth, 1 otherwise.
#include <cmath>
#include <cstdio>
#include <vector>

#include "rigcal/calib/rig_calibrator.h"
#include "rigcal/calib/synthetic.h"
#include "rigcal/camera_pose_t.hpp"
#include "rigcal/capture/frame.h"
#include "rigcal/vo/monocular_vo.h"

int main() {
  rigcal::Similarity rig;
  rig.q = Eigen::Quaterniond(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()));
  rig.C = Eigen::Vector3d(0.3, -0.1, 0.2);
  rig.scale = 2.0;
  rigcal::DriveOptions drive;
  drive.num_frames = 200;
  rigcal::SyntheticDrive data = rigcal::GenerateDrive({"cam0", "cam1"}, {rig}, drive);
  rigcal::RigCalibration result =
      rigcal::CalibrateRig(data.recording, rigcal::CalibrationOptions{});
  if (result.slaves.size() != 1) return 1;
  const rigcal::Similarity& estimate = result.slaves[0].estimate;
  const double rot_err_rad = estimate.q.angularDistance(rig.q);
  const double pos_err = (estimate.C - rig.C).norm();
  const double scale_err = estimate.scale / rig.scale - 1.0;
  std::printf("consumer: rotation error %.4f deg, position error %.4f, scale error %.4f\n",
              rot_err_rad * 180.0 / 3.14159265358979, pos_err, scale_err);

  rigcal::capture::Frame frame;
  frame.image = cv::Mat::zeros(4, 4, CV_8UC1);
  rigcal::vo::VoOptions vo_options;
  rigcal::camera_pose_t message{};
  std::vector<uint8_t> bytes(message.getEncodedSize());
  const bool encoded = message.encode(bytes.data(), 0, static_cast<int>(bytes.size())) > 0;
  const bool ok = rot_err_rad < 0.01 && pos_err < 0.05 && std::abs(scale_err) < 0.01 &&
                  vo_options.Check().ok() && frame.image.total() == 16 && encoded;
  std::puts(ok ? "consumer: OK" : "consumer: FAILED");
  return ok ? 0 : 1;
}
