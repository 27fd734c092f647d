// SPDX-License-Identifier: Apache-2.0
// MonocularVo rolling shutter: the motion over a frame's readout and the tracks' bearings moved
// from their rows' times to the frame's stamp (rolling_shutter.h), so that PnP, triangulation
// and the bundle adjustment see a global-shutter frame at the stamp.

#include <algorithm>

#include "monocular_vo_impl.h"
#include "triangulation.h"

namespace rigcal::vo {

void MonocularVo::Impl::SetRollingShutterMotion(const CameraPoseRC& predicted) {
  if (!rolling_shutter_.enabled() || rs_count_ < 2) return;
  constexpr int kSize = kRollingShutterWindow + 1;
  const int oldest = rs_count_ < kSize ? 0 : rs_next_;
  const int newest = (rs_next_ + kSize - 1) % kSize;
  const CameraPoseRC& a = rs_poses_[oldest];
  const CameraPoseRC& b = rs_poses_[newest];
  const Eigen::Matrix3d R_a_from_b = a.R_world_from_cam.transpose() * b.R_world_from_cam;
  const Eigen::Vector3d C_b_in_a = a.R_world_from_cam.transpose() * (b.C - a.C);
  const double dt_s = static_cast<double>(rs_t_ns_[newest] - rs_t_ns_[oldest]) * 1e-9;
  const Eigen::Matrix3d cam_b_from_cam_now =
      b.R_world_from_cam.transpose() * predicted.R_world_from_cam;
  rolling_shutter_.SetMotion(TwistFromMotion(R_a_from_b, C_b_in_a, dt_s, cam_b_from_cam_now));
}

void MonocularVo::Impl::RecordRollingShutterPose(int64_t t_ns, const CameraPoseRC& pose) {
  if (!rolling_shutter_.enabled()) return;
  rs_poses_[rs_next_] = pose;
  rs_t_ns_[rs_next_] = t_ns;
  rs_next_ = (rs_next_ + 1) % (kRollingShutterWindow + 1);
  rs_count_ = std::min(rs_count_ + 1, kRollingShutterWindow + 1);
}

void MonocularVo::Impl::ResetRollingShutterPoses() {
  rs_count_ = 0;
  rs_next_ = 0;
}

InitialViews MonocularVo::Impl::ViewsAtStamps(int64_t t_ns, const InitialViews& views,
                                              const RelativePoseRansacResult& motion) {
  if (!rolling_shutter_.enabled()) return views;
  const Eigen::Matrix3d& r1 = motion.pose.R_1_from_2;  // reference = world
  const Eigen::Vector3d c1 = motion.pose.C2_in_1.normalized();
  const double dt_s = static_cast<double>(t_ns - reference_t_ns_) * 1e-9;
  RollingShutter at_reference = rolling_shutter_;
  at_reference.SetMotion(TwistFromMotion(r1, c1, dt_s, r1.transpose()));
  rolling_shutter_.SetMotion(TwistFromMotion(r1, c1, dt_s, Eigen::Matrix3d::Identity()));
  InitialViews out = views;
  for (size_t i = 0; i < views.reference.size(); ++i) {
    const auto px0 = camera_->Project(views.reference[i]);
    const auto px1 = camera_->Project(views.current[i]);
    if (!px0 || !px1) continue;
    // Each view is the ray from its row's camera centre (rolling_shutter.h); the point where
    // the two rays meet gives the bearings at the stamps. Rays that do not meet (a point too
    // far for the baseline): their directions, as for a point at infinity.
    const Eigen::Vector3d o0 = at_reference.RayOrigin(px0->y());
    const Eigen::Vector3d d0 = at_reference.RayDirection(views.reference[i], px0->y());
    const Eigen::Vector3d o1 = rolling_shutter_.RayOrigin(px1->y());
    const Eigen::Vector3d d1 = rolling_shutter_.RayDirection(views.current[i], px1->y());
    const auto tri = TriangulateMidpoint(o0, d0, c1 + r1 * o1, r1 * d1);
    out.reference[i] = tri ? BearingFromStamp(o0, d0, tri->point) : d0;
    out.current[i] = tri ? BearingFromStamp(o1, d1, r1.transpose() * (tri->point - c1)) : d1;
  }
  return out;
}

void MonocularVo::Impl::CorrectTracksToStamp(const CameraPoseRC& predicted) {
  if (!rolling_shutter_.active()) return;
  const Eigen::Matrix3d cam_from_world = predicted.R_world_from_cam.transpose();
  for (Track& t : tracks_) {
    const Landmark* lm = t.landmark >= 0 ? map_.landmark(t.landmark) : nullptr;
    if (lm == nullptr) {
      SetRayAtStamp(&t);
      continue;
    }
    const double distance =
        rolling_shutter_.DistanceAtRow(cam_from_world * (lm->point - predicted.C), t.px.y);
    t.bearing = rolling_shutter_.ToStamp(t.bearing, t.px.y, distance);
    t.ray_origin.setZero();
  }
}

void MonocularVo::Impl::SetRayAtStamp(Track* track) const {
  if (!rolling_shutter_.active()) return;
  track->ray_origin = rolling_shutter_.RayOrigin(track->px.y);
  track->bearing = rolling_shutter_.RayDirection(track->bearing, track->px.y);
}

std::optional<Eigen::Vector2d> MonocularVo::Impl::ProjectFromStamp(
    const Eigen::Vector3d& p_in_stamp_cam) const {
  std::optional<Eigen::Vector2d> px = camera_->Project(p_in_stamp_cam);
  // The row depends on the time and the time on the row: two fixed-point steps (the readout
  // moves a point by a few pixels, the second step by a fraction of one).
  for (int step = 0; step < 2 && rolling_shutter_.active() && px.has_value(); ++step) {
    px = camera_->Project(rolling_shutter_.FromStamp(p_in_stamp_cam, px->y()));
  }
  return px;
}

}  // namespace rigcal::vo
