// SPDX-License-Identifier: Apache-2.0
#pragma once
// Numbers as text, the same way everywhere: files (shortest round-trip), messages and tables
// (significant digits, fixed decimals).

#include <Eigen/Core>
#include <string>

namespace rigcal {

// The shortest text that reads back as exactly `v` (std::to_chars): "0.1", "1e-05", "20".
// Non-finite values as to_chars spells them: "nan", "-nan", "inf", "-inf".
std::string ShortestText(double v);

// `v` with `digits` significant digits, as printf's "%.<digits>g" (and an ostream with
// precision(digits), the default being 6): "8.33333", "1e+06", "nan".
std::string SignificantText(double v, int digits);

// `v` with `decimals` digits after the point, as printf's "%.<decimals>f": "0.250".
std::string FixedText(double v, int decimals);

// A standard deviation with `digits` significant digits (SignificantText), or "unknown" when it
// is not finite (not computed, the covariance failed, or undetermined): never "nan" or a 0.
std::string SigmaText(double sigma, int digits);

// "[x, y, z]" with FixedText(., decimals) per coordinate.
std::string VectorText(const Eigen::Vector3d& v, int decimals);

// "[sx, sy, sz]" with SigmaText(., digits) per coordinate ("unknown" where not finite).
std::string SigmaVectorText(const Eigen::Vector3d& sigma, int digits);

}  // namespace rigcal
