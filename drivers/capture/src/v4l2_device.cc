// SPDX-License-Identifier: Apache-2.0
#include "rigcal/capture/v4l2_device.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <vector>

#include "rigcal/base/logging.h"
#include "rigcal/capture/v4l2_timestamp.h"
#include "v4l2_controls.h"
#include "v4l2_node.h"

namespace rigcal::capture {
namespace {

constexpr int kPollTimeoutMs = 100;  // bounds how late a frame timeout is noticed
constexpr int64_t kFirstBackoffNs = 100'000'000;

std::string V4l2Errno(const char* what) { return std::string(what) + ": " + std::strerror(errno); }

// The steps of V4l2Device::Connect. Errors start with the node.

// Opens `node` into *fd (closed by the caller's stream) and checks that it is a single-planar
// capture device with streaming I/O; fills in its identity.
Status OpenCaptureNode(const std::string& node, int* fd, V4l2Negotiated* n) {
  *fd = open(node.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (*fd < 0) return Error{node + ": " + V4l2Errno("open")};
  auto info = v4l2::QueryNode(*fd);
  if (!info) return Error{node + ": " + info.error()};
  if (!v4l2::CanCapture(*info)) {
    return Error{node + " (" + info->card +
                 ") is not a single-planar capture device with "
                 "streaming I/O"};
  }
  n->node = node;
  n->card = info->card;
  n->bus_info = info->bus_info;
  n->driver = info->driver;
  return Status::Ok();
}

// The first of the `preferred` pixel formats the driver lists; the error names both lists.
Expected<PixelFormat> ChoosePixelFormat(int fd, const std::string& node,
                                        const std::vector<PixelFormat>& preferred) {
  std::vector<uint32_t> offered;
  v4l2_fmtdesc desc{};
  desc.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  while (v4l2::Ioctl(fd, VIDIOC_ENUM_FMT, &desc) == 0) {
    offered.push_back(desc.pixelformat);
    ++desc.index;
  }
  for (PixelFormat f : preferred) {
    if (std::find(offered.begin(), offered.end(), V4l2Fourcc(f)) != offered.end()) return f;
  }
  std::string wanted, has;
  for (PixelFormat f : preferred) wanted += std::string(wanted.empty() ? "" : ", ") + ToString(f);
  for (uint32_t f : offered) has += (has.empty() ? "" : ", ") + FourccText(f);
  return Error{node + ": none of the pixel formats " + wanted +
               " is offered (the driver has: " + (has.empty() ? "none" : has) + ")"};
}

// Sets `format` at width x height; an error when the driver changes either. Fills in the
// fourcc and the image layout.
Status SetPixelFormat(int fd, const std::string& node, PixelFormat chosen, int width, int height,
                      V4l2Negotiated* n) {
  v4l2_format format{};
  format.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  format.fmt.pix.width = static_cast<uint32_t>(width);
  format.fmt.pix.height = static_cast<uint32_t>(height);
  format.fmt.pix.pixelformat = V4l2Fourcc(chosen);
  format.fmt.pix.field = V4L2_FIELD_NONE;
  if (v4l2::Ioctl(fd, VIDIOC_S_FMT, &format) != 0) {
    return Error{node + ": " + V4l2Errno("VIDIOC_S_FMT")};
  }
  if (format.fmt.pix.pixelformat != V4l2Fourcc(chosen)) {
    return Error{node + ": asked for " + ToString(chosen) + ", the driver set " +
                 FourccText(format.fmt.pix.pixelformat)};
  }
  if (static_cast<int>(format.fmt.pix.width) != width ||
      static_cast<int>(format.fmt.pix.height) != height) {
    return Error{node + ": the driver gives " + std::to_string(format.fmt.pix.width) + "x" +
                 std::to_string(format.fmt.pix.height) + " " + ToString(chosen) +
                 " where the camera needs " + std::to_string(width) + "x" + std::to_string(height)};
  }
  n->fourcc = format.fmt.pix.pixelformat;
  n->layout.format = chosen;
  n->layout.width = width;
  n->layout.height = height;
  n->layout.bytes_per_line = static_cast<int>(format.fmt.pix.bytesperline);
  return Status::Ok();
}

// Asks for `frame_rate_hz` (> 0; a refusal is logged for `camera`) and reads back the frame
// interval the driver uses, if it says.
void SetFrameInterval(int fd, const std::string& node, const std::string& camera,
                      double frame_rate_hz, V4l2Negotiated* n) {
  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (frame_rate_hz > 0.0) {
    parm.parm.capture.timeperframe.numerator = 1000;
    parm.parm.capture.timeperframe.denominator =
        static_cast<uint32_t>(std::llround(frame_rate_hz * 1000.0));
    if (v4l2::Ioctl(fd, VIDIOC_S_PARM, &parm) != 0) {
      ModuleLogger("capture")->warn("camera {}: {}: cannot set {} Hz: {}", camera, node,
                                    frame_rate_hz, std::strerror(errno));
    }
  }
  parm = {};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (v4l2::Ioctl(fd, VIDIOC_G_PARM, &parm) == 0 && parm.parm.capture.timeperframe.numerator > 0) {
    n->frame_rate_hz = static_cast<double>(parm.parm.capture.timeperframe.denominator) /
                       parm.parm.capture.timeperframe.numerator;
  }
}

// Requests `count` mmap buffers (the driver must grant at least 2), maps each into `buffers`
// and queues it.
Status MapBuffers(int fd, const std::string& node, int count,
                  std::vector<std::pair<void*, size_t>>* buffers, V4l2Negotiated* n) {
  v4l2_requestbuffers request{};
  request.count = static_cast<uint32_t>(count);
  request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  request.memory = V4L2_MEMORY_MMAP;
  if (v4l2::Ioctl(fd, VIDIOC_REQBUFS, &request) != 0) {
    return Error{node + ": " + V4l2Errno("VIDIOC_REQBUFS (mmap)")};
  }
  if (request.count < 2) {
    return Error{node + ": the driver grants " + std::to_string(request.count) + " buffer(s)"};
  }
  for (uint32_t i = 0; i < request.count; ++i) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    buffer.index = i;
    if (v4l2::Ioctl(fd, VIDIOC_QUERYBUF, &buffer) != 0) {
      return Error{node + ": " + V4l2Errno("VIDIOC_QUERYBUF")};
    }
    void* start =
        mmap(nullptr, buffer.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd, buffer.m.offset);
    if (start == MAP_FAILED) return Error{node + ": " + V4l2Errno("mmap")};
    buffers->emplace_back(start, buffer.length);
    if (v4l2::Ioctl(fd, VIDIOC_QBUF, &buffer) != 0) {
      return Error{node + ": " + V4l2Errno("VIDIOC_QBUF")};
    }
  }
  n->buffers = static_cast<int>(request.count);
  return Status::Ok();
}

}  // namespace

// The open node and its mapped buffers; closing it stops streaming and unmaps.
struct V4l2Device::Stream {
  int fd = -1;
  std::vector<std::pair<void*, size_t>> buffers;
  bool streaming = false;

