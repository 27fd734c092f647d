// rigcal's LCM logs against the real LCM tools (Debian liblcm-bin): a log written by rigcal plays
// in lcm-logplayer, and what lcm-logger records of it replays in rigcal. udpm:// traffic only
// inside a private network namespace the test creates (unshare --net, a multicast route on its
// own lo); nothing is sent in the host's namespace. Without unshare permission or the tools the
// test is skipped with the reason (a failure under CI=true).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "support/command_runner.h"
#include "support/simulated_rig_config.h"

namespace rigcal {
namespace {

namespace fs = std::filesystem;
using support::ShellQuote;

struct Event {
  std::string channel;
  std::vector<uint8_t> data;
  bool operator==(const Event& other) const {
    return channel == other.channel && data == other.data;
  }
};

std::vector<Event> ReadEvents(const std::string& path) {
  std::vector<Event> events;
  lcm::LogFile log(path, "r");
  EXPECT_TRUE(log.good()) << path;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    const auto* data = static_cast<const uint8_t*>(e->data);
    events.push_back({e->channel, std::vector<uint8_t>(data, data + e->datalen)});
  }
  return events;
}

// Plays each log (argument pairs IN OUT) with lcm-logplayer while lcm-logger records the bus.
constexpr char kPlayAndRecordScript[] = R"(set -euo pipefail
links=$(ip -o link show | awk -F': ' '{print $2}' | tr '\n' ' ')
if [ "$links" != "lo " ]; then echo "FAIL: not a private namespace, links: $links"; exit 1; fi
ip link set lo up
ip link set lo multicast on
ip route add 224.0.0.0/4 dev lo
url='udpm://239.255.76.67:7667?ttl=0'
speed=$1; shift
while [ $# -ge 2 ]; do
  lcm-logger --lcm-url="$url" --quiet --force "$2" &
  logger=$!
  sleep 0.5
  lcm-logplayer --lcm-url="$url" --speed="$speed" "$1"
  sleep 0.5
  kill -INT "$logger"
  wait "$logger" || true
  shift 2
done
)";

class LcmToolsNetnsTest : public ::testing::Test {
 protected:
  void SetUp() override {
#ifndef RIGCAL_BINARY
    FAIL() << "RIGCAL_BINARY is not defined: tests/CMakeLists.txt must pass the rigcal path";
#else
    binary_ = RIGCAL_BINARY;
#endif
    std::string pattern = (fs::path(::testing::TempDir()) / "lcm_tools_netns_XXXXXX").string();
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    std::error_code ec;
    if (!HasFailure()) fs::remove_all(dir_, ec);
  }
  support::CommandResult Rigcal(const std::string& args) {
    return support::RunShell(ShellQuote(binary_) + " " + args, dir_);
  }
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

  std::string binary_;
  fs::path dir_;
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
  const auto recorded = Rigcal("record --config " + ShellQuote(Path("rig.yaml")) + " -o " +
                               ShellQuote(Path("images.lcmlog")) + " --no-vo --fast");
  ASSERT_EQ(recorded.exit_code, 0) << recorded.err;
  const auto synth = Rigcal("synth-log --config " + ShellQuote(Path("rig.yaml")) + " --out " +
                            ShellQuote(Path("poses.lcmlog")) + " --frames 600");
  ASSERT_EQ(synth.exit_code, 0) << synth.err;

  std::ofstream(Path("play.sh")) << kPlayAndRecordScript;
  const auto played = support::RunShell(
      "unshare --net --fork bash " + ShellQuote(Path("play.sh")) + " 4 " +
          ShellQuote(Path("images.lcmlog")) + " " + ShellQuote(Path("bus_images.lcmlog")) + " " +
          ShellQuote(Path("poses.lcmlog")) + " " + ShellQuote(Path("bus_poses.lcmlog")),
      dir_);
  ASSERT_EQ(played.exit_code, 0) << played.out << played.err;

  // lcm-logplayer published every event of rigcal's logs, byte for byte, in order.
  for (const auto& [written, bus] : {std::pair{"images.lcmlog", "bus_images.lcmlog"},
                                     std::pair{"poses.lcmlog", "bus_poses.lcmlog"}}) {
    const std::vector<Event> original = ReadEvents(Path(written));
    const std::vector<Event> received = ReadEvents(Path(bus));
    EXPECT_EQ(original.size(), written == std::string("images.lcmlog") ? 80u : 1200u);
    ASSERT_EQ(received.size(), original.size()) << bus;
    for (size_t i = 0; i < original.size(); ++i) {
      ASSERT_TRUE(received[i] == original[i]) << bus << " event " << i << " "
                                              << original[i].channel;
    }
  }

  // lcm-logger's recording replays in rigcal: every pose decoded, every stamp matched into a
  // set, the slave in the result. (How well the replay calibrates is the replay tests' subject;
  // the bytes are rigcal's own, compared above.)
  const auto replay = Rigcal("calib --config " + ShellQuote(Path("rig.yaml")) + " --log " +
                             ShellQuote(Path("bus_poses.lcmlog")) + " --json --out " +
                             ShellQuote(Path("result.yaml")));
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
