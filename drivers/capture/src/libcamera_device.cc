// SPDX-License-Identifier: Apache-2.0
#include "rigcal/capture/libcamera_device.h"

#include <libcamera/libcamera.h>
#include <sys/mman.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <map>
#include <sstream>
#include <thread>

#include "libcamera_manager.h"
#include "rigcal/base/logging.h"
#include "rigcal/base/thread_annotations.h"
#include "rigcal/capture/v4l2_timestamp.h"

namespace rigcal::capture {
namespace {

using libcamera::Camera;
using libcamera::CameraConfiguration;
using libcamera::FrameBuffer;
using libcamera::Request;
using libcamera::StreamRole;

constexpr auto kWaitSlice = std::chrono::milliseconds(100);

std::optional<PixelFormat> FromLibcamera(const libcamera::PixelFormat& format) {
  namespace f = libcamera::formats;
  if (format == f::R8) return PixelFormat::kGrey;
  if (format == f::YUYV) return PixelFormat::kYuyv;
  if (format == f::NV12) return PixelFormat::kNv12;
  if (format == f::RGB888) return PixelFormat::kBgr24;  // memory order B, G, R
  if (format == f::BGR888) return PixelFormat::kRgb24;  // memory order R, G, B
  if (format == f::MJPEG) return PixelFormat::kMjpeg;
  return std::nullopt;
}

std::optional<StreamRole> Role(const std::string& role) {
  if (role == "video") return StreamRole::VideoRecording;
  if (role == "viewfinder") return StreamRole::Viewfinder;
  if (role == "still") return StreamRole::StillCapture;
  if (role == "raw") return StreamRole::Raw;
  return std::nullopt;
}

std::string Model(const Camera& camera) {
  const auto model = camera.properties().get(libcamera::properties::Model);
  return model ? *model : std::string();
}

const std::vector<PixelFormat>& DefaultPreference() {
  static const std::vector<PixelFormat> preference = {PixelFormat::kGrey,  PixelFormat::kYuyv,
                                                      PixelFormat::kNv12,  PixelFormat::kBgr24,
                                                      PixelFormat::kRgb24, PixelFormat::kMjpeg};
  return preference;
}

}  // namespace

bool LibcameraBuiltIn() { return true; }

Expected<std::vector<std::string>> ListLibcameraCameras() {
  auto manager = SharedCameraManager();
  if (!manager) return Error{manager.error()};
  std::vector<std::string> list;
  for (const auto& camera : (*manager)->cameras()) {
    list.push_back(camera->id() + " (" + Model(*camera) + ")");
  }
  return list;
}

struct LibcameraDevice::Impl {
  struct Mapping {
    void* base = nullptr;
    size_t mapped = 0;
    const uint8_t* data = nullptr;  // plane 0
    size_t length = 0;
  };

  std::string name;
  int index = 0;
  LibcameraOptions options;
  std::shared_ptr<libcamera::CameraManager> manager;
  // The capture thread's (Connect / Disconnect / Grab):
  std::shared_ptr<Camera> camera;
  std::unique_ptr<CameraConfiguration> config;
  libcamera::Stream* stream = nullptr;
  std::unique_ptr<libcamera::FrameBufferAllocator> allocator;
  std::vector<std::unique_ptr<Request>> requests;
  std::map<const FrameBuffer*, Mapping> mappings;
  ImageLayout layout;
  std::string validation = "not configured";
  std::string configuration;
  double rate_hz = 30.0;
  int64_t last_sequence = -1;
  int64_t seq_base = 0;
  int64_t last_seq_out = -1;

  mutable Mutex mutex;
  std::condition_variable changed;
  std::deque<Request*> completed RIGCAL_GUARDED_BY(mutex);
  bool removed RIGCAL_GUARDED_BY(mutex) = false;
  bool interrupted RIGCAL_GUARDED_BY(mutex) = false;
  LibcameraStats stats RIGCAL_GUARDED_BY(mutex);

  std::shared_ptr<Camera> Find() const {
    const auto cameras = manager->cameras();
    for (const auto& c : cameras) {
      if (options.camera.empty() || c->id() == options.camera || Model(*c) == options.camera) {
        return c;
      }
    }
    return nullptr;
  }

