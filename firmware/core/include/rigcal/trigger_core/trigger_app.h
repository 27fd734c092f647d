#pragma once
// TriggerApp: the trigger generator's firmware logic without the board: command parsing and
// answers, the scheduler, heartbeats and the outgoing byte queue. The board port feeds it
// received bytes and the time, drains its transmit queue into the UART and drives the lines.
//
//   boot:       Boot(now)                      queues a Hello (the host detects the restart)
//   main loop:  OnRxByte(b, now) for every received byte; Poll(now); PopTx() into the UART
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
// No heap, no exceptions; not thread-safe (the board calls it from its main loop only).

#include <cstddef>
#include <cstdint>

#include "rigcal/trigger_core/scheduler.h"
#include "rigcal/trigger_core/trigger_config.h"
#include "rigcal/trigger_protocol/frame_codec.h"

namespace rigcal::trigger_core {

inline constexpr uint16_t kFirmwareVersion = 1;

// Drives the physical trigger lines (board: GPIO; tests: a recorder).
class LineDriver {
 public:
  virtual void SetLines(uint8_t high_mask) = 0;

 protected:
  ~LineDriver() = default;
};

class TriggerApp final : private SchedulerListener {
 public:
  static constexpr size_t kTxCapacity = 1024;

  explicit TriggerApp(LineDriver* lines) : lines_(lines) {}

  void Boot(uint64_t now_us);
  void OnRxByte(uint8_t byte, uint64_t now_us);
  void Poll(uint64_t now_us);
  // Next byte to transmit; false when the queue is empty.
  bool PopTx(uint8_t* byte);
  size_t tx_pending() const { return tx_size_; }

  const Scheduler& scheduler() const { return scheduler_; }
  const TriggerConfig& config() const { return config_; }
  uint32_t rx_errors() const { return decoder_.stats().Errors(); }
  uint32_t tx_dropped() const { return tx_dropped_; }

 private:
  void OnLines(uint8_t high_mask) override;
  void OnPulse(const proto::PulseReport& report) override;
  void HandleCommand(const proto::Message& m, uint64_t now_us);
  void Answer(uint16_t id, uint8_t type, ConfigProblem problem);
  void SendHeartbeat(uint64_t now_us);
  void SendHello(uint64_t now_us);
  void Send(const proto::Message& m);

  LineDriver* lines_;
  Scheduler scheduler_;
  TriggerConfig config_;
  proto::MessageDecoder decoder_;
  uint64_t next_heartbeat_us_ = 0;
  uint8_t tx_[kTxCapacity] = {};
  size_t tx_head_ = 0;  // next byte to send
  size_t tx_size_ = 0;
  uint32_t tx_dropped_ = 0;
};

}  // namespace rigcal::trigger_core
