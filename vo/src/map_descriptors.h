// SPDX-License-Identifier: Apache-2.0
#pragma once
// Binary descriptors for relocalisation: ORB (OpenCV's rBRIEF on a 31-pixel patch) with the
// orientation held at 0. Between a tracking loss and its relocalisation (a second or two) the
// camera's roll changes little, and upright descriptors tell more features apart than
// rotation-invariant ones. Landmarks get a descriptor at every keyframe that observes them;
// the features of a frame to relocalise are detected on an image pyramid (scale 1.2), so a
// landmark seen up to ~2x closer than at its keyframes still matches.

#include <array>
#include <cstdint>
#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <vector>

namespace rigcal::vo {

using Descriptor = std::array<uint8_t, 32>;

int HammingDistance(const Descriptor& a, const Descriptor& b);

struct OrbFeature {
  cv::Point2f px;  // full-resolution image position
  int octave = 0;  // pyramid level it was detected at (scale 1.2^octave)
  Descriptor descriptor{};
};

class OrbDescriber {
 public:
  // `max_features`: at most this many features per Detect call.
  explicit OrbDescriber(int max_features);

  // Upright descriptors of CV_8UC1 `grey` at `points` (full resolution). (*ok)[i] = 0 where
  // there is none (the 31-pixel patch leaves the image).
  void Describe(const cv::Mat& grey, const std::vector<cv::Point2f>& points,
                std::vector<Descriptor>* descriptors, std::vector<char>* ok) const;
  // The strongest features of `grey` over the pyramid, with upright descriptors.
  std::vector<OrbFeature> Detect(const cv::Mat& grey) const;

 private:
  cv::Ptr<cv::ORB> orb_;
};

struct DescriptorMatch {
  int query = -1;     // index into the query descriptors
  int landmark = -1;  // the landmark id
  int distance = 0;   // Hamming distance, bits
};

// A map descriptor: the landmark it describes and its descriptor.
struct LandmarkDescriptor {
  int landmark = -1;
  Descriptor descriptor{};
};

// For every query descriptor, the landmark with the nearest descriptor, kept when its distance
// is at most `max_bits` and below `ratio` times the nearest distance of any other landmark
// (an ambiguous feature is no match). Brute force: O(queries x map descriptors).
std::vector<DescriptorMatch> MatchToLandmarks(const std::vector<Descriptor>& query,
                                              const std::vector<LandmarkDescriptor>& map,
                                              int max_bits, double ratio);

}  // namespace rigcal::vo
