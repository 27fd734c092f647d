// SPDX-License-Identifier: Apache-2.0
// The libcamera source of a build without libcamera-dev: every call says so.
#include "rigcal/capture/libcamera_device.h"

namespace rigcal::capture {
namespace {
const char* kNotBuilt =
    "the libcamera source is not built in (libcamera-dev was not found when rigcal was "
    "configured; install it and reconfigure)";
}  // namespace

struct LibcameraDevice::Impl {};

bool LibcameraBuiltIn() { return false; }
Expected<std::vector<std::string>> ListLibcameraCameras() { return Error{kNotBuilt}; }
Expected<std::unique_ptr<LibcameraDevice>> LibcameraDevice::Open(std::string, int,
                                                                 LibcameraOptions) {
  return Error{kNotBuilt};
}
LibcameraDevice::LibcameraDevice(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
LibcameraDevice::~LibcameraDevice() = default;
const std::string& LibcameraDevice::name() const {
  static const std::string none;
  return none;
}
double LibcameraDevice::frame_rate_hz() const { return 0.0; }
Expected<std::optional<Frame>> LibcameraDevice::Grab() { return Error{kNotBuilt}; }
void LibcameraDevice::Interrupt() {}
std::string LibcameraDevice::validation() const { return ""; }
std::string LibcameraDevice::configuration() const { return ""; }
std::string LibcameraDevice::camera_id() const { return ""; }
LibcameraStats LibcameraDevice::stats() const { return {}; }

}  // namespace rigcal::capture