  // Acquires the camera, configures it, maps its buffers and starts it (on failure with the
  // camera released again).
  Status Connect() {
    if (Status s = Acquire(); !s.ok()) return s;
    if (Status s = Configure(); !s.ok()) return s;
    if (Status s = CreateRequests(); !s.ok()) return s;
    if (Status s = Start(); !s.ok()) return s;
    last_sequence = -1;
    MutexLock lock(mutex);
    removed = false;
    stats.connected = true;
    return Status::Ok();
  }

  // Finds the camera of options.camera and acquires it.
  Status Acquire() {
    camera = Find();
    if (!camera) {
      std::string seen;
      for (const auto& c : manager->cameras()) {
        seen += (seen.empty() ? "" : ", ") + c->id() + " (" + Model(*c) + ")";
      }
      return Error{"no libcamera camera '" + options.camera +
                   "' (found: " + (seen.empty() ? "none" : seen) + ")"};
    }
    if (camera->acquire() != 0) {
      camera.reset();
      return Error{"libcamera camera '" + options.camera + "' is in use"};
    }
    return Status::Ok();
  }

  // Generates the role's configuration, sets the first preferred pixel format offered, the
  // camera model's size and the buffer count, validates it (validation) and applies it (layout,
  // stream).
  Status Configure() {
    config = camera->generateConfiguration({*Role(options.role)});
    if (!config || config->empty()) {
      Disconnect();
      return Error{"the camera has no configuration for the " + options.role + " role"};
    }
    libcamera::StreamConfiguration& cfg = config->at(0);
    const std::vector<libcamera::PixelFormat> offered = cfg.formats().pixelformats();
    std::optional<libcamera::PixelFormat> chosen;
    for (PixelFormat wanted : options.formats.empty() ? DefaultPreference() : options.formats) {
      for (const libcamera::PixelFormat& f : offered) {
        if (FromLibcamera(f) == wanted) {
          chosen = f;
          break;
        }
      }
      if (chosen) break;
    }
    if (!chosen) {
      std::string has;
      for (const auto& f : offered) has += (has.empty() ? "" : ", ") + f.toString();
      Disconnect();
      return Error{"none of the preferred pixel formats is offered (the camera has: " + has + ")"};
    }
    cfg.pixelFormat = *chosen;
    cfg.size = libcamera::Size(options.width, options.height);
    cfg.bufferCount = options.buffers;
    if (Status s = Validate(&cfg); !s.ok()) return s;
    const auto format = FromLibcamera(cfg.pixelFormat);
    if (camera->configure(config.get()) != 0) {
      Disconnect();
      return Error{"configuring " + cfg.toString() + " failed"};
    }
    layout = {*format, options.width, options.height, static_cast<int>(cfg.stride)};
    stream = cfg.stream();
    return Status::Ok();
  }

  // Validates the configuration `cfg` is part of: an error when the camera refuses it, or
  // adjusts the size or to a format rigcal does not convert.
  Status Validate(libcamera::StreamConfiguration* cfg) {
    const std::string asked = cfg->toString();
    switch (config->validate()) {
      case CameraConfiguration::Invalid:
        Disconnect();
        return Error{"the camera refuses the configuration " + asked};
      case CameraConfiguration::Adjusted:
        validation = "adjusted: " + asked + " -> " + cfg->toString() + ", " +
                     std::to_string(cfg->bufferCount) + " buffers";
        break;
      case CameraConfiguration::Valid:
        validation = "valid";
        break;
    }
    if (static_cast<int>(cfg->size.width) != options.width ||
        static_cast<int>(cfg->size.height) != options.height) {
      const std::string message = "the camera delivers " + cfg->size.toString() +
                                  " where the camera model needs " + std::to_string(options.width) +
                                  "x" + std::to_string(options.height) + " (" + validation + ")";
      Disconnect();
      return Error{message};
    }
    if (!FromLibcamera(cfg->pixelFormat)) {
      const std::string message = "the camera changed the format to " +
                                  cfg->pixelFormat.toString() + ", which rigcal does not convert";
      Disconnect();
      return Error{message};
    }
    return Status::Ok();
  }

