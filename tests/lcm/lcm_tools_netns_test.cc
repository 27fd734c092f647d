// SPDX-License-Identifier: Apache-2.0
// rigcal's LCM logs against the real LCM tools (Debian liblcm-bin): a log written by rigcal plays
// in lcm-logplayer, and what lcm-logger records of it replays in rigcal. udpm:// traffic only
// inside a private network namespace the test creates (unshare --net, a multicast route on its
// own lo); nothing is sent in the host's namespace. Without unshare permission or the tools the
// test is skipped with the reason (a failure under CI=true).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli/command_test.h"
#include "support/command_runner.h"
#include "support/lcm_log_events.h"
#include "support/simulated_rig_config.h"

namespace rigcal {
namespace {

namespace fs = std::filesystem;
using cli_test::Quote;

// Plays each log (argument triples IN OUT SPEED) with lcm-logplayer while lcm-logger records the
// bus. A receive buffer of 4 MB keeps the kernel from dropping datagrams of image bursts where the
// host's net.core.rmem_max allows it (the limit is the host's; a namespace cannot raise it).
constexpr char kPlayAndRecordScript[] = R"sh(set -euo pipefail
links=$(ip -o link show | awk -F': ' '{print $2}' | tr '\n' ' ')
if [ "$links" != "lo " ]; then echo "FAIL: not a private namespace, links: $links"; exit 1; fi
ip link set lo up
ip link set lo multicast on
ip route add 224.0.0.0/4 dev lo
sysctl -qw net.core.rmem_max=8388608 2>/dev/null || true
url='udpm://239.255.76.67:7667?ttl=0&recv_buf_size=4194304'
while [ $# -ge 3 ]; do
  lcm-logger --lcm-url="$url" --quiet --force "$2" &
  logger=$!
  # Play once the logger's socket is bound (and at least half a second, for its subscription).
  sleep 0.5
  for _ in $(seq 1 100); do ss -uln | grep -q ':7667 ' && break; sleep 0.1; done
  lcm-logplayer --lcm-url="$url" --speed="$3" "$1"
  # Time for the logger to receive and write the last events on a busy machine.
  sleep 2
  kill -INT "$logger"
  wait "$logger" || true
  shift 3
done
)sh";

// Whether `received` is `original` with some events left out, the rest in order and whole.
bool IsInOrderSubset(const std::vector<support::LoggedEvent>& received,
                     const std::vector<support::LoggedEvent>& original) {
  size_t next = 0;
  for (const support::LoggedEvent& event : received) {
    while (next < original.size() && !(original[next] == event)) ++next;
    if (next == original.size()) return false;
    ++next;
  }
  return true;
}

class LcmToolsNetnsTest : public cli_test::CommandTest {
 protected:
  // Plays `written` (expected to hold `events` events) in a private namespace while lcm-logger
  // records it to `bus`, and checks that the recording holds every event, byte for byte, in order.
  // UDP may drop a datagram of a burst when the host's receive-buffer limit is small (a
  // transport's loss, not the log's content): an attempt that lost events but kept the rest
  // whole and in order is repeated, up to three attempts; anything else fails at once.
  void PlayAndCompare(const std::string& written, const std::string& bus, int speed,
                      size_t events) {
    const std::vector<support::LoggedEvent> original = support::ReadLcmLog(Path(written));
    ASSERT_EQ(original.size(), events) << written;
    std::vector<support::LoggedEvent> received;
    for (int attempt = 1; attempt <= 3; ++attempt) {
      const auto played = support::RunShell("unshare --net --fork bash " + Quote(Path("play.sh")) +
                                                " " + Quote(Path(written)) + " " +
                                                Quote(Path(bus)) + " " + std::to_string(speed),
                                            dir_);
      ASSERT_EQ(played.exit_code, 0) << played.out << played.err;
      received = support::ReadLcmLog(Path(bus));
      ASSERT_TRUE(IsInOrderSubset(received, original))
          << bus << ": an event that rigcal's log does not hold, or out of order";
      if (received.size() == original.size()) return;
      std::cerr << bus << ": attempt " << attempt << " received " << received.size() << " of "
                << original.size() << " events (UDP loss in a burst); playing again\n";
    }
    EXPECT_EQ(received.size(), original.size()) << bus << " after three attempts";
  }
};

TEST_F(LcmToolsNetnsTest, RigcalLogsPlayInLcmToolsAndTheirRecordingsReplay) {
  for (const char* tool : {"unshare", "ip", "lcm-logger", "lcm-logplayer"}) {
    if (support::RunShell(std::string("command -v ") + tool, dir_).exit_code != 0) {
      RIGCAL_SKIP_UNLESS_CI(std::string(tool) + " not found (Debian: util-linux, iproute2, " +
                            "liblcm-bin)");
    }
  }
  if (support::RunShell("unshare --net true", dir_).exit_code != 0) {
    RIGCAL_SKIP_UNLESS_CI(
        "cannot create a network namespace here (unshare --net needs root or user namespaces)");
  }

  // A rigcal image log (rigcal record) and a rigcal pose log (rigcal synth-log: a simulated
  // drive's poses, written by the same LogWriter).
  std::ofstream(Path("rig.yaml")) << support::SimulatedRigConfig(160, 120, 40);
  const auto recorded = Run("record --config " + Quote(Path("rig.yaml")) + " -o " +
                            Quote(Path("images.lcmlog")) + " --no-vo --fast");
  ASSERT_EQ(recorded.exit_code, 0) << recorded.err;
  const auto synth = Run("synth-log --config " + Quote(Path("rig.yaml")) + " --out " +
                         Quote(Path("poses.lcmlog")) + " --frames 600");
  ASSERT_EQ(synth.exit_code, 0) << synth.err;

  // lcm-logplayer published every event of rigcal's logs, byte for byte, in order.
  std::ofstream(Path("play.sh")) << kPlayAndRecordScript;
  PlayAndCompare("images.lcmlog", "bus_images.lcmlog", 1, 80);
  PlayAndCompare("poses.lcmlog", "bus_poses.lcmlog", 4, 1200);

  // lcm-logger's recording replays in rigcal: every pose decoded, every stamp matched into a
  // set, the slave in the result. (How well the replay calibrates is the replay tests' subject;
  // the bytes are rigcal's own, compared above.)
  const auto replay =
      Run("calib --config " + Quote(Path("rig.yaml")) + " --log " +
          Quote(Path("bus_poses.lcmlog")) + " --json --out " + Quote(Path("result.yaml")));
  EXPECT_TRUE(replay.exit_code == 0 || replay.exit_code == 3) << replay.err;
  EXPECT_NE(replay.err.find("decoder: accepted 1200, rejected 0; unknown cameras: 0"),
            std::string::npos)
      << replay.err;
  EXPECT_NE(replay.err.find("sync: sets 600 "), std::string::npos) << replay.err;
  EXPECT_EQ(replay.err.find("truncated"), std::string::npos) << replay.err;
  const auto json = nlohmann::json::parse(replay.out, nullptr, /*allow_exceptions=*/false);
  ASSERT_FALSE(json.is_discarded()) << replay.out;
  ASSERT_EQ(json.at("slaves").size(), 1u) << json.dump(2);
  EXPECT_EQ(json["slaves"][0].value("name", ""), "cam1");
}

}  // namespace
}  // namespace rigcal
