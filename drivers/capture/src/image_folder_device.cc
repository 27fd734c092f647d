// SPDX-License-Identifier: Apache-2.0
#include "rigcal/capture/image_folder_device.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "image_folder_listing.h"
#include "rigcal/base/logging.h"
#include "rigcal/base/robust_statistics.h"

namespace rigcal::capture {

Expected<std::unique_ptr<ImageFolderDevice>> ImageFolderDevice::Open(const std::string& folder,
                                                                     std::string name,
                                                                     int camera_index,
                                                                     double frame_rate_hz) {
  ImageFolderOptions options;
  options.rate_hz = frame_rate_hz;
  return Open(folder, std::move(name), camera_index, options);
}

Expected<std::unique_ptr<ImageFolderDevice>> ImageFolderDevice::Open(
    const std::string& folder, std::string name, int camera_index,
    const ImageFolderOptions& options) {
  auto log = ModuleLogger("capture");
  std::error_code ec;
  const bool asl = std::filesystem::exists(std::filesystem::path(folder) / "data.csv", ec) ||
                   !std::filesystem::is_directory(folder, ec);
  auto listing = asl ? internal::ListAslFolder(folder, name)
                     : internal::ListPlainFolder(folder, options.rate_hz, options.timestamps_file);
  if (!listing) {
    return asl ? Error{listing.error()} : Error{"camera " + name + ": " + listing.error()};
  }
  std::unique_ptr<ImageFolderDevice> device(new ImageFolderDevice());
  device->name_ = std::move(name);
  device->camera_index_ = camera_index;
  device->layout_ = listing->layout;
  device->csv_problems_ = std::move(listing->problems);
  for (const std::string& problem : device->csv_problems_) {
    log->warn("camera {}: skipping line: {}", device->name_, problem);
  }
  for (internal::FolderEntry& entry : listing->entries) {
    device->entries_.push_back({entry.t_ns, std::move(entry.path), entry.exists});
  }
  if (!listing->missing.empty()) {
    log->warn("camera {}: {} of {} images listed in {} are missing (first: {})", device->name_,
              listing->missing.size(), device->entries_.size(), folder, listing->missing.front());
  }
  {
    MutexLock lock(device->mutex_);
    device->skipped_ = std::move(listing->missing);
  }

  if (options.rate_hz > 0.0 && (asl || options.timestamps_file.empty())) {
    device->frame_rate_hz_ = options.rate_hz;
  } else if (device->entries_.size() >= 2) {
    std::vector<int64_t> dt;
    for (size_t i = 1; i < device->entries_.size(); ++i) {
      dt.push_back(device->entries_[i].t_ns - device->entries_[i - 1].t_ns);
    }
    device->frame_rate_hz_ = 1e9 / static_cast<double>(UpperMedian(std::move(dt)));
  }
  log->info("camera {}: {} images from {} ({}) at {:.2f} Hz", device->name_,
            device->entries_.size(), folder, device->layout_, device->frame_rate_hz_);
  return device;
}

cv::Mat ImageFolderDevice::ToGrey8(cv::Mat image) {
  if (image.empty()) return image;
  if (image.channels() == 3) {
    cv::cvtColor(image, image, cv::COLOR_BGR2GRAY);
  } else if (image.channels() == 4) {
    cv::cvtColor(image, image, cv::COLOR_BGRA2GRAY);
  }
  if (image.depth() == CV_16U) {
    if (!(sixteen_bit_scale_ > 0.0)) {
      // The bit depth the first 16-bit image uses (at least 8 bits): a 10- or 12-bit sensor's
      // values in 16-bit words keep their full contrast, and every frame gets the same scale.
      double max_value = 0.0;
      cv::minMaxLoc(image, nullptr, &max_value);
      const int bits = std::clamp(static_cast<int>(std::ceil(std::log2(max_value + 1.0))), 8, 16);
      sixteen_bit_scale_ = 255.0 / ((1 << bits) - 1);
      ModuleLogger("capture")->info("camera {}: 16-bit images use {} bits", name_, bits);
    }
    image.convertTo(image, CV_8U, sixteen_bit_scale_);
  }
  if (image.type() != CV_8UC1) return cv::Mat();
  return image;
}

Expected<std::optional<Frame>> ImageFolderDevice::Grab() {
  while (!interrupted_ && next_ < entries_.size()) {
    const size_t index = next_++;
    const Entry& entry = entries_[index];
    if (!entry.exists) continue;  // reported at Open
    cv::Mat image = ToGrey8(cv::imread(entry.path, cv::IMREAD_ANYDEPTH | cv::IMREAD_ANYCOLOR));
    if (image.empty()) {
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
