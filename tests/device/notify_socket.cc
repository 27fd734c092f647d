// SPDX-License-Identifier: Apache-2.0
#include "notify_socket.h"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <sstream>

namespace rigcal::device_test {

NotifySocket::NotifySocket(std::string path) : path_(std::move(path)) {
  sockaddr_un address{};
  if (path_.size() >= sizeof(address.sun_path)) {
    error_ = path_ + ": too long for a Unix socket";
    return;
  }
  fd_ = socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) {
    error_ = std::string("socket: ") + std::strerror(errno);
    return;
  }
  unlink(path_.c_str());
  address.sun_family = AF_UNIX;
  std::strncpy(address.sun_path, path_.c_str(), sizeof(address.sun_path) - 1);
  if (bind(fd_, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) != 0) {
    error_ = path_ + ": bind: " + std::strerror(errno);
    return;
  }
  thread_ = std::thread([this] { Receive(); });
}

NotifySocket::~NotifySocket() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  if (fd_ >= 0) close(fd_);
  unlink(path_.c_str());
}

void NotifySocket::Receive() {
  char buffer[4096];
  while (!stop_) {
    pollfd fds{fd_, POLLIN, 0};
    if (poll(&fds, 1, 50) <= 0) continue;
    const ssize_t n = recv(fd_, buffer, sizeof(buffer), MSG_DONTWAIT);
    if (n <= 0) continue;
    std::lock_guard<std::mutex> lock(mutex_);
    messages_.push_back({Clock::now(), std::string(buffer, static_cast<size_t>(n))});
  }
}

std::vector<NotifySocket::Message> NotifySocket::Messages() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return messages_;
}

std::vector<NotifySocket::Clock::time_point> NotifySocket::Times(const std::string& line) const {
  std::vector<Clock::time_point> times;
  for (const Message& m : Messages()) {
    std::istringstream in(m.text);
    for (std::string l; std::getline(in, l);) {
      if (l == line) {
        times.push_back(m.at);
        break;
      }
    }
  }
  return times;
}

}  // namespace rigcal::device_test
