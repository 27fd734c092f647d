// SPDX-License-Identifier: Apache-2.0
#include "rigcal/base/format.h"

#include <array>
#include <charconv>
#include <cmath>
#include <cstdio>

namespace rigcal {

std::string ShortestText(double v) {
  std::array<char, 32> buffer{};
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), v);
  return std::string(buffer.data(), result.ptr);
}

std::string SignificantText(double v, int digits) {
  std::array<char, 64> buffer{};
  std::snprintf(buffer.data(), buffer.size(), "%.*g", digits, v);
  return buffer.data();
}

std::string FixedText(double v, int decimals) {
  // Large enough for any double with up to 40 decimals ("%f" of 1e308 has 309 digits).
  std::array<char, 384> buffer{};
  std::snprintf(buffer.data(), buffer.size(), "%.*f", decimals, v);
  return buffer.data();
}

std::string SigmaText(double sigma, int digits) {
  return std::isfinite(sigma) ? SignificantText(sigma, digits) : "unknown";
}

std::string SigmaVectorText(const Eigen::Vector3d& sigma, int digits) {
  std::string text = "[";  // piece by piece, as VectorText
  text += SigmaText(sigma.x(), digits);
  text += ", ";
  text += SigmaText(sigma.y(), digits);
  text += ", ";
  text += SigmaText(sigma.z(), digits);
  text += "]";
  return text;
}

std::string VectorText(const Eigen::Vector3d& v, int decimals) {
  std::string text = "[";  // appended piece by piece: GCC 12 warns (-Wrestrict) on "[" + ...
  text += FixedText(v.x(), decimals);
  text += ", ";
  text += FixedText(v.y(), decimals);
  text += ", ";
  text += FixedText(v.z(), decimals);
  text += "]";
  return text;
}

}  // namespace rigcal
