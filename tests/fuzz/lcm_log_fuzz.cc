// SPDX-License-Identifier: Apache-2.0
// Fuzz target `lcm_log`: LogReader on any file: every event, then the decoder of its channel's
// type (RIGCAL_POSE_*, RIGCAL_IMAGE_*, RIGCAL_EXTRINSICS, RIGCAL_STATUS), as `rigcal calib --log`
// and `rigcal replay` read a log. Events lie within the file and follow each other; a damaged log
// says where; a second pass with NextHeader sees the same events.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "fuzz_support.h"
#include "rigcal/lcm/extrinsics_message.h"
#include "rigcal/lcm/image_message.h"
#include "rigcal/lcm/log_reader.h"
#include "rigcal/lcm/pose_message.h"
#include "rigcal/lcm/status_message.h"

namespace rigcal::fuzz {
namespace {

const lcm::CameraNames kNames = {"front", "left", "back"};

struct Pass {
  std::vector<int64_t> offsets;
  lcm::LogReader::Outcome outcome = lcm::LogReader::Outcome::kEnd;
};

Pass ReadAll(const std::string& path, int64_t file_size, bool with_data) {
  using Outcome = lcm::LogReader::Outcome;
  Pass pass;
  Expected<std::unique_ptr<lcm::LogReader>> reader = lcm::LogReader::Open(path);
  RIGCAL_FUZZ_EXPECT(reader.ok(), "an existing file opens: " + reader.error());
  lcm::MessageValidator validator(kNames);
  rigcal::lcm::LogEvent event;
  int64_t previous_end = 0;
  while (true) {
    const Outcome outcome = with_data ? (*reader)->Next(&event) : (*reader)->NextHeader(&event);
    if (outcome != Outcome::kEvent) {
      pass.outcome = outcome;
      RIGCAL_FUZZ_EXPECT((outcome == Outcome::kDamaged) != (*reader)->problem().empty(),
                         "damage, and only damage, has a problem");
      RIGCAL_FUZZ_EXPECT((*reader)->Next(&event) == outcome, "the outcome stays");
      break;
    }
    pass.offsets.push_back(event.offset);
    RIGCAL_FUZZ_EXPECT(event.offset == previous_end, "events follow each other");
    RIGCAL_FUZZ_EXPECT((*reader)->position() <= file_size, "events lie within the file");
    previous_end = (*reader)->position();
    if (!with_data) continue;
    const std::string& channel = event.channel;
    const auto* data = event.data.data();
    const auto size = static_cast<int64_t>(event.data.size());
    if (channel.rfind("RIGCAL_POSE_", 0) == 0) {
      (void)validator.DecodeCameraPose(channel, data, size);
    } else if (channel.rfind("RIGCAL_IMAGE_", 0) == 0) {
      (void)validator.Decode<image_t>(channel, data, size);
    } else if (channel == "RIGCAL_EXTRINSICS") {
      (void)validator.Decode<rig_extrinsics_t>(channel, data, size);
    } else if (channel == "RIGCAL_STATUS") {
      (void)validator.Decode<rig_status_t>(channel, data, size);
    }
  }
  return pass;
}

}  // namespace
}  // namespace rigcal::fuzz

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  rigcal::fuzz::QuietLogs();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace rigcal;
  static fuzz::InputFile file("drive.lcmlog");
  const std::string& path = file.Write(data, size);
  const fuzz::Pass full = fuzz::ReadAll(path, static_cast<int64_t>(size), true);
  const fuzz::Pass headers = fuzz::ReadAll(path, static_cast<int64_t>(size), false);
  RIGCAL_FUZZ_EXPECT(full.offsets == headers.offsets && full.outcome == headers.outcome,
                     "Next and NextHeader see the same events");
  return 0;
}
