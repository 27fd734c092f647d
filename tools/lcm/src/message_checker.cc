// SPDX-License-Identifier: Apache-2.0
#include "message_checker.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <utility>

#include "rigcal/base/format.h"

namespace rigcal::lcm::internal {

std::string FormatNumber(double value) { return SignificantText(value, 10); }

Checker::Checker(std::string_view channel, std::string prefix)
    : channel_(channel), prefix_(std::move(prefix)) {}

Checker Checker::Nested(const std::string& field) const { return Checker(channel_, Field(field)); }

void Checker::Merge(Checker&& nested) {
  if (ok() && !nested.ok()) rejection_ = nested.TakeRejection();
}

void Checker::Fail(RejectCause cause, std::string_view field, const std::string& what) {
  if (!ok()) return;
  rejection_ = Rejection{cause, std::string(channel_) + ": " + Field(field) + ": " + what + " (" +
                                    ToString(cause) + ")"};
}

void Checker::Version(int16_t version, int16_t expected) {
  if (version != expected) {
    Fail(RejectCause::kWrongVersion, "version",
         "schema version " + std::to_string(version) + ", this build reads " +
             std::to_string(expected));
  }
}

void Checker::Finite(std::string_view field, const double* values, int count) {
  for (int i = 0; i < count; ++i) {
    if (!std::isfinite(values[i])) {
      const std::string name =
          count == 1 ? std::string(field) : std::string(field) + "[" + std::to_string(i) + "]";
      Fail(RejectCause::kNonFinite, name, "not finite (" + FormatNumber(values[i]) + ")");
      return;
    }
  }
}

void Checker::Unit(std::string_view field, double* values, int count, RejectCause cause,
                   std::string_view what) {
  Finite(field, values, count);
  if (!ok()) return;
  double norm_sq = 0.0;
  for (int i = 0; i < count; ++i) norm_sq += values[i] * values[i];
  const double norm = std::sqrt(norm_sq);
  if (!(std::abs(norm - 1.0) <= kUnitTolerance)) {
    std::string text = "|";  // appended piecewise: "|" + std::string trips GCC 12's -Wrestrict
    text += what;
    text += "| = " + FormatNumber(norm) + " is not 1 within " + FormatNumber(kUnitTolerance);
    Fail(cause, field, text);
    return;
  }
  // Unit to rounding already: left bit for bit (a receiver then sees what the sender's own
  // computation used, so a replayed recording repeats the live run exactly).
  if (std::abs(norm - 1.0) <= 4.0 * std::numeric_limits<double>::epsilon()) return;
  for (int i = 0; i < count; ++i) values[i] /= norm;
}

void Checker::Count(std::string_view count_field, int64_t count, size_t vector_size,
                    std::string_view vector_field) {
  if (count < 0) {
    Fail(RejectCause::kBadSize, count_field, "negative length " + std::to_string(count));
  } else if (static_cast<uint64_t>(count) != vector_size) {
    Fail(RejectCause::kBadSize, count_field,
         std::to_string(count) + " but " + std::string(vector_field) + " has " +
             std::to_string(vector_size) + " elements");
  }
}

void Checker::Text(std::string_view field, const std::string& text) {
  if (ok() && text.find('\0') != std::string::npos) {
    Fail(RejectCause::kMalformed, field,
         "contains a NUL byte at " + std::to_string(text.find('\0')) + " of " +
             std::to_string(text.size()));
  }
}

void Checker::CameraName(std::string_view field, const std::string& name, const CameraNames& names,
                         size_t first, std::string_view allowed_what) {
  if (name.empty()) {
    Fail(RejectCause::kUnknownCamera, field, "empty camera name");
  } else if (name.find('\0') != std::string::npos) {
    Fail(RejectCause::kMalformed, field, "camera name contains a NUL byte");
  } else if (!names.empty() && std::find(names.begin() + std::min(first, names.size()), names.end(),
                                         name) == names.end()) {
    Fail(RejectCause::kUnknownCamera, field,
         "camera '" + name + "' is not one of " + std::string(allowed_what));
  }
}

}  // namespace rigcal::lcm::internal
