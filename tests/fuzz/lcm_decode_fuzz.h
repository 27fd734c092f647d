// SPDX-License-Identifier: Apache-2.0
#pragma once
// The body of the LCM decoder fuzz targets (lcm_<type>_fuzz.cc): MessageValidator::Decode of one
// message type on any bytes, for the rig of tests/lcm/message_fixtures.h and for an empty name
// table. An accepted message passes CheckMessage, encodes (EncodeMessage) and decodes again to
// the same bytes; every rejection is counted under one cause and says why.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_support.h"
#include "rigcal/lcm/message_validation.h"

namespace rigcal::fuzz {

inline const lcm::CameraNames kFuzzNames = {"front", "left", "back"};

// Decode<Message> of `data` against `names`; the accepted message, re-encoded, or nothing.
template <typename Message>
std::optional<Message> DecodeAndCheck(const char* channel, const lcm::CameraNames& names,
                                      const uint8_t* data, size_t size) {
  lcm::MessageValidator validator(names);
  Expected<Message> msg =
      validator.template Decode<Message>(channel, data, static_cast<int64_t>(size));
  const lcm::DecodeStats& stats = validator.stats();
  if (!msg) {
    RIGCAL_FUZZ_EXPECT(stats.accepted == 0 && stats.TotalRejected() == 1,
                       "a rejection is counted once");
    RIGCAL_FUZZ_EXPECT(!msg.error().empty(), "a rejection says why");
    return std::nullopt;
  }
  RIGCAL_FUZZ_EXPECT(stats.accepted == 1 && stats.TotalRejected() == 0, "acceptance counted");
  Message copy = *msg;
  RIGCAL_FUZZ_EXPECT(!lcm::CheckMessage(channel, names, &copy).has_value(),
                     "an accepted message passes CheckMessage");
  Expected<std::vector<uint8_t>> encoded = lcm::EncodeMessage(channel, names, *msg);
  RIGCAL_FUZZ_EXPECT(encoded.ok(), "an accepted message encodes: " + encoded.error());
  Expected<Message> again = validator.template Decode<Message>(
      channel, encoded->data(), static_cast<int64_t>(encoded->size()));
  RIGCAL_FUZZ_EXPECT(again.ok(), "a re-encoded message decodes: " + again.error());
  Expected<std::vector<uint8_t>> twice = lcm::EncodeMessage(channel, names, *again);
  RIGCAL_FUZZ_EXPECT(twice.ok() && *twice == *encoded, "encoding is stable");
  return *msg;
}

}  // namespace rigcal::fuzz
