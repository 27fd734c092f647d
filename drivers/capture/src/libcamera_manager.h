// SPDX-License-Identifier: Apache-2.0
#pragma once
// The process's one libcamera CameraManager, shared by every LibcameraDevice (libcamera allows
// a single instance at a time). Started on first use, stopped when the last user lets go.

#include <libcamera/camera_manager.h>

#include <memory>

#include "rigcal/base/status.h"

namespace rigcal::capture {

Expected<std::shared_ptr<libcamera::CameraManager>> SharedCameraManager();

}  // namespace rigcal::capture
