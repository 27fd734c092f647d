// SPDX-License-Identifier: Apache-2.0
// `rigcal trigger --hello` through the built binary: against the firmware under QEMU (its USART1
// on a pseudo-terminal) it prints the Hello with QEMU's clock status and exits 0; a port that
// does not exist and a port nobody answers on are errors naming the port (exit 1).
// Skips without the arm toolchain or QEMU (fails under CI=true).
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "cli/command_test.h"
#include "firmware/qemu_process.h"
#include "support/skip.h"

namespace rigcal::cli_test {
namespace {

class TriggerHello : public CommandTest {};

TEST_F(TriggerHello, PrintsTheFirmwaresHelloWithItsClockStatus) {
  if (const std::string missing = testing::QemuFirmwareMissing(); !missing.empty()) {
    RIGCAL_SKIP_MISSING() << missing;
  }
  testing::QemuFirmware qemu;
  std::string error;
  ASSERT_TRUE(qemu.Start(testing::QemuFirmware::Serial::kPty, &error)) << error;
  // The firmware boots while the command waits (up to 20 s on a loaded host).
  const RunResult r = Run("trigger --hello --port " + qemu.pty_path() + " --timeout-ms 20000");
  ASSERT_EQ(r.exit_code, 0) << r.Explain();
  EXPECT_NE(r.out.find("firmware 2, protocol 2, 8 lines"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("clock status 0x07: HSE (8 MHz crystal) did not start"), std::string::npos)
      << r.out;
  std::printf("%s", r.out.c_str());
}

TEST_F(TriggerHello, APortThatIsMissingOrSilentIsAnError) {
  RunResult r = Run("trigger --hello --port /dev/nonexistent-trigger");
  EXPECT_EQ(r.exit_code, 1) << r.Explain();
  EXPECT_NE(r.err.find("rigcal trigger:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("/dev/nonexistent-trigger"), std::string::npos) << r.err;
  r = Run("trigger --port /dev/null");  // --hello is required
  EXPECT_EQ(r.exit_code, 2) << r.Explain();
}

}  // namespace
}  // namespace rigcal::cli_test
