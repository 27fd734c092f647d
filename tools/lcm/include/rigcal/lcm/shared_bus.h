// SPDX-License-Identifier: Apache-2.0
#pragma once
// One LCM bus that several threads publish on. ::lcm::LCM::publish may not be called from two
// threads at once on every provider: file:// writes an event in several unlocked writes, so two
// publishing threads interleave their bytes and the log is damaged from there on (a `run --lcm
// file://...` whose VO threads and status timer publish together). Every publisher of a process
// goes through one SharedBus; subscribing and handling stay on the ::lcm::LCM itself.

#include <cstdint>
#include <string>
#include <vector>

#include "rigcal/base/thread_annotations.h"

namespace lcm {
class LCM;
}

namespace rigcal::lcm {

class SharedBus {
 public:
  // `bus` (not owned) must outlive this.
  explicit SharedBus(::lcm::LCM* bus) : bus_(bus) {}
  SharedBus(const SharedBus&) = delete;
  SharedBus& operator=(const SharedBus&) = delete;

  // Publishes one encoded message; any thread, one at a time. 0 on success (::lcm::LCM::publish).
  int Publish(const std::string& channel, const std::vector<uint8_t>& bytes)
      RIGCAL_EXCLUDES(mutex_);

 private:
  ::lcm::LCM* const bus_;
  Mutex mutex_;
};

}  // namespace rigcal::lcm