  ~Stream() {
    if (fd < 0) return;
    if (streaming) {
      v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      v4l2::Ioctl(fd, VIDIOC_STREAMOFF, &type);
    }
    for (auto& [start, length] : buffers) munmap(start, length);
    buffers.clear();
    v4l2_requestbuffers release{};
    release.count = 0;
    release.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    release.memory = V4L2_MEMORY_MMAP;
    v4l2::Ioctl(fd, VIDIOC_REQBUFS, &release);
    close(fd);
  }
};

Expected<std::unique_ptr<V4l2Device>> V4l2Device::Open(std::string name, int camera_index,
                                                       V4l2Options options) {
  if (Status s = options.Check(); !s.ok()) return Error{"camera " + name + ": " + s.message()};
  if (options.formats.empty()) options.formats = DefaultFormatPreference();
  std::unique_ptr<V4l2Device> device(new V4l2Device());
  device->name_ = std::move(name);
  device->camera_index_ = camera_index;
  device->options_ = std::move(options);
  device->wake_fd_ = eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
  if (device->wake_fd_ < 0) return Error{"camera " + device->name_ + ": " + V4l2Errno("eventfd")};
  if (Status s = device->Connect(); !s.ok()) {
    return Error{"camera " + device->name_ + ": " + device->options_.device + ": " + s.message()};
  }
  const V4l2Negotiated& n = device->negotiated_;
  ModuleLogger("capture")->info("camera {}: {} ({}, {}, {}) {} {}x{} at {:.2f} Hz, {} buffers",
                                device->name_, n.node, n.card, n.driver, n.bus_info,
                                FourccText(n.fourcc), n.layout.width, n.layout.height,
                                n.frame_rate_hz, n.buffers);
  return device;
}

V4l2Device::~V4l2Device() {
  stream_.reset();
  if (wake_fd_ >= 0) close(wake_fd_);
}

double V4l2Device::frame_rate_hz() const {
  if (negotiated_.frame_rate_hz > 0.0) return negotiated_.frame_rate_hz;
  return options_.frame_rate_hz > 0.0 ? options_.frame_rate_hz : 30.0;
}

void V4l2Device::Interrupt() {
  interrupted_ = true;
  const uint64_t one = 1;
  if (wake_fd_ >= 0) {
    [[maybe_unused]] const ssize_t written = write(wake_fd_, &one, sizeof(one));
  }
}

V4l2Stats V4l2Device::stats() const {
  MutexLock lock(mutex_);
  return stats_;
}

Status V4l2Device::Connect() {
  auto node = v4l2::ResolveNode(options_.device);
  if (!node) return Error{node.error()};
  auto stream = std::make_unique<Stream>();
  V4l2Negotiated n;
  if (Status s = OpenCaptureNode(*node, &stream->fd, &n); !s.ok()) return s;
  auto format = ChoosePixelFormat(stream->fd, *node, options_.formats);
  if (!format) return Error{format.error()};
  if (Status s = SetPixelFormat(stream->fd, *node, *format, options_.width, options_.height, &n);
      !s.ok()) {
    return s;
  }
  SetFrameInterval(stream->fd, *node, name_, options_.frame_rate_hz, &n);
  auto exposure = v4l2::ApplyControls(stream->fd, options_);
  if (!exposure) return Error{*node + ": " + exposure.error()};
  exposure_ns_ = *exposure;
  if (Status s = MapBuffers(stream->fd, *node, options_.buffers, &stream->buffers, &n); !s.ok()) {
    return s;
  }
  v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (v4l2::Ioctl(stream->fd, VIDIOC_STREAMON, &type) != 0) {
    return Error{*node + ": " + V4l2Errno("VIDIOC_STREAMON")};
  }
  stream->streaming = true;
  stream_ = std::move(stream);
  negotiated_ = n;
  last_sequence_ = -1;
  last_frame_ns_ = MonotonicNowNs();
  MutexLock lock(mutex_);
  stats_.connected = true;
  return Status::Ok();
}

void V4l2Device::Disconnect() {
  stream_.reset();
  MutexLock lock(mutex_);
  stats_.connected = false;
}

Status V4l2Device::Lost(const std::string& why) {
  Disconnect();
  {
    MutexLock lock(mutex_);
    ++stats_.device_losses;
    stats_.last_loss = why;
  }
  ModuleLogger("capture")->warn("camera {}: device {} lost: {}{}", name_, options_.device, why,
                                options_.reconnect ? "; reconnecting" : "");
  if (!options_.reconnect) {
    return Error{"camera " + name_ + ": device " + options_.device + " lost: " + why};
  }
  return Status::Ok();
}

bool V4l2Device::Sleep(int64_t ns) {
  pollfd wake{wake_fd_, POLLIN, 0};
  poll(&wake, 1, static_cast<int>(std::max<int64_t>(1, ns / 1'000'000)));
  return !interrupted_;
}

bool V4l2Device::Reconnect() {
  int64_t backoff_ns = kFirstBackoffNs;
  const auto max_ns = static_cast<int64_t>(options_.reconnect_max_backoff_s * 1e9);
  std::string last_error;
  while (!interrupted_) {
    if (!Sleep(backoff_ns)) return false;
    const Status connected = Connect();
    if (connected.ok()) {
      seq_base_ = last_seq_out_ + 1;
      {
        MutexLock lock(mutex_);
        ++stats_.reconnections;
      }
      ModuleLogger("capture")->info("camera {}: device {} is back as {}", name_, options_.device,
                                    negotiated_.node);
      return true;
    }
    if (connected.message() != last_error) {
      ModuleLogger("capture")->debug("camera {}: reconnecting: {}", name_, connected.message());
      last_error = connected.message();
    }
    backoff_ns = std::min(max_ns, backoff_ns * 2);
  }
  return false;
}

Expected<std::optional<Frame>> V4l2Device::Grab() {
  while (!interrupted_) {
    if (!stream_ && !Reconnect()) break;
    pollfd fds[2] = {{stream_->fd, POLLIN, 0}, {wake_fd_, POLLIN, 0}};
    const int ready = poll(fds, 2, kPollTimeoutMs);
    if (interrupted_) break;
    if (ready < 0) {
      if (errno == EINTR) continue;
      if (Status s = Lost(V4l2Errno("poll")); !s.ok()) return Error{s.message()};
      continue;
    }
    if (ready == 0 || (fds[0].revents & (POLLIN | POLLERR | POLLHUP | POLLNVAL)) == 0) {
      if (options_.frame_timeout_s > 0.0 &&
          MonotonicNowNs() - last_frame_ns_ >
              static_cast<int64_t>(options_.frame_timeout_s * 1e9)) {
        if (Status s = Lost("no frame for " + std::to_string(options_.frame_timeout_s) + " s");
            !s.ok()) {
          return Error{s.message()};
        }
      }
      continue;
    }
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    if (v4l2::Ioctl(stream_->fd, VIDIOC_DQBUF, &buffer) != 0) {
      if (errno == EAGAIN && (fds[0].revents & (POLLERR | POLLHUP | POLLNVAL)) == 0) continue;
      const std::string why =
          errno == EAGAIN ? std::string("poll reports an error") : V4l2Errno("VIDIOC_DQBUF");
      if (Status s = Lost(why); !s.ok()) return Error{s.message()};
      continue;
    }
    const int64_t dequeue_ns = MonotonicNowNs();
    last_frame_ns_ = dequeue_ns;
    const auto sequence = static_cast<int64_t>(buffer.sequence);
    if (last_sequence_ >= 0 && sequence > last_sequence_ + 1) {
      MutexLock lock(mutex_);
      stats_.sequence_drops += sequence - last_sequence_ - 1;
    }
    if (last_sequence_ >= 0 && sequence <= last_sequence_) seq_base_ = last_seq_out_ + 1;
    last_sequence_ = sequence;

    Expected<cv::Mat> image = Error{"flagged as erroneous by the driver"};
    if ((buffer.flags & V4L2_BUF_FLAG_ERROR) == 0 && buffer.index < stream_->buffers.size()) {
      const auto& [start, length] = stream_->buffers[buffer.index];
      const size_t used =
          buffer.bytesused > 0 ? std::min<size_t>(buffer.bytesused, length) : length;
      image = ConvertToGrey(negotiated_.layout, static_cast<const uint8_t*>(start), used);
    }
    BufferStamp stamp;
    stamp.tv_sec = buffer.timestamp.tv_sec;
    stamp.tv_usec = buffer.timestamp.tv_usec;
    stamp.flags = buffer.flags;
    const auto readout_ns = static_cast<int64_t>(std::llround(options_.readout_us * 1e3));
    const CaptureTime time = BufferCaptureTime(stamp, dequeue_ns, exposure_ns_, readout_ns);
    if (time.from_dequeue && !warned_clock_) {
      warned_clock_ = true;
      ModuleLogger("capture")->warn(
          "camera {}: {} does not stamp buffers with CLOCK_MONOTONIC; using the dequeue time",
          name_, negotiated_.node);
    }
    if (v4l2::Ioctl(stream_->fd, VIDIOC_QBUF, &buffer) != 0) {
      const std::string why = V4l2Errno("VIDIOC_QBUF");
      if (Status s = Lost(why); !s.ok()) return Error{s.message()};
    }
    if (!image) {
      MutexLock lock(mutex_);
      ++stats_.error_buffers;
      ModuleLogger("capture")->warn("camera {}: buffer {} dropped: {}", name_, sequence,
                                    image.error());
      continue;
    }
    Frame frame;
    frame.camera = camera_index_;
    frame.t_ns = time.t_ns;
    frame.seq = std::max(seq_base_ + sequence, last_seq_out_ + 1);
    frame.image = std::move(*image);
    last_seq_out_ = frame.seq;
    {
      MutexLock lock(mutex_);
      ++stats_.frames;
    }
    return std::optional<Frame>(std::move(frame));
  }
  return std::optional<Frame>();
}

}  // namespace rigcal::capture
