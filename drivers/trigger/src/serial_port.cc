// SPDX-License-Identifier: Apache-2.0
#include "rigcal/trigger/serial_port.h"

#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <cstring>

namespace rigcal::trigger {
namespace {

std::string SerialErrno(const std::string& what) { return what + ": " + std::strerror(errno); }

bool BaudConstant(int baud, speed_t* out) {
  switch (baud) {
    case 9600:
      *out = B9600;
      return true;
    case 19200:
      *out = B19200;
      return true;
    case 38400:
      *out = B38400;
      return true;
    case 57600:
      *out = B57600;
      return true;
    case 115200:
      *out = B115200;
      return true;
    case 230400:
      *out = B230400;
      return true;
    case 460800:
      *out = B460800;
      return true;
    case 921600:
      *out = B921600;
      return true;
    case 1000000:
      *out = B1000000;
      return true;
    case 2000000:
      *out = B2000000;
      return true;
    case 4000000:
      *out = B4000000;
      return true;
  }
  return false;
}

}  // namespace

int64_t ByteStream::NowNs() const {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

Expected<std::unique_ptr<SerialPort>> SerialPort::Open(const std::string& path, int baud) {
  speed_t speed;
  if (!BaudConstant(baud, &speed)) {
    return Error{path + ": unsupported baud rate " + std::to_string(baud)};
  }
  const int fd = open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return Error{SerialErrno(path + ": open")};
  termios tio{};
  if (tcgetattr(fd, &tio) != 0) {
    const std::string error = SerialErrno(path + ": tcgetattr (not a terminal?)");
    close(fd);
    return Error{error};
  }
  cfmakeraw(&tio);
  tio.c_cflag |= CLOCAL | CREAD;
  tio.c_cflag &= ~(CSTOPB | CRTSCTS);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  cfsetispeed(&tio, speed);
  cfsetospeed(&tio, speed);
  if (tcsetattr(fd, TCSANOW, &tio) != 0) {
    const std::string error = SerialErrno(path + ": tcsetattr");
    close(fd);
    return Error{error};
  }
  tcflush(fd, TCIOFLUSH);
  return std::unique_ptr<SerialPort>(new SerialPort(fd, path));
}

SerialPort::~SerialPort() {
  if (fd_ >= 0) close(fd_);
}

Expected<size_t> SerialPort::Read(uint8_t* data, size_t size, int timeout_ms) {
  pollfd p{fd_, POLLIN, 0};
  const int ready = poll(&p, 1, timeout_ms);
  if (ready < 0) {
    if (errno == EINTR) return size_t{0};
    return Error{SerialErrno(path_ + ": poll")};
  }
  if (ready == 0) return size_t{0};
  if (p.revents & (POLLERR | POLLNVAL)) return Error{path_ + ": device error"};
  const ssize_t n = read(fd_, data, size);
  if (n < 0) {
    if (errno == EAGAIN || errno == EINTR) return size_t{0};
    return Error{SerialErrno(path_ + ": read")};
  }
  if (n == 0 && (p.revents & POLLHUP)) return Error{path_ + ": hung up"};
  return static_cast<size_t>(n);
}

Status SerialPort::Write(const uint8_t* data, size_t size) {
  size_t done = 0;
  while (done < size) {
    const ssize_t n = write(fd_, data + done, size - done);
    if (n < 0) {
      if (errno == EAGAIN || errno == EINTR) {
        pollfd p{fd_, POLLOUT, 0};
        poll(&p, 1, 100);
        continue;
      }
      return Error{SerialErrno(path_ + ": write")};
    }
    done += static_cast<size_t>(n);
  }
  return Status::Ok();
}

}  // namespace rigcal::trigger
