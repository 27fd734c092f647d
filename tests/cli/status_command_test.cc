// SPDX-License-Identifier: Apache-2.0
// `rigcal status` as a command: the built binary reads RIGCAL_STATUS / RIGCAL_EXTRINSICS from an
// LCM log through LCM's file:// provider (no network), prints the JSON snapshot with the health
// exit code, plain lines when stdout is not a terminal and the dashboard with terminal control
// codes when it is (a pseudo-terminal made by `script`). Live udpm:// between processes:
// status_report_netns_test.sh.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <stdlib.h>

#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include "cli/command_test.h"
#include "monitor/status_fixtures.h"
#include "rigcal/lcm/channels.h"
#include "support/skip.h"

namespace rigcal {
namespace {

using cli_test::Quote;
using monitor::MakeExtrinsics;
using monitor::MakeStatus;
using cli_test::RunResult;
using ::testing::HasSubstr;

class StatusCommandTest : public cli_test::CommandTest {
 protected:
  // A log of `statuses` RIGCAL_STATUS in `state`, each followed by a RIGCAL_EXTRINSICS.
  std::string WriteLog(const std::string& name, int8_t state, int statuses) {
    const std::string path = (dir_ / name).string();
    ::lcm::LogFile log(path, "w");
    int64_t n = 0;
    auto write = [&](const char* channel, const auto& msg) {
      auto bytes = lcm::EncodeMessage(channel, lcm::CameraNames{}, msg);
      ASSERT_TRUE(bytes.ok()) << bytes.error();
      ::lcm::LogEvent event;
      event.eventnum = n;
      event.timestamp = 1000 * ++n;
      event.channel = channel;
      event.datalen = static_cast<int32_t>(bytes->size());
      event.data = bytes->data();
      ASSERT_EQ(log.writeEvent(&event), 0);
    };
    const int8_t slave_state = state == rig_status_t::ESTIMATOR_CONVERGED
                                   ? slave_extrinsics_t::STATE_CONVERGED
                                   : slave_extrinsics_t::STATE_USABLE;
    for (int i = 0; i < statuses; ++i) {
      write(lcm::kStatusChannel, MakeStatus(state, 1000 + i));
      write(lcm::kExtrinsicsChannel, MakeExtrinsics(slave_state, 0.01));
    }
    return path;
  }

  RunResult Status(const std::string& log, const std::string& args) const {
    return Run("status --lcm " + Quote("file://" + log + "?speed=0") + " " + args);
  }
};

TEST_F(StatusCommandTest, OnceJsonExitsWithTheHealth) {
  const std::pair<int8_t, int> cases[] = {{rig_status_t::ESTIMATOR_CONVERGED, 0},
                                          {rig_status_t::ESTIMATOR_INITIALISING, 1},
                                          {rig_status_t::ESTIMATOR_DECALIBRATED, 2}};
  for (const auto& [state, code] : cases) {
    const std::string log = WriteLog("state" + std::to_string(state) + ".lcmlog", state, 1);
    const RunResult r = Status(log, "--once --json --timeout 2");
    EXPECT_EQ(r.exit_code, code) << r.Explain();
    const nlohmann::json j = nlohmann::json::parse(r.out, nullptr, false);
    ASSERT_FALSE(j.is_discarded()) << r.Explain();
    EXPECT_EQ(j["exit_code"], code);
    EXPECT_EQ(j["status"]["cameras"].size(), 2u);
    EXPECT_EQ(j["extrinsics"]["slaves"][0]["motions_used"], 321);
  }
}

TEST_F(StatusCommandTest, NoDataIsExitCode3) {
  // A log with an unrelated channel only.
  const std::string path = (dir_ / "other.lcmlog").string();
  {
    ::lcm::LogFile log(path, "w");
    uint8_t byte = 0;
    ::lcm::LogEvent event{0, 1, "SOMETHING_ELSE", 1, &byte};
    ASSERT_EQ(log.writeEvent(&event), 0);
  }
  const RunResult r = Status(path, "--once --json --timeout 1");
  EXPECT_EQ(r.exit_code, 3) << r.Explain();
  EXPECT_THAT(r.out, HasSubstr("\"health\": \"no_data\""));
  // An URL LCM cannot open: no data can arrive, and the message says why.
  const RunResult bad = Run("status --lcm 'bogus://nowhere' --once --timeout 1");
  EXPECT_EQ(bad.exit_code, 3) << bad.Explain();
  EXPECT_THAT(bad.err, HasSubstr("bogus://nowhere: cannot open LCM"));
}

TEST_F(StatusCommandTest, PlainLinesWhenNotATerminal) {
  const std::string log = WriteLog("plain.lcmlog", rig_status_t::ESTIMATOR_USABLE, 5);
  const RunResult r = Status(log, "");
  EXPECT_EQ(r.exit_code, 1) << r.Explain();  // the log ends; its last health: converging
  int blocks = 0;
  for (size_t pos = r.out.find("---\n"); pos != std::string::npos;
       pos = r.out.find("---\n", pos + 1)) {
    ++blocks;
  }
  EXPECT_EQ(blocks, 5) << r.out;
  EXPECT_THAT(r.out, HasSubstr("slave left (master front): usable refined"));
  EXPECT_THAT(r.out, ::testing::Not(HasSubstr("\x1b")));
}

TEST_F(StatusCommandTest, DashboardOnATerminal) {
  if (std::system("command -v script >/dev/null 2>&1") != 0) {
    RIGCAL_SKIP_MISSING() << "`script` (util-linux) is not installed: no pseudo-terminal";
  }
  const std::string log = WriteLog("tty.lcmlog", rig_status_t::ESTIMATOR_CONVERGED, 3);
  // script runs the command on a pseudo-terminal and copies what it printed.
  const std::string inner =
      Quote(binary_) + " status --refresh 0.05 --lcm " + Quote("file://" + log + "?speed=0");
  const RunResult r = cli_test::RunShell("script -qfec " + Quote(inner) + " /dev/null", dir_);
  EXPECT_EQ(r.exit_code, 0) << r.Explain();
  EXPECT_THAT(r.out, HasSubstr("\x1b[2J"));  // cleared once
  EXPECT_THAT(r.out, HasSubstr("\x1b[H"));   // redrawn from home
  EXPECT_THAT(r.out, HasSubstr("\x1b[K"));   // lines cleared to their end
  EXPECT_THAT(r.out, HasSubstr("rig: converged"));
}

TEST_F(StatusCommandTest, UsageErrors) {
  const RunResult r = Run("status --once --timeout -1");
  EXPECT_EQ(r.exit_code, 2) << r.Explain();
  const RunResult help = Run("status --help");
  EXPECT_EQ(help.exit_code, 0);
  for (const char* option :
       {"--lcm", "--once", "--json", "--timeout", "--refresh", "0 converged, 1 still"}) {
    EXPECT_THAT(help.out, HasSubstr(option));
  }
}

}  // namespace
}  // namespace rigcal
