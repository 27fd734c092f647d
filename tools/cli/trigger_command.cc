// SPDX-License-Identifier: Apache-2.0
// `rigcal trigger --hello`: checks the link to a trigger generator (firmware/, docs/firmware.md):
// opens its serial port, asks for its Hello and prints the firmware's answer, clock status
// included.
#include <cstdio>
#include <memory>
#include <string>

#include "commands.h"
#include "exit_codes.h"
#include "rigcal/trigger/serial_port.h"
#include "rigcal/trigger/trigger_hello.h"
#include "rigcal/trigger/trigger_link.h"

namespace rigcal::cli {
namespace {

struct TriggerOptions {
  std::string port;
  int baud = 115200;
  int timeout_ms = 2000;
  bool hello = false;
};

int RunTriggerHello(const TriggerOptions& o) {
  auto port = trigger::SerialPort::Open(o.port, o.baud);
  if (!port) return PrintCommandError("trigger", port.error());
  trigger::TriggerLink link(std::move(*port));
  const auto info = trigger::QueryTriggerHello(&link, o.timeout_ms);
  if (!info) return PrintCommandError("trigger", o.port + ": " + info.error());
  const trigger_protocol::Hello& h = info->hello;
  std::printf("trigger generator on %s: firmware %u, protocol %u, %u lines, MCU time %.6f s\n",
              o.port.c_str(), h.firmware_version, trigger_protocol::kProtocolVersion, h.max_lines,
              static_cast<double>(h.mcu_time_us) * 1e-6);
  std::printf("clock status 0x%02x: %s\n", h.clock_status,
              trigger::DescribeClockStatus(h.clock_status, h.hse_mhz).c_str());
  std::printf("round trip %.1f ms\n", static_cast<double>(info->round_trip_ns) * 1e-6);
  return kExitOk;
}

}  // namespace

void RegisterTrigger(CLI::App& app, int* exit_code) {
  auto options = std::make_shared<TriggerOptions>();
  CLI::App* cmd = app.add_subcommand(
      "trigger",
      "The trigger generator's serial link. --hello asks it for its Hello and prints the\n"
      "firmware version, lines, MCU time and the clock status (crystal and PLL, or the HSI\n"
      "fallback). Exit 0 when it answered, 1 otherwise.");
  cmd->add_option("--port", options->port, "Serial device: /dev/ttyACM0, /dev/ttyUSB0, /dev/pts/N")
      ->required();
  cmd->add_option("--baud", options->baud, "Baud rate of a UART link")->default_val(115200);
  cmd->add_option("--timeout-ms", options->timeout_ms, "How long to wait for the answer")
      ->check(CLI::Range(10, 60000))
      ->default_val(2000);
  cmd->add_flag("--hello", options->hello, "Ask for the Hello (the link check)")->required();
  cmd->callback([options, exit_code]() { *exit_code = RunTriggerHello(*options); });
}

}  // namespace rigcal::cli
