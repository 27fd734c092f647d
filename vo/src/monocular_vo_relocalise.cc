// SPDX-License-Identifier: Apache-2.0
// MonocularVo relocalisation: after a tracking loss the frame's ORB features are matched with
// the descriptors the landmarks got at keyframes, P3P RANSAC on bearings finds the pose, and
// tracking resumes in the same scale segment. After relocalisation_timeout_s of failures the
// map is dropped and a new initialisation opens a new segment.

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <vector>

#include "monocular_vo_impl.h"

namespace rigcal::vo {
namespace {

// Per-axis σ of an ORB feature at pyramid level `octave`: its corner is found on a grid of
// 1.2^octave pixels (uniform quantisation, s / √12), on top of the tracks' measured noise.
double FeatureSigmaPx(double track_sigma_px, int octave) {
  const double cell = std::pow(1.2, octave);
  return std::sqrt(track_sigma_px * track_sigma_px + cell * cell / 12.0);
}

}  // namespace

bool MonocularVo::Impl::PlaceOnLandmarkPatch(const cv::Mat& grey, const Landmark& landmark,
                                             int octave, Track* track) const {
  if (landmark.patch == nullptr) return false;
  AffinePatchOptions affine;
  affine.half_size = options_.affine_half_size;
  Eigen::Matrix2d warp = landmark.warp;
  Eigen::Vector2d centre(track->px.x, track->px.y);
  if (!AlignPatch(*landmark.patch, grey, affine, &warp, &centre)) return false;
  // The alignment must stay on the feature found: within its detection cell.
  if ((centre - Eigen::Vector2d(track->px.x, track->px.y)).norm() > 2.0 * std::pow(1.2, octave)) {
    return false;
  }
  track->px = cv::Point2f(static_cast<float>(centre.x()), static_cast<float>(centre.y()));
  track->patch = landmark.patch;
  track->warp = warp;
  return true;
}

std::vector<LandmarkDescriptor> MonocularVo::Impl::MapDescriptors() const {
  std::vector<LandmarkDescriptor> out;
  for (const auto& [id, lm] : map_.landmarks()) {
    for (const Descriptor& d : lm.descriptors) out.push_back({id, d});
  }
  return out;
}

void MonocularVo::Impl::GiveUpSegment(int64_t t_ns, const cv::Mat& grey, VoResult* result) {
  const double lost_s = static_cast<double>(t_ns - lost_since_ns_) * 1e-9;
  log_->warn(
      "camera {}: relocalisation failed for {:.2f} s (limit {:.2f} s): segment {} ends, the next "
      "initialisation opens a new one",
      camera_index_, lost_s, options_.relocalisation_timeout_s, segment_);
  map_.Clear();
  tracks_.clear();
  lost_since_ns_ = -1;
  has_reference_ = false;
  state_ = VoState::kInitialising;
  Initialise(t_ns, grey, result);
  result->message = "relocalisation failed for " + std::to_string(lost_s) + " s; " +
                    (result->message.empty() ? "initialising" : result->message);
}

void MonocularVo::Impl::ResumeTracking(int64_t t_ns, const cv::Mat& grey,
                                       const std::vector<OrbFeature>& features,
                                       const std::vector<DescriptorMatch>& matches,
                                       const std::vector<char>& inliers, CameraPoseRC pose,
                                       VoResult* result) {
  // One track per landmark: the inlier feature nearest in descriptor distance.
  std::map<int, const DescriptorMatch*> best;
  for (size_t k = 0; k < matches.size(); ++k) {
    if (!inliers[k]) continue;
    auto [it, added] = best.emplace(matches[k].landmark, &matches[k]);
    if (!added && matches[k].distance < it->second->distance) it->second = &matches[k];
  }
  tracks_.clear();
  for (const auto& [landmark, match] : best) {
    const OrbFeature& feature = features[static_cast<size_t>(match->query)];
    Track t;
    t.px = feature.px;
    t.landmark = landmark;
    if (!PlaceOnLandmarkPatch(grey, *map_.landmark(landmark), feature.octave, &t)) {
      t.patch = MakePatch(grey, t.px);
    }
    if (!InMask(t.px) || !Unproject(t.px, &t.bearing)) continue;
    tracks_.push_back(t);
  }
  // The pose again from the placed tracks.
  const MapMatches placed = CollectMapMatches();
  CameraPoseRC refined = pose;
  if (RefineAbsolutePose(placed.bearing, placed.point, {}, HuberRad(), 10, &refined) &&
      refined.R_world_from_cam.allFinite() && refined.C.allFinite()) {
    pose = refined;
  }
  const double gap_s = static_cast<double>(t_ns - pose_t_ns_) * 1e-9;
  pose_ = pose;
  pose_t_ns_ = t_ns;
  has_velocity_ = false;
  ResetRollingShutterPoses();
  RecordRollingShutterPose(t_ns, pose_);
  state_ = VoState::kTracking;
  lost_since_ns_ = -1;
  ++relocalisations_;
  CreateKeyframe(t_ns, grey);
  result->state = state_;
  result->keyframe = true;
  result->relocalised = true;
  result->inliers = static_cast<int>(best.size());
  result->message.clear();
  result->pose = MakePose(t_ns, pose_, std::min(1.0, static_cast<double>(best.size()) / 100.0));
  log_->info("camera {}: relocalised in segment {} after {:.2f} s ({} landmarks, {} matches)",
             camera_index_, segment_, gap_s, best.size(), matches.size());
}

void MonocularVo::Impl::Relocalise(int64_t t_ns, const cv::Mat& grey, VoResult* result) {
  result->state = state_;
  if (lost_since_ns_ < 0) lost_since_ns_ = t_ns;
  if (static_cast<double>(t_ns - lost_since_ns_) > options_.relocalisation_timeout_s * 1e9) {
    GiveUpSegment(t_ns, grey, result);
    return;
  }
  auto fail = [&](const std::string& why) {
    result->message += (result->message.empty() ? "" : "; ") + ("relocalisation: " + why);
  };
  if (grey.empty()) return fail("no image");
  const std::vector<OrbFeature> features = describer_->Detect(grey);
  std::vector<Descriptor> query;
  query.reserve(features.size());
  for (const OrbFeature& f : features) query.push_back(f.descriptor);
  const std::vector<DescriptorMatch> matches = MatchToLandmarks(
      query, MapDescriptors(), options_.relocalisation_max_bits, options_.relocalisation_ratio);
  if (static_cast<int>(matches.size()) < options_.relocalisation_min_inliers) {
    return fail(std::to_string(matches.size()) + " descriptor matches");
  }
  std::vector<Eigen::Vector3d> f, X;
  std::vector<DescriptorMatch> usable;
  int coarsest = 0;
  for (const DescriptorMatch& m : matches) {
    Eigen::Vector3d bearing;
    const OrbFeature& feature = features[static_cast<size_t>(m.query)];
    if (!Unproject(feature.px, &bearing)) continue;
    f.push_back(bearing);
    X.push_back(map_.landmark(m.landmark)->point);
    usable.push_back(m);
    coarsest = std::max(coarsest, feature.octave);
  }
  PnpRansacOptions ransac;
  ransac.max_angle_rad =
      options_.inlier_sigmas * FeatureSigmaPx(noise_.sigma_px(), coarsest) * pixel_angle_;
  ransac.max_iterations = 4 * options_.ransac_max_iterations;  // many wrong matches
  ransac.confidence = options_.ransac_confidence;
  ransac.min_inliers = options_.relocalisation_min_inliers;
  PnpRansacResult pnp = EstimateAbsolutePose(f, X, ransac, nullptr, &rng_);
  if (!pnp.success) return fail("PnP found no pose from " + std::to_string(f.size()) + " matches");
  CameraPoseRC pose = pnp.pose;
  if (!RefineAbsolutePose(f, X, pnp.inliers, HuberRad(), 10, &pose)) return fail("degenerate");
  std::vector<char> inliers(f.size());
  int count = 0;
  for (size_t k = 0; k < f.size(); ++k) {
    inliers[k] = AngularResidual(pose, f[k], X[k]) <= ransac.max_angle_rad;
    count += inliers[k];
  }
  if (count < options_.relocalisation_min_inliers) {
    return fail(std::to_string(count) + " inliers of " + std::to_string(f.size()) + " matches");
  }
  ResumeTracking(t_ns, grey, features, usable, inliers, pose, result);
}

}  // namespace rigcal::vo
