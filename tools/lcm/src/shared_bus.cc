// SPDX-License-Identifier: Apache-2.0
#include "rigcal/lcm/shared_bus.h"

#include <lcm/lcm-cpp.hpp>

namespace rigcal::lcm {

int SharedBus::Publish(const std::string& channel, const std::vector<uint8_t>& bytes) {
  MutexLock lock(mutex_);
  return bus_->publish(channel, bytes.data(), static_cast<unsigned int>(bytes.size()));
}

}  // namespace rigcal::lcm
