// SPDX-License-Identifier: Apache-2.0
#include "map_descriptors.h"

#include <cstring>
#include <limits>

namespace rigcal::vo {
namespace {

constexpr int kPatchSize = 31;
// Features are neither detected nor described closer to the border than the upright patch
// reaches (15 pixels) plus the smoothing ORB applies first.
constexpr int kEdge = 19;
constexpr float kScaleFactor = 1.2f;
constexpr int kLevels = 4;

// Descriptors of `keypoints` (their angle set to 0) into `out`; keypoints ORB drops (too near
// the border) are dropped from `keypoints` as well (class_id keeps the caller's index).
void ComputeUpright(const cv::Ptr<cv::ORB>& orb, const cv::Mat& grey,
                    std::vector<cv::KeyPoint>* keypoints, cv::Mat* out) {
  for (cv::KeyPoint& k : *keypoints) k.angle = 0.f;
  orb->compute(grey, *keypoints, *out);
}

Descriptor RowToDescriptor(const cv::Mat& rows, int row) {
  Descriptor d{};
  std::memcpy(d.data(), rows.ptr<uint8_t>(row), d.size());
  return d;
}

}  // namespace

int HammingDistance(const Descriptor& a, const Descriptor& b) {
  int bits = 0;
  for (size_t i = 0; i < a.size(); i += 8) {
    uint64_t x = 0, y = 0;
    std::memcpy(&x, a.data() + i, 8);
    std::memcpy(&y, b.data() + i, 8);
    bits += __builtin_popcountll(x ^ y);
  }
  return bits;
}

OrbDescriber::OrbDescriber(int max_features)
    : orb_(cv::ORB::create(max_features, kScaleFactor, kLevels, kEdge, 0, 2, cv::ORB::HARRIS_SCORE,
                           kPatchSize)) {}

void OrbDescriber::Describe(const cv::Mat& grey, const std::vector<cv::Point2f>& points,
                            std::vector<Descriptor>* descriptors, std::vector<char>* ok) const {
  descriptors->assign(points.size(), Descriptor{});
  ok->assign(points.size(), 0);
  std::vector<cv::KeyPoint> keypoints;
  keypoints.reserve(points.size());
  for (size_t i = 0; i < points.size(); ++i) {
    keypoints.emplace_back(points[i], static_cast<float>(kPatchSize), 0.f, 0.f, 0,
                           static_cast<int>(i));
  }
  cv::Mat rows;
  ComputeUpright(orb_, grey, &keypoints, &rows);
  for (int r = 0; r < static_cast<int>(keypoints.size()) && r < rows.rows; ++r) {
    const auto i = static_cast<size_t>(keypoints[r].class_id);
    (*descriptors)[i] = RowToDescriptor(rows, r);
    (*ok)[i] = 1;
  }
}

std::vector<OrbFeature> OrbDescriber::Detect(const cv::Mat& grey) const {
  std::vector<cv::KeyPoint> keypoints;
  orb_->detect(grey, keypoints);
  for (size_t i = 0; i < keypoints.size(); ++i) keypoints[i].class_id = static_cast<int>(i);
  cv::Mat rows;
  ComputeUpright(orb_, grey, &keypoints, &rows);
  std::vector<OrbFeature> features;
  for (int r = 0; r < static_cast<int>(keypoints.size()) && r < rows.rows; ++r) {
    OrbFeature f;
    f.px = keypoints[r].pt;
    f.octave = keypoints[r].octave;
    f.descriptor = RowToDescriptor(rows, r);
    features.push_back(f);
  }
  return features;
}

std::vector<DescriptorMatch> MatchToLandmarks(const std::vector<Descriptor>& query,
                                              const std::vector<LandmarkDescriptor>& map,
                                              int max_bits, double ratio) {
  std::vector<DescriptorMatch> matches;
  for (int q = 0; q < static_cast<int>(query.size()); ++q) {
    int best = std::numeric_limits<int>::max(), second = best, best_landmark = -1;
    for (const LandmarkDescriptor& m : map) {
      const int d = HammingDistance(query[q], m.descriptor);
      if (d < best) {
        if (m.landmark != best_landmark) second = best;
        best = d;
        best_landmark = m.landmark;
      } else if (d < second && m.landmark != best_landmark) {
        second = d;
      }
    }
    if (best_landmark < 0 || best > max_bits) continue;
    if (second < std::numeric_limits<int>::max() && best >= ratio * second) continue;
    matches.push_back({q, best_landmark, best});
  }
  return matches;
}

}  // namespace rigcal::vo
