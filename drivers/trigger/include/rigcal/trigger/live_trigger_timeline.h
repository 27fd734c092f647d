// SPDX-License-Identifier: Apache-2.0
#pragma once
// LiveTriggerTimeline: a trigger generator on a serial port (a USB CDC device, a USB-UART
// adapter, or QEMU's `-serial pty`) as the TriggerTimeline of externally triggered cameras.
// Start opens the port, applies the settings (TriggerSession) and starts the receiver thread
// (TriggerReceiver), which feeds the matcher by itself: AdvanceTo is a no-op. Capture sources
// start it before their cameras and stop it after them.
//
// How a frame's stamp relates to its exposure centre depends on the source (FrameStamp):
// CameraTriggerSpec::stamp_offset_ns is StampOffsetNs(stamp, exposure, readout).
//
// Threads: the owner calls Start/Stop; matcher(), problem(), stats() and NextTick() any
// thread.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "rigcal/base/status.h"
#include "rigcal/base/thread_annotations.h"
#include "rigcal/trigger/trigger_link.h"
#include "rigcal/trigger/trigger_matcher.h"
#include "rigcal/trigger/trigger_receiver.h"
#include "rigcal/trigger/trigger_timeline.h"

namespace rigcal::trigger {

// Where in its exposure a capture source stamps a frame.
enum class FrameStamp {
  kStartOfExposure,  // V4L2 (start-of-exposure flag, or end-of-frame moved back), libcamera
  kExposureCentre,   // the simulated rig; recordings stamped at mid-exposure
  kEndOfFrame,       // end of exposure plus the sensor readout
};
// "start_of_exposure", "exposure_centre", "end_of_frame".
const char* ToString(FrameStamp stamp);
std::optional<FrameStamp> FrameStampFromString(const std::string& text);
// Frame stamp - exposure centre, ns: -exposure/2, 0, or +exposure/2 + readout.
int64_t StampOffsetNs(FrameStamp stamp, int64_t exposure_us, int64_t readout_us);

struct LiveTriggerOptions {
  std::string port;  // serial device: /dev/ttyACM0, /dev/ttyUSB0, /dev/pts/N
  int baud = 115200;
  // The reports cross a UART at `baud` on their way (the MCU's USART, e.g. through a USB-UART
  // adapter): each message is stamped earlier by the wire time of its bytes and of the bytes
  // read after it (TriggerLink::set_uart_byte_ns). false: no UART paces the bytes (a USB CDC
  // device, an emulator's pty).
  bool uart_wire = true;
  TriggerSettings settings;
  TriggerMatcherOptions matcher;
  int command_timeout_ms = 1000;  // per command, [10, 60000]
  // Listen this long for the generator to speak (its boot Hello or a heartbeat) before
  // configuring it: bytes sent while it boots are lost. [0, 60000]
  int listen_ms = 1000;
  Status Check() const;
};

class LiveTriggerTimeline final : public TriggerTimeline {
 public:
  // Opens the port, configures and starts the generator, then the receiver thread. Errors name
  // the port and what failed (no such device, a refused setting by field, no answer).
  static Expected<std::unique_ptr<LiveTriggerTimeline>> Start(const LiveTriggerOptions& options);
  ~LiveTriggerTimeline() override;

  void AdvanceTo(int64_t) override {}  // the receiver thread delivers the messages
  const TriggerMatcher& matcher() const override { return matcher_; }

  // The first trigger tick whose exposure centre (phase offset 0) lies at or after
  // `not_before_ns`, once the clock map is synced: where a source paced from the trigger (a
  // simulated rig in real time, an image-folder replay) puts its frame 0. Waits up to
  // `timeout_ns` for sync; errors name the port (the link failed, no pulse within the time).
  struct Tick {
    uint64_t mcu_us = 0;  // its time on the generator's clock
    int64_t host_ns = 0;  // mapped to the host clock as the map is now
  };
  Expected<Tick> NextTick(int64_t not_before_ns, int64_t timeout_ns) const;

  // Ends the receiver thread and stops the generator. Idempotent.
  void Stop();
  // "" while the link runs fine, else "<port>: <why the receiver stopped>".
  std::string problem() const;
  const std::string& port() const { return options_.port; }
  const LiveTriggerOptions& options() const { return options_; }

 private:
  explicit LiveTriggerTimeline(LiveTriggerOptions options)
      : options_(std::move(options)), matcher_(options_.matcher) {}

  struct LastPulse {
    bool seen = false;
    uint32_t seq = 0;
    uint64_t mcu_us = 0;
  };
  LiveTriggerOptions options_;
  TriggerMatcher matcher_;
  std::unique_ptr<TriggerReceiver> receiver_;
  mutable Mutex mutex_;
  LastPulse last_ RIGCAL_GUARDED_BY(mutex_);  // written by the receiver thread
};

}  // namespace rigcal::trigger
