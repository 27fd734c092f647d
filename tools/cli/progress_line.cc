// SPDX-License-Identifier: Apache-2.0
#include "progress_line.h"

#include <spdlog/sinks/base_sink.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <cstdio>
#include <memory>
#include <mutex>

#include "command_line.h"

namespace rigcal::cli {
namespace {

// The progress line on the terminal now, shared by the display and the log sink.
struct ActiveLine {
  std::mutex mutex;
  bool active = false;
  std::string text;
};

ActiveLine& Active() {
  static ActiveLine line;
  return line;
}

class ProgressAwareSink : public spdlog::sinks::base_sink<std::mutex> {
 protected:
  void sink_it_(const spdlog::details::log_msg& msg) override {
    spdlog::memory_buf_t formatted;
    formatter_->format(msg, formatted);
    ActiveLine& line = Active();
    std::lock_guard<std::mutex> lock(line.mutex);
    if (line.active) std::fputs("\r\033[K", stderr);
    std::fwrite(formatted.data(), 1, formatted.size(), stderr);
    if (line.active) std::fprintf(stderr, "%s\033[K", line.text.c_str());
    std::fflush(stderr);
  }
  void flush_() override { std::fflush(stderr); }
};

}  // namespace

ProgressLine::ProgressLine() : tty_(::isatty(STDERR_FILENO) == 1) {}

ProgressLine::~ProgressLine() {
  ActiveLine& line = Active();
  std::lock_guard<std::mutex> lock(line.mutex);
  if (line.active) std::fputs("\n", stderr);
  line.active = false;
}

void ProgressLine::Show(const std::string& text, bool final) {
  if (QuietRequested()) return;
  ActiveLine& line = Active();
  std::lock_guard<std::mutex> lock(line.mutex);
  if (!tty_) {
    std::fprintf(stderr, "%s\n", text.c_str());
    return;
  }
  std::fprintf(stderr, "\r%s\033[K%s", text.c_str(), final ? "\n" : "");
  std::fflush(stderr);
  line.active = !final;
  line.text = text;
  shown_ = true;
}

void InstallProgressAwareLogging(const std::vector<std::string>& modules) {
  auto sink = std::make_shared<ProgressAwareSink>();
  sink->set_pattern("[%H:%M:%S.%e] [%n] [%l] %v");
  for (const std::string& module : modules) {
    if (spdlog::get(module)) continue;
    auto logger = std::make_shared<spdlog::logger>(module, sink);
    spdlog::register_logger(logger);
  }
}

}  // namespace rigcal::cli
