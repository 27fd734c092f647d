// SPDX-License-Identifier: Apache-2.0
#pragma once
// A trigger generator speaking the firmware's protocol (firmware/protocol) on the master side of
// a pseudo-terminal, for tests of the live trigger path without hardware: it acknowledges every
// command, sends heartbeats, and once started reports tick k at its MCU time
// T_k = t_start + k * period as soon as the host clock passes it (the delay is the poll loop's,
// 0-1 ms). Its MCU clock is the host's CLOCK_MONOTONIC since `boot`, so the true host time of
// a pulse is known (TrueHostNs). set_late_start(late, span) makes every report and heartbeat
// from Start until `span` after the trigger's start reach the host `late` late, then on time
// (those still held back then are dropped, so that no arrival is partly late): what a loaded host
// sees at the start, on which the host's clock map is first fitted, then restarts. Header-only.

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <deque>
#include <mutex>
#include <string>
#include <thread>
#include <utility>

#include "rigcal/capture/v4l2_timestamp.h"
#include "rigcal/trigger_protocol/frame_codec.h"

namespace rigcal::testing {

class FakeTriggerGenerator {
 public:
  ~FakeTriggerGenerator() { Stop(); }

  // Opens the pty pair; the host opens slave_path().
  bool Open(std::string* error) {
    master_ = posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC);  // not inherited by a child rigcal
    if (master_ < 0 || grantpt(master_) != 0 || unlockpt(master_) != 0) {
      *error = "posix_openpt failed";
      return false;
    }
    slave_path_ = ptsname(master_);
    // Keep a slave open so the master never sees a hang-up while the host reopens it.
    slave_ = open(slave_path_.c_str(), O_RDWR | O_NOCTTY | O_CLOEXEC);
    termios tio{};
    if (slave_ < 0 || tcgetattr(slave_, &tio) != 0) {
      *error = "cannot open " + slave_path_;
      return false;
    }
    cfmakeraw(&tio);
    tcsetattr(slave_, TCSANOW, &tio);
    boot_ns_ = capture::MonotonicNowNs() - 1'000'000'000;
    return true;
  }
  // Before Start: the reports and heartbeats reach the host `late_ns` late until `span_ns` after
  // the trigger starts.
  void set_late_start(int64_t late_ns, int64_t span_ns) {
    late_ns_ = late_ns;
    late_span_ns_ = span_ns;
    late_until_ns_ = INT64_MAX;  // until the trigger starts
  }
  // Host time from which messages are on time again (INT64_MIN without a late start, INT64_MAX
  // before the trigger starts).
  int64_t late_until_ns() const { return late_until_ns_.load(); }
  // late_until_ns() + `settle_ns` (>= 0), saturated.
  int64_t settled_from_ns(int64_t settle_ns) const {
    const int64_t until = late_until_ns();
    return until > INT64_MAX - settle_ns ? INT64_MAX : until + settle_ns;
  }
  // Answers commands (`answer` false: stays silent, a dead generator).
  void Start(bool answer = true) {
    answer_ = answer;
    thread_ = std::thread([this] { Loop(); });
  }
  void Stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    if (slave_ >= 0) close(slave_);
    if (master_ >= 0) close(master_);
    slave_ = master_ = -1;
  }

  const std::string& slave_path() const { return slave_path_; }
  // True host time (ns) of tick `seq`'s exposure centre (the last start); -1 before one.
  int64_t TrueHostNs(int64_t seq) const {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!started_) return -1;
    return boot_ns_ + static_cast<int64_t>(start_us_ + seq * period_us_) * 1000;
  }

 private:
  uint64_t McuUs() const {
    return static_cast<uint64_t>((capture::MonotonicNowNs() - boot_ns_) / 1000);
  }
  void Send(const trigger_protocol::Message& m) {
    uint8_t frame[trigger_protocol::kMaxFrameSize];
    const size_t n = trigger_protocol::EncodeFrame(m, frame, sizeof(frame));
    if (write(master_, frame, n) != static_cast<ssize_t>(n)) failed_writes_++;
  }
  // A report or heartbeat: held back `late_ns_` during the late start.
  void SendTimed(const trigger_protocol::Message& m) {
    const int64_t now = capture::MonotonicNowNs();
    if (late_ns_ > 0 && now < late_until_ns_.load()) {
      held_.emplace_back(now + late_ns_, m);
    } else {
      Send(m);
    }
  }
  // Sends the held messages that are due; once the late start is over, drops the others.
  void ReleaseHeld() {
    const int64_t now = capture::MonotonicNowNs();
    while (!held_.empty() && held_.front().first <= now) {
      Send(held_.front().second);
      held_.pop_front();
    }
    if (now >= late_until_ns_.load()) held_.clear();
  }
  void OnCommand(const trigger_protocol::Message& c) {
    using trigger_protocol::MessageType;
    uint16_t id = c.simple.command_id;
    switch (c.type) {
      case MessageType::kSetRate:
        id = c.set_rate.command_id;
        rate_mhz_ = c.set_rate.rate_mhz;
        break;
      case MessageType::kSetLine:
        id = c.set_line.command_id;
        if (c.set_line.enabled) {
          line_mask_ = static_cast<uint8_t>(line_mask_ | (1u << c.set_line.line));
        } else {
          line_mask_ = static_cast<uint8_t>(line_mask_ & ~(1u << c.set_line.line));
        }
        break;
      case MessageType::kSetHeartbeat:
        id = c.set_heartbeat.command_id;
        heartbeat_ms_ = c.set_heartbeat.period_ms;
        break;
      case MessageType::kStart: {
        std::lock_guard<std::mutex> lock(mutex_);
        running_ = started_ = true;
        if (late_ns_ > 0) late_until_ns_ = capture::MonotonicNowNs() + late_span_ns_;
        period_us_ = trigger_protocol::PeriodUs(rate_mhz_);
        start_us_ = McuUs() + 10'000;
        next_seq_ = 0;
        break;
      }
      case MessageType::kStop: {
        std::lock_guard<std::mutex> lock(mutex_);
        running_ = false;
        break;
      }
      default:
        break;
    }
    trigger_protocol::Message ack;
    ack.type = MessageType::kAck;
    ack.ack.command_id = id;
    ack.ack.command = c.type;
    Send(ack);
  }
  void Loop() {
    using trigger_protocol::MessageType;
    trigger_protocol::MessageDecoder decoder;
    uint64_t next_heartbeat_us = McuUs();
    while (!stop_) {
      pollfd p{master_, POLLIN, 0};
      if (poll(&p, 1, 1) > 0 && (p.revents & POLLIN)) {
        uint8_t buffer[256];
        const ssize_t n = read(master_, buffer, sizeof(buffer));
        for (ssize_t i = 0; i < n; ++i) {
          if (decoder.Push(buffer[i]) == trigger_protocol::DecodeEvent::kMessage && answer_) {
            OnCommand(decoder.message());
          }
        }
      }
      if (!answer_) continue;
      ReleaseHeld();
      const uint64_t now = McuUs();
      std::lock_guard<std::mutex> lock(mutex_);
      // Pulses first: a heartbeat stamped now must not precede a pulse report of an earlier
      // tick (the host takes MCU time going back for a reboot).
      while (running_ && now >= start_us_ + next_seq_ * uint64_t{period_us_}) {
        trigger_protocol::Message r;
        r.type = MessageType::kPulseReport;
        r.pulse.line_mask = line_mask_;
        r.pulse.seq = next_seq_;
        r.pulse.mcu_time_us = start_us_ + next_seq_ * uint64_t{period_us_};
        SendTimed(r);
        ++next_seq_;
      }
      if (heartbeat_ms_ > 0 && now >= next_heartbeat_us) {
        trigger_protocol::Message h;
        h.type = MessageType::kHeartbeat;
        h.heartbeat.mcu_time_us = now;
        h.heartbeat.running = running_ ? 1 : 0;
        h.heartbeat.next_seq = next_seq_;
        SendTimed(h);
        next_heartbeat_us = now + heartbeat_ms_ * 1000ull;
      }
    }
  }

  int master_ = -1;
  int slave_ = -1;
  std::string slave_path_;
  int64_t boot_ns_ = 0;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  bool answer_ = true;
  int failed_writes_ = 0;
  int64_t late_ns_ = 0;                                             // set_late_start
  int64_t late_span_ns_ = 0;                                        // set_late_start
  std::atomic<int64_t> late_until_ns_{INT64_MIN};                   // set at kStart
  std::deque<std::pair<int64_t, trigger_protocol::Message>> held_;  // release time, message
  // The loop thread's configuration.
  uint32_t rate_mhz_ = 20'000;
  uint8_t line_mask_ = 0;
  uint16_t heartbeat_ms_ = 100;
  mutable std::mutex mutex_;  // guards the running state read by TrueHostNs
  bool running_ = false;
  bool started_ = false;  // started once: TrueHostNs is valid
  uint64_t start_us_ = 0;
  uint32_t period_us_ = 50'000;
  uint32_t next_seq_ = 0;
};

}  // namespace rigcal::testing