  // Allocates the stream's buffers, maps each and makes one request per buffer.
  Status CreateRequests() {
    allocator = std::make_unique<libcamera::FrameBufferAllocator>(camera);
    if (allocator->allocate(stream) < 0) {
      Disconnect();
      return Error{"allocating the frame buffers failed"};
    }
    for (const std::unique_ptr<FrameBuffer>& buffer : allocator->buffers(stream)) {
      const FrameBuffer::Plane& plane = buffer->planes().front();
      Mapping m;
      m.mapped = plane.offset + plane.length;
      m.base = mmap(nullptr, m.mapped, PROT_READ, MAP_SHARED, plane.fd.get(), 0);
      if (m.base == MAP_FAILED) {
        Disconnect();
        return Error{std::string("mmap of a frame buffer: ") + std::strerror(errno)};
      }
      m.data = static_cast<const uint8_t*>(m.base) + plane.offset;
      m.length = plane.length;
      mappings[buffer.get()] = m;
      std::unique_ptr<Request> request = camera->createRequest();
      if (!request || request->addBuffer(stream, buffer.get()) != 0) {
        Disconnect();
        return Error{"creating a capture request failed"};
      }
      requests.push_back(std::move(request));
    }
    const libcamera::StreamConfiguration& cfg = config->at(0);
    configuration = cfg.toString() + " stride " + std::to_string(cfg.stride) + ", " +
                    std::to_string(requests.size()) + " buffers";
    return Status::Ok();
  }

  // Connects the completion signal, starts the camera and queues every request.
  Status Start() {
    camera->requestCompleted.connect(this, &Impl::OnRequestCompleted);
    if (camera->start() != 0) {
      Disconnect();
      return Error{"starting the camera failed"};
    }
    for (const auto& request : requests) {
      if (camera->queueRequest(request.get()) != 0) {
        Disconnect();
        return Error{"queueing a capture request failed"};
      }
    }
    return Status::Ok();
  }

  void Disconnect() {
    if (camera) {
      camera->stop();  // completes every queued request as cancelled
      camera->requestCompleted.disconnect(this);
    }
    {
      MutexLock lock(mutex);
      completed.clear();
      stats.connected = false;
    }
    requests.clear();
    for (auto& [buffer, m] : mappings) munmap(m.base, m.mapped);
    mappings.clear();
    allocator.reset();
    config.reset();
    stream = nullptr;
    if (camera) {
      camera->release();
      camera.reset();
    }
  }

  // libcamera's thread.
  void OnRequestCompleted(Request* request) {
    MutexLock lock(mutex);
    if (request->status() == Request::RequestCancelled) return;
    completed.push_back(request);
    changed.notify_all();
  }

  // libcamera's thread.
  void OnCameraRemoved(std::shared_ptr<Camera> gone) {
    MutexLock lock(mutex);
    if (camera && gone.get() == camera.get()) {  // camera is only reset by this device's thread
      removed = true;
      changed.notify_all();
    }
  }

