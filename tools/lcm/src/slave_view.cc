// SPDX-License-Identifier: Apache-2.0
#include "rigcal/lcm/slave_view.h"

#include "rigcal/lcm/extrinsics_message.h"

namespace rigcal::lcm {

SlaveView ViewOf(const slave_extrinsics_t& s) {
  SlaveView view;
  view.q = Eigen::Quaterniond(s.q[0], s.q[1], s.q[2], s.q[3]);
  view.state = s.state >= slave_extrinsics_t::STATE_INITIALISING &&
                       s.state <= slave_extrinsics_t::STATE_DECALIBRATED
                   ? static_cast<SlaveState>(s.state)
                   : SlaveState::kInitialising;
  for (std::string_view fact : FactNames(FactsOfWireFlags(s.flags))) view.facts.emplace_back(fact);
  if (s.flags & kWireFlagAxisFromPrior) view.facts.push_back("axis-from-prior");
  return view;
}

}  // namespace rigcal::lcm
