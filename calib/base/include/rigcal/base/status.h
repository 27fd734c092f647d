// SPDX-License-Identifier: Apache-2.0
#pragma once
// rigcal's one error vocabulary, used by every layer:
//   Status       success, or an error message that names the file, line or field at fault;
//   Expected<T>  a value, or the Status saying why there is none. value() on an error throws
//                BadExpectedAccess with the error's message (never undefined behaviour);
//   Check()      every options struct has `Status Check() const`, returning the first violated
//                constraint as "<field>: <constraint>" (the model is Ceres's
//                Solver::Options::IsValid). A constructor that takes options calls
//                RequireValid(options.Check(), "<Options type>") and so rejects invalid options
//                with InvalidOptions instead of replacing them.
// Library code returns Status/Expected for anything a user can get wrong (files, options,
// messages); exceptions are thrown only at construction (InvalidOptions) and by a checked
// value() on an error, and the command line turns both into exit code 1 or 2 with the message.

#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

namespace rigcal {

// The error half of Status/Expected: construct an Expected<T> or a Status from Error{"..."}.
struct Error {
  std::string message;
};

class [[nodiscard]] Status {
 public:
  Status() = default;  // success
  Status(Error error)  // NOLINT(google-explicit-constructor)
      : ok_(false), message_(std::move(error.message)) {}
  static Status Ok() { return Status(); }

  bool ok() const { return ok_; }
  explicit operator bool() const { return ok(); }
  // The error message; empty for success.
  const std::string& message() const { return message_; }
  // The same error with `context` in front ("<context>: <message>"); success stays success.
  Status Prefixed(std::string_view context) const {
    if (ok()) return *this;
    return Error{std::string(context) + ": " + message_};
  }

 private:
  // A flag beside a plain string rather than std::optional<std::string>: GCC 12 warns
  // (-Wmaybe-uninitialized) about moving optional strings.
  bool ok_ = true;
  std::string message_;
};

// Thrown by Expected<T>::value() when it holds an error: a programming error at the caller,
// reported with the error it ignored.
class BadExpectedAccess : public std::logic_error {
 public:
  explicit BadExpectedAccess(const std::string& message)
      : std::logic_error("value() of an error: " + message) {}
};

// Thrown by constructors given options whose Check() fails; the message names the options type
// and the field ("VoOptions: max_features: must be > 0, is -1").
class InvalidOptions : public std::invalid_argument {
 public:
  explicit InvalidOptions(const std::string& message) : std::invalid_argument(message) {}
};

// Throws InvalidOptions with "<what>: <status message>" unless `status` is ok.
inline void RequireValid(const Status& status, std::string_view what) {
  if (!status.ok()) throw InvalidOptions(std::string(what) + ": " + status.message());
}

template <typename T>
class [[nodiscard]] Expected {
 public:
  Expected(T value) : value_(std::move(value)) {}       // NOLINT(google-explicit-constructor)
  Expected(Error error) : status_(std::move(error)) {}  // NOLINT(google-explicit-constructor)
  // An Expected from a failed Status (a successful one is a programming error).
  Expected(Status status) : status_(std::move(status)) {  // NOLINT(google-explicit-constructor)
    if (status_.ok()) throw std::logic_error("Expected built from a successful Status, no value");
  }

  bool ok() const { return value_.has_value(); }
  explicit operator bool() const { return ok(); }
  const T& value() const& { return Checked(), *value_; }
  T& value() & { return Checked(), *value_; }
  T&& value() && { return Checked(), std::move(*value_); }
  const T& operator*() const& { return value(); }
  T& operator*() & { return value(); }
  T&& operator*() && { return std::move(*this).value(); }
  const T* operator->() const { return &value(); }
  T* operator->() { return &value(); }
  // The error message (empty when ok).
  const std::string& error() const { return status_.message(); }
  const Status& status() const { return status_; }

 private:
  void Checked() const {
    if (!value_) throw BadExpectedAccess(status_.message());
  }

  std::optional<T> value_;
  Status status_;
};

}  // namespace rigcal