  // Waits with backoff until the camera is back (true) or Interrupt (false).
  bool Reconnect() {
    auto backoff = std::chrono::milliseconds(100);
    const auto max =
        std::chrono::milliseconds(static_cast<int64_t>(options.reconnect_max_backoff_s * 1000.0));
    for (;;) {
      {
        MutexLock lock(mutex);
        const auto until = std::chrono::steady_clock::now() + backoff;
        while (!interrupted && lock.WaitUntil(changed, until) != std::cv_status::timeout) {
        }
        if (interrupted) return false;
      }
      if (Connect().ok()) {
        seq_base = last_seq_out + 1;
        MutexLock lock(mutex);
        ++stats.reconnections;
        ModuleLogger("capture")->info("camera {}: libcamera camera {} is back", name,
                                      options.camera);
        return true;
      }
      backoff = std::min(max, backoff * 2);
    }
  }
};

LibcameraDevice::LibcameraDevice(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}

Expected<std::unique_ptr<LibcameraDevice>> LibcameraDevice::Open(std::string name, int camera_index,
                                                                 LibcameraOptions options) {
  if (Status s = options.Check(); !s.ok()) return Error{"camera " + name + ": " + s.message()};
  auto manager = SharedCameraManager();
  if (!manager) return Error{"camera " + name + ": " + manager.error()};
  auto impl = std::make_unique<Impl>();
  impl->name = std::move(name);
  impl->index = camera_index;
  impl->options = std::move(options);
  impl->manager = *manager;
  if (Status s = impl->Connect(); !s.ok()) {
    return Error{"camera " + impl->name + ": libcamera: " + s.message()};
  }
  impl->manager->cameraRemoved.connect(impl.get(), &Impl::OnCameraRemoved);
  ModuleLogger("capture")->info("camera {}: libcamera {} ({}), {}, {}", impl->name,
                                impl->camera->id(), Model(*impl->camera), impl->configuration,
                                impl->validation);
  return std::unique_ptr<LibcameraDevice>(new LibcameraDevice(std::move(impl)));
}

LibcameraDevice::~LibcameraDevice() {
  impl_->manager->cameraRemoved.disconnect(impl_.get());
  impl_->Disconnect();
}

const std::string& LibcameraDevice::name() const { return impl_->name; }
double LibcameraDevice::frame_rate_hz() const { return impl_->rate_hz; }

void LibcameraDevice::Interrupt() {
  MutexLock lock(impl_->mutex);
  impl_->interrupted = true;
  impl_->changed.notify_all();
}

std::string LibcameraDevice::validation() const { return impl_->validation; }
std::string LibcameraDevice::configuration() const { return impl_->configuration; }
std::string LibcameraDevice::camera_id() const { return impl_->camera ? impl_->camera->id() : ""; }

LibcameraStats LibcameraDevice::stats() const {
  MutexLock lock(impl_->mutex);
  return impl_->stats;
}

Expected<std::optional<Frame>> LibcameraDevice::Grab() {
  Impl& d = *impl_;
  for (;;) {
    Request* request = nullptr;
    bool lost = false;
    {
      MutexLock lock(d.mutex);
      while (!d.interrupted && !d.removed && d.completed.empty() && d.camera) {
        lock.WaitUntil(d.changed, std::chrono::steady_clock::now() + kWaitSlice);
      }
      if (d.interrupted) return std::optional<Frame>();
      if (d.removed || !d.camera) {
        lost = true;
      } else {
        request = d.completed.front();
        d.completed.pop_front();
      }
    }
    if (lost) {
      if (d.camera) {
        {
          MutexLock lock(d.mutex);
          ++d.stats.removals;
        }
        ModuleLogger("capture")->warn("camera {}: libcamera camera {} removed{}", d.name,
                                      d.options.camera,
                                      d.options.reconnect ? "; reconnecting" : "");
        d.Disconnect();
        if (!d.options.reconnect) {
          return Error{"camera " + d.name + ": libcamera camera " + d.options.camera + " removed"};
        }
      }
      if (!d.Reconnect()) return std::optional<Frame>();
      continue;
    }
    FrameBuffer* buffer = request->findBuffer(d.stream);
    const bool failed = request->status() != Request::RequestComplete || buffer == nullptr ||
                        buffer->metadata().status != libcamera::FrameMetadata::FrameSuccess;
    Expected<cv::Mat> image = Error{"the request failed"};
    int64_t t_ns = 0;
    int64_t sequence = -1;
    if (!failed) {
      const Impl::Mapping& m = d.mappings.at(buffer);
      const auto& planes = buffer->metadata().planes();
      const size_t used =
          planes.empty() ? m.length : std::min<size_t>(planes[0].bytesused, m.length);
      image =
          ConvertToGrey(d.layout, m.data, d.layout.format == PixelFormat::kMjpeg ? used : m.length);
      const auto sensor = request->metadata().get(libcamera::controls::SensorTimestamp);
      t_ns = sensor ? *sensor : static_cast<int64_t>(buffer->metadata().timestamp);
      sequence = buffer->metadata().sequence;
      MutexLock lock(d.mutex);
      d.stats.sensor_timestamps = sensor.has_value();
    }
    request->reuse(Request::ReuseBuffers);
    d.camera->queueRequest(request);
    if (failed || !image) {
      MutexLock lock(d.mutex);
      ++d.stats.failed_requests;
      continue;
    }
    if (d.last_sequence >= 0 && sequence > d.last_sequence + 1) {
      MutexLock lock(d.mutex);
      d.stats.sequence_drops += sequence - d.last_sequence - 1;
    }
    if (d.last_sequence >= 0 && sequence <= d.last_sequence) d.seq_base = d.last_seq_out + 1;
    d.last_sequence = sequence;
    Frame frame;
    frame.camera = d.index;
    frame.t_ns = t_ns;
    frame.seq = std::max(d.seq_base + sequence, d.last_seq_out + 1);
    frame.image = std::move(*image);
    d.last_seq_out = frame.seq;
    MutexLock lock(d.mutex);
    ++d.stats.frames;
    return std::optional<Frame>(std::move(frame));
  }
}

}  // namespace rigcal::capture
