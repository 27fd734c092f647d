#include "rigcal/capture/image_folder_device.h"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "rigcal/base/logging.h"
#include "rigcal/base/robust_statistics.h"

namespace rigcal::capture {
namespace {

std::string Trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  const auto last = s.find_last_not_of(" \t\r\n");
  return s.substr(first, last - first + 1);
}

}  // namespace

Expected<std::unique_ptr<ImageFolderDevice>> ImageFolderDevice::Open(const std::string& folder,
                                                                     std::string name,
                                                                     int camera_index,
                                                                     double frame_rate_hz) {
  auto log = ModuleLogger("capture");
  const std::filesystem::path dir(folder);
  const std::filesystem::path csv = dir / "data.csv";
  std::ifstream in(csv);
  if (!in) {
    return Error{"camera " + name + ": cannot open " + csv.string() + ": " + std::strerror(errno)};
  }
  std::unique_ptr<ImageFolderDevice> device(new ImageFolderDevice());
  device->name_ = std::move(name);
  device->camera_index_ = camera_index;

  std::vector<std::string> missing;  // skipped_ from the start (the device is not shared yet)
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const std::string text = Trim(line);
    if (text.empty() || text[0] == '#') continue;
    auto problem = [&](const std::string& reason) {
      const std::string message = csv.string() + ":" + std::to_string(line_number) + ": " + reason;
      log->warn("camera {}: skipping line: {}", device->name_, message);
      device->csv_problems_.push_back(message);
    };
    const auto comma = text.find(',');
    if (comma == std::string::npos) {
      problem("expected \"timestamp_ns,filename\"");
      continue;
    }
    const std::string stamp = Trim(text.substr(0, comma));
    const std::string file = Trim(text.substr(comma + 1));
    int64_t t_ns = 0;
    const auto [end, ec] = std::from_chars(stamp.data(), stamp.data() + stamp.size(), t_ns);
    if (ec != std::errc() || end != stamp.data() + stamp.size() || t_ns < 0) {
      problem("bad timestamp \"" + stamp + "\"");
      continue;
    }
    if (file.empty() || file.find(',') != std::string::npos) {
      problem("bad file name \"" + file + "\"");
      continue;
    }
    if (!device->entries_.empty() && t_ns <= device->entries_.back().t_ns) {
      problem("timestamp " + stamp + " not after the previous one");
      continue;
    }
    Entry entry;
    entry.t_ns = t_ns;
    entry.path = (dir / "data" / file).string();
    std::error_code exists_error;
    entry.exists = std::filesystem::is_regular_file(entry.path, exists_error);
    if (!entry.exists) missing.push_back(entry.path);
    device->entries_.push_back(std::move(entry));
  }
  if (device->entries_.empty()) {
    return Error{"camera " + device->name_ + ": " + csv.string() + " lists no valid image"};
  }
  if (!missing.empty()) {
    log->warn("camera {}: {} of {} images listed in {} are missing (first: {})", device->name_,
              missing.size(), device->entries_.size(), csv.string(), missing.front());
  }
  {
    MutexLock lock(device->mutex_);
    device->skipped_ = std::move(missing);
  }

  if (frame_rate_hz > 0.0) {
    device->frame_rate_hz_ = frame_rate_hz;
  } else if (device->entries_.size() >= 2) {
    std::vector<int64_t> dt;
    for (size_t i = 1; i < device->entries_.size(); ++i) {
      dt.push_back(device->entries_[i].t_ns - device->entries_[i - 1].t_ns);
    }
    device->frame_rate_hz_ = 1e9 / static_cast<double>(UpperMedian(std::move(dt)));
  }
  log->info("camera {}: {} images from {} at {:.2f} Hz", device->name_, device->entries_.size(),
            folder, device->frame_rate_hz_);
  return device;
}

Expected<std::optional<Frame>> ImageFolderDevice::Grab() {
  while (!interrupted_ && next_ < entries_.size()) {
    const size_t index = next_++;
    const Entry& entry = entries_[index];
    if (!entry.exists) continue;  // reported at Open
    cv::Mat image = cv::imread(entry.path, cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR);
    if (!image.empty() && image.channels() == 3) {
      cv::cvtColor(image, image, cv::COLOR_BGR2GRAY);
    } else if (!image.empty() && image.channels() == 4) {
      cv::cvtColor(image, image, cv::COLOR_BGRA2GRAY);
    }
    if (!image.empty() && image.depth() == CV_16U) image.convertTo(image, CV_8U, 1.0 / 257.0);
    if (image.empty() || image.type() != CV_8UC1) {
      ModuleLogger("capture")->warn("camera {}: cannot read image {}; skipped", name_, entry.path);
      MutexLock lock(mutex_);
      skipped_.push_back(entry.path);
      continue;
    }
    Frame frame;
    frame.camera = camera_index_;
    frame.t_ns = entry.t_ns;
    frame.seq = static_cast<int64_t>(index);
    frame.image = std::move(image);
    return std::optional<Frame>(std::move(frame));
  }
  return std::optional<Frame>();
}

std::vector<std::string> ImageFolderDevice::skipped_files() const {
  MutexLock lock(mutex_);
  return skipped_;
}

size_t ImageFolderDevice::skipped_count() const {
  MutexLock lock(mutex_);
  return skipped_.size();
}

}  // namespace rigcal::capture
