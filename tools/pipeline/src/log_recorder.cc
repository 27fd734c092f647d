// SPDX-License-Identifier: Apache-2.0
#include "rigcal/pipeline/log_recorder.h"

#include <algorithm>
#include <stdexcept>
#include <utility>

#include "rigcal/lcm/channels.h"

namespace rigcal::pipeline {
namespace {

// A device whose frames are also recorded.
class RecordingDevice final : public capture::CameraDevice {
 public:
  RecordingDevice(std::unique_ptr<capture::CameraDevice> device, int camera, LogRecorder* recorder)
      : device_(std::move(device)), camera_(camera), recorder_(recorder) {}
  const std::string& name() const override { return device_->name(); }
  double frame_rate_hz() const override { return device_->frame_rate_hz(); }
  Expected<std::optional<capture::Frame>> Grab() override {
    Expected<std::optional<capture::Frame>> grabbed = device_->Grab();
    if (grabbed.ok() && grabbed->has_value()) recorder_->RecordFrame(camera_, **grabbed);
    return grabbed;
  }
  void Interrupt() override { device_->Interrupt(); }

 private:
  std::unique_ptr<capture::CameraDevice> device_;
  int camera_;
  LogRecorder* recorder_;
};

}  // namespace

Status RecorderOptions::Check() const {
  if (const Status status = image.Check(); !status.ok()) return status.Prefixed("image");
  if (const Status status = log.Check(); !status.ok()) return status.Prefixed("log");
  if (queue_events < 1) return Error{"queue_events: must be >= 1"};
  return Status::Ok();
}

int64_t RecorderStats::FramesTotal() const {
  int64_t total = 0;
  for (int64_t n : frames) total += n;
  return total;
}

int64_t RecorderStats::DroppedTotal() const {
  int64_t total = dropped_disk;
  for (int64_t n : dropped_capture) total += n;
  return total;
}

LogRecorder::LogRecorder(std::vector<std::string> names, const RecorderOptions& options,
                         std::unique_ptr<lcm::LogWriter> writer)
    : names_(std::move(names)),
      options_(options),
      writer_(std::move(writer)),
      queue_(static_cast<size_t>(options.queue_events)) {
  MutexLock lock(mutex_);
  stats_.frames.assign(names_.size(), 0);
  stats_.dropped_capture.assign(names_.size(), 0);
  stats_.files = writer_->files();
  last_seq_.assign(names_.size(), -1);
}

Expected<std::unique_ptr<LogRecorder>> LogRecorder::Open(const std::string& path,
                                                         std::vector<std::string> names,
                                                         const RecorderOptions& options) {
  if (const Status status = options.Check(); !status.ok()) {
    return Error{"RecorderOptions: " + status.message()};
  }
  auto writer = lcm::LogWriter::Open(path, options.log);
  if (!writer) return writer.status();
  std::unique_ptr<LogRecorder> recorder(
      new LogRecorder(std::move(names), options, std::move(*writer)));
  recorder->writer_thread_ = std::thread([r = recorder.get()] { r->WriterLoop(); });
  return recorder;
}

LogRecorder::~LogRecorder() { (void)Stop(); }

std::unique_ptr<capture::CameraDevice> LogRecorder::Tap(
    std::unique_ptr<capture::CameraDevice> device, int camera) {
  if (camera < 0 || static_cast<size_t>(camera) >= names_.size()) {
    throw std::invalid_argument("LogRecorder::Tap: camera index out of range");
  }
  return std::make_unique<RecordingDevice>(std::move(device), camera, this);
}

void LogRecorder::RecordFrame(int camera, const capture::Frame& frame) {
  if (stopped_.load()) return;
  const auto index = static_cast<size_t>(camera);
  {
    MutexLock lock(mutex_);
    if (last_seq_[index] >= 0 && frame.seq > last_seq_[index] + 1) {
      stats_.dropped_capture[index] += frame.seq - last_seq_[index] - 1;
    }
    if (frame.seq >= 0) last_seq_[index] = frame.seq;
  }
  Expected<std::vector<uint8_t>> bytes = EncodeImageEvent(frame, names_, camera, options_.image);
  if (!bytes) return Fail(bytes.error());
  Enqueue(Event{camera, lcm::ImageChannel(names_[index]), frame.t_ns / 1000, std::move(*bytes)});
}

void LogRecorder::Record(std::string channel, int64_t utime, std::vector<uint8_t> data) {
  if (stopped_.load()) return;
  Enqueue(Event{-1, std::move(channel), utime, std::move(data)});
}

void LogRecorder::Enqueue(Event event) {
  const uint64_t dropped_before = queue_.dropped();
  const bool queued =
      options_.lossless ? queue_.PushWait(std::move(event)) : queue_.Push(std::move(event));
  if (!queued) return;  // stopped
  const uint64_t dropped = queue_.dropped() - dropped_before;
  if (dropped > 0) {
    MutexLock lock(mutex_);
    stats_.dropped_disk += static_cast<int64_t>(dropped);
  }
}

void LogRecorder::Fail(const std::string& error) {
  MutexLock lock(mutex_);
  if (stats_.error.empty()) stats_.error = error;
}

void LogRecorder::WriterLoop() {
  int64_t last_utime = 0;
  bool failed = false;
  while (std::optional<Event> event = queue_.Pop()) {
    if (failed) continue;  // drain: producers must not block on a dead disk
    last_utime = std::max(last_utime, event->utime);
    const Status status =
        writer_->Write(event->channel, last_utime, event->data.data(), event->data.size());
    MutexLock lock(mutex_);
    if (!status.ok()) {
      failed = true;
      if (stats_.error.empty()) stats_.error = status.message();
      continue;
    }
    stats_.bytes = writer_->bytes();
    stats_.events = writer_->events();
    stats_.files = writer_->files();
    if (event->camera >= 0) {
      ++stats_.frames[static_cast<size_t>(event->camera)];
    } else {
      ++stats_.other_events;
    }
  }
}

Status LogRecorder::Stop() {
  if (!stopped_.exchange(true)) {
    queue_.Stop();  // the writer drains what is queued, then ends
    if (writer_thread_.joinable()) writer_thread_.join();
    const Status closed = writer_->Close();
    if (!closed.ok()) Fail(closed.message());
  }
  MutexLock lock(mutex_);
  if (!stats_.error.empty()) return Error{stats_.error};
  return Status::Ok();
}

RecorderStats LogRecorder::Stats() const {
  MutexLock lock(mutex_);
  return stats_;
}

}  // namespace rigcal::pipeline
