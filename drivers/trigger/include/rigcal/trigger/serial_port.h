// SPDX-License-Identifier: Apache-2.0
#pragma once
// The byte stream of the trigger link: a serial port (termios: a USB CDC/UART adapter, or a
// pseudo-terminal such as QEMU's `-serial pty`), or a simulated stream (rigcal_sim's
// SimulatedTriggerStream).

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "rigcal/base/status.h"

namespace rigcal::trigger {

class ByteStream {
 public:
  virtual ~ByteStream() = default;
  // Reads up to `size` bytes into `data`, waiting at most `timeout_ms` for the first one.
  // Returns the count (0 after the timeout), or an error (device gone). One reader thread.
  virtual Expected<size_t> Read(uint8_t* data, size_t size, int timeout_ms) = 0;
  // Writes all `size` bytes (blocking). One writer thread (may differ from the reader).
  virtual Status Write(const uint8_t* data, size_t size) = 0;
  // CLOCK_MONOTONIC now, ns: the time a Read's bytes are stamped with. A simulated stream
  // returns its simulated host time.
  virtual int64_t NowNs() const;
};

// A serial port in raw mode (8N1, no flow control, no echo, no line editing).
class SerialPort final : public ByteStream {
 public:
  // Opens `path` (e.g. /dev/ttyACM0, /dev/pts/3) at `baud` (one of the standard termios rates:
  // 9600 ... 4000000). Errors name the path and the failing call.
  static Expected<std::unique_ptr<SerialPort>> Open(const std::string& path, int baud);
  ~SerialPort() override;

  Expected<size_t> Read(uint8_t* data, size_t size, int timeout_ms) override;
  Status Write(const uint8_t* data, size_t size) override;
  const std::string& path() const { return path_; }

 private:
  SerialPort(int fd, std::string path) : fd_(fd), path_(std::move(path)) {}
  int fd_ = -1;
  std::string path_;
};

}  // namespace rigcal::trigger
