// SPDX-License-Identifier: Apache-2.0
// The relocalisation's descriptors: upright ORB describes the same texture the same way after a
// shift of the image (and a small rotation), different features differently, and the matcher
// keeps only unambiguous matches within the distance limit.
#include "../../vo/src/map_descriptors.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <random>

namespace rigcal::vo {
namespace {

cv::Mat Texture(int seed) {
  cv::Mat noise(480, 640, CV_8UC1);
  cv::randu(noise, 0, 255);
  cv::theRNG().state = static_cast<uint64_t>(seed);
  cv::Mat blurred;
  cv::GaussianBlur(noise, blurred, cv::Size(0, 0), 2.0);
  cv::normalize(blurred, blurred, 0, 255, cv::NORM_MINMAX);
  return blurred;
}

TEST(MapDescriptors, SameTextureMatchesAfterAShiftAndASmallRotation) {
  const cv::Mat image = Texture(1);
  const OrbDescriber describer(500);
  const std::vector<cv::Point2f> points = {{200, 150}, {320, 240}, {450, 300}, {100, 400}};
  std::vector<Descriptor> reference;
  std::vector<char> ok;
  describer.Describe(image, points, &reference, &ok);
  for (char o : ok) EXPECT_TRUE(o);
  // The image shifted by (7.3, -4.6) px and turned by 3 degrees about (320, 240).
  const cv::Mat motion = cv::getRotationMatrix2D(cv::Point2f(320, 240), 3.0, 1.0);
  cv::Mat moved_image;
  cv::Mat shifted = motion.clone();
  shifted.at<double>(0, 2) += 7.3;
  shifted.at<double>(1, 2) -= 4.6;
  cv::warpAffine(image, moved_image, shifted, image.size());
  std::vector<cv::Point2f> moved;
  cv::transform(points, moved, shifted);
  std::vector<Descriptor> after;
  describer.Describe(moved_image, moved, &after, &ok);
  // Independent random bits differ in half of 256; the same point in far fewer.
  for (size_t i = 0; i < points.size(); ++i) {
    EXPECT_LT(HammingDistance(reference[i], after[i]), 50) << i;
    for (size_t j = 0; j < points.size(); ++j) {
      if (j != i) {
        EXPECT_GT(HammingDistance(reference[i], after[j]), 80) << i << " " << j;
      }
    }
  }
  // A point whose patch leaves the image has no descriptor.
  describer.Describe(image, {cv::Point2f(3, 3)}, &after, &ok);
  EXPECT_FALSE(ok[0]);
}

TEST(MapDescriptors, MatcherKeepsUnambiguousMatchesWithinTheLimit) {
  std::mt19937 rng(2);
  std::uniform_int_distribution<int> byte(0, 255);
  auto random_descriptor = [&]() {
    Descriptor d{};
    for (auto& b : d) b = static_cast<uint8_t>(byte(rng));
    return d;
  };
  auto flip = [](Descriptor d, int bits) {  // the first `bits` bits
    for (int i = 0; i < bits; ++i)
      d[static_cast<size_t>(i / 8)] ^= static_cast<uint8_t>(1u << (i % 8));
    return d;
  };
  const Descriptor a = random_descriptor(), b = random_descriptor();
  // Landmark 7 has two descriptors; landmark 8 one.
  const std::vector<LandmarkDescriptor> map = {{7, a}, {7, flip(a, 30)}, {8, b}};
  const std::vector<Descriptor> query = {
      flip(a, 10),          // landmark 7 (its two descriptors do not compete)
      flip(b, 70),          // beyond 64 bits
      random_descriptor(),  // nothing near
  };
  const std::vector<DescriptorMatch> matches = MatchToLandmarks(query, map, 64, 0.8);
  ASSERT_EQ(matches.size(), 1u);
  EXPECT_EQ(matches[0].query, 0);
  EXPECT_EQ(matches[0].landmark, 7);
  EXPECT_EQ(matches[0].distance, 10);
  // Ambiguous: as near to two landmarks.
  const std::vector<LandmarkDescriptor> twins = {{1, a}, {2, flip(a, 2)}};
  EXPECT_TRUE(MatchToLandmarks({flip(a, 1)}, twins, 64, 0.8).empty());
}

}  // namespace
}  // namespace rigcal::vo
