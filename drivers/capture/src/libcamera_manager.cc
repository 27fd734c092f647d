// SPDX-License-Identifier: Apache-2.0
#include "libcamera_manager.h"

#include <cstring>

#include "rigcal/base/thread_annotations.h"

namespace rigcal::capture {

Expected<std::shared_ptr<libcamera::CameraManager>> SharedCameraManager() {
  static Mutex mutex;
  static std::weak_ptr<libcamera::CameraManager> shared RIGCAL_GUARDED_BY(mutex);
  MutexLock lock(mutex);
  if (auto manager = shared.lock()) return manager;
  auto manager = std::make_shared<libcamera::CameraManager>();
  if (const int result = manager->start(); result != 0) {
    return Error{std::string("libcamera: the camera manager does not start: ") +
                 std::strerror(-result)};
  }
  shared = manager;
  return manager;
}

}  // namespace rigcal::capture
