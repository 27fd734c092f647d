// SPDX-License-Identifier: Apache-2.0
#pragma once
// TriggerApp: the trigger generator's firmware logic without the board: command parsing and
// answers, the scheduler, the exposure meter, heartbeats and the outgoing byte queue. The board
// port feeds it received bytes and the time, drains its transmit queue into the UART, and calls
// it from its timer interrupts; the lines are the board's timer channels (LineTimers).
//
//   boot:       Boot(now, board)              queues a Hello (the host detects the restart)
//   main loop:  OnRxByte(b, now) for every received byte; Poll(now); PopTx() into the UART
//   compare:    OnCompare(line)               a line's armed edge happened (timer interrupt)
//   capture:    OnCapture(line, count)        a wired line's exposure input changed
//
// Commands (messages.h) are answered in the order received: Ack when applied, Nack with the
// reason and field otherwise. Range rules: trigger_config.h. The configuration (rate, lines,
// heartbeat period) changes only while stopped (else Nack kBusy); Start needs an enabled line
// (Nack kNoLinesEnabled); Start while running and Stop while stopped are acknowledged no-ops.
// Frames with a bad CRC or framing are counted (heartbeat rx_errors) and not answered: their
// command id cannot be trusted.
//
// Outgoing frames go into a fixed ring of kTxCapacity bytes; a frame that does not fit whole is
// dropped and counted (heartbeat tx_dropped), so the host never sees half a frame.
//
// No heap, no exceptions. Threads: the main-loop calls and the interrupt calls share only the
// scheduler's and the meter's queues and counters (see scheduler.h); the commands that start or
// stop a run change the timers' state before enabling / after disabling their interrupts.

#include <cstddef>
#include <cstdint>

#include "rigcal/trigger_core/exposure_meter.h"
#include "rigcal/trigger_core/ideal_line_timers.h"
#include "rigcal/trigger_core/line_timers.h"
#include "rigcal/trigger_core/scheduler.h"
#include "rigcal/trigger_core/trigger_config.h"
#include "rigcal/trigger_protocol/frame_codec.h"

namespace rigcal::trigger_core {

inline constexpr uint16_t kFirmwareVersion = 2;

// What the board tells the host in its Hello (messages.h ClockStatusBit).
struct BoardInfo {
  uint8_t clock_status = 0;
  uint8_t hse_mhz = 0;
};

class TriggerApp final : public CompareHandler {
 public:
  static constexpr size_t kTxCapacity = 1024;

  explicit TriggerApp(LineTimers* timers) : timers_(timers) {}

  void Boot(uint64_t now_us, BoardInfo board = {});
  void OnRxByte(uint8_t byte, uint64_t now_us);
  // Sends the reports whose time has come, and a heartbeat when due.
  void Poll(uint64_t now_us);
  // Compare context.
  void OnCompare(int line) override { scheduler_.OnCompare(line, timers_); }
  // Capture context: a wired line's input made the edge it waited for, at count `count32`.
  void OnCapture(int line, uint32_t count32) { meter_.OnCapture(line, count32, scheduler_); }
  void OnOvercapture(int line) { meter_.OnOvercapture(line); }
  const ExposureMeter& meter() const { return meter_; }
  // Next byte to transmit; false when the queue is empty.
  bool PopTx(uint8_t* byte);
  size_t tx_pending() const { return tx_size_; }

  const Scheduler& scheduler() const { return scheduler_; }
  const TriggerConfig& config() const { return config_; }
  uint32_t rx_errors() const { return decoder_.stats().Errors(); }
  // Frames dropped for a full transmit queue, and reports dropped for a full report queue.
  uint32_t tx_dropped() const {
    return tx_dropped_ + scheduler_.dropped_reports() + meter_.dropped();
  }

 private:
  void HandleCommand(const proto::Message& m, uint64_t now_us);
  void Answer(uint16_t id, uint8_t type, ConfigProblem problem);
  void StartRun(uint64_t now_us);
  void SendHeartbeat(uint64_t now_us);
  void SendHello(uint64_t now_us);
  void Send(const proto::Message& m);

  LineTimers* timers_;
  BoardInfo board_;
  Scheduler scheduler_;
  ExposureMeter meter_;
  TriggerConfig config_;
  proto::MessageDecoder decoder_;
  uint64_t next_heartbeat_us_ = 0;
  uint8_t tx_[kTxCapacity] = {};
  size_t tx_head_ = 0;  // next byte to send
  size_t tx_size_ = 0;
  uint32_t tx_dropped_ = 0;
};

}  // namespace rigcal::trigger_core
