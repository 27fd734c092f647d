// SPDX-License-Identifier: Apache-2.0
#pragma once
// The field checks shared by every rigcal LCM message type (private to rigcal_lcm): a Checker
// keeps the first rule a message fails, as a Rejection that names channel, field and rule.

#include <cstddef>
#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "rigcal/lcm/message_validation.h"

namespace rigcal::lcm::internal {

// `value` with 10 significant digits, as rejection messages print numbers.
std::string FormatNumber(double value);

// Collects the first failed rule of one message. Fields are named "<prefix>.<field>". Every check
// does nothing once a rule has failed.
class Checker {
 public:
  Checker(std::string_view channel, std::string prefix);

  bool ok() const { return !rejection_.has_value(); }
  std::optional<Rejection> TakeRejection() { return std::move(rejection_); }

  // A checker for a nested message, e.g. "rig_extrinsics_t.slaves[1]".
  Checker Nested(const std::string& field) const;
  // Takes over the rejection of `nested` unless this checker has one already.
  void Merge(Checker&& nested);

  // Records `cause` for `field` with `what` (the first failure only).
  void Fail(RejectCause cause, std::string_view field, const std::string& what);

  // The message's schema version.
  void Version(int16_t version, int16_t expected);

  // Every one of `count` values is finite.
  void Finite(std::string_view field, const double* values, int count);
  void Finite(std::string_view field, double value) { Finite(field, &value, 1); }

  // A unit vector within kUnitTolerance, normalised in place (unless unit within 4 ulp);
  // `cause` for a wrong norm.
  void Unit(std::string_view field, double* values, int count, RejectCause cause,
            std::string_view what);
  // A unit quaternion (w, x, y, z), normalised in place.
  void Quaternion(std::string_view field, double* q) {
    Unit(field, q, 4, RejectCause::kNonUnitQuaternion, "q");
  }

  // Range checks; `value` is a double or an integer.
  template <typename T>
  void AtLeast(std::string_view field, T value, T min) {
    if (!(value >= min)) {
      Fail(RejectCause::kOutOfRange, field,
           FormatNumber(static_cast<double>(value)) + " is below " +
               FormatNumber(static_cast<double>(min)));
    }
  }
  template <typename T>
  void InRange(std::string_view field, T value, T min, T max) {
    if (!(value >= min && value <= max)) {
      Fail(RejectCause::kOutOfRange, field,
           FormatNumber(static_cast<double>(value)) + " is outside [" +
               FormatNumber(static_cast<double>(min)) + ", " +
               FormatNumber(static_cast<double>(max)) + "]");
    }
  }

  // Array length field `count_field` against the vector's size.
  void Count(std::string_view count_field, int64_t count, size_t vector_size,
             std::string_view vector_field);

  // Checks element i of `elements` as the nested message "<array>[i]" with
  // check_element(&element, &nested checker), in order while no rule has failed, and that its
  // name is neither in `seen` nor the name of an earlier element.
  template <typename Element, typename CheckElement>
  void NamedElements(std::string_view array, std::vector<Element>* elements,
                     std::set<std::string> seen, CheckElement check_element) {
    for (size_t i = 0; i < elements->size() && ok(); ++i) {
      Element& element = (*elements)[i];
      const std::string field = std::string(array) + "[" + std::to_string(i) + "]";
      Checker nested = Nested(field);
      check_element(&element, &nested);
      Merge(std::move(nested));
      if (ok() && !seen.insert(element.name).second) {
        Fail(RejectCause::kOutOfRange, field + ".name",
             "camera '" + element.name + "' appears twice");
      }
    }
  }

  // A free-text string (a message, a fourcc): no NUL byte. LCM decodes a string as its announced
  // length and encodes it up to the first NUL, so a string with a NUL inside would not encode
  // again (EncodeMessage fails; a relay or a recorder would drop it).
  void Text(std::string_view field, const std::string& text);

  // A camera name: non-empty, no NUL, and one of names[first..] unless `names` is empty (no
  // table: any name). `allowed_what` says which names ("the rig's cameras", "the rig's slaves").
  void CameraName(std::string_view field, const std::string& name, const CameraNames& names,
                  size_t first, std::string_view allowed_what);

 private:
  std::string Field(std::string_view field) const { return prefix_ + "." + std::string(field); }

  std::string channel_;
  std::string prefix_;
  std::optional<Rejection> rejection_;
};

}  // namespace rigcal::lcm::internal
