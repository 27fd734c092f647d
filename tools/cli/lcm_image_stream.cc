// SPDX-License-Identifier: Apache-2.0
// `rigcal intrinsics` from an LCM image log.
#include "lcm_image_stream.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <map>
#include <memory>

#include "rigcal/lcm/channels.h"
#include "rigcal/lcm/image_message.h"
#include "rigcal/lcm/log_reader.h"
#include "rigcal/pipeline/image_codec.h"

namespace rigcal::cli {

bool IsLcmImageLog(const std::string& source) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path path(source);
  if (!fs::is_regular_file(path, ec) && !fs::is_regular_file(source + ".00", ec)) return false;
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  for (const char* e : {".png", ".jpg", ".jpeg", ".bmp", ".pgm", ".ppm", ".tif", ".tiff", ".csv"}) {
    if (ext == e) return false;
  }
  return true;
}

pattern::ImageStream LcmImageStream(const std::string& path, const std::string& camera) {
  struct State {
    std::unique_ptr<lcm::LogReader> reader;
    lcm::MessageValidator validator;
    lcm::LogEvent event;
    std::map<std::string, int> channels;  // seen, for the message when the camera has none
    int images = 0;
  };
  auto state = std::make_shared<State>();
  const std::string channel = lcm::ImageChannel(camera);
  return [state, path, camera, channel](pattern::GreyImage* out) -> Expected<bool> {
    if (!state->reader) {
      auto reader = lcm::LogReader::Open(path);
      if (!reader) return Error{reader.error()};
      state->reader = std::move(*reader);
    }
    while (true) {
      const auto outcome = state->reader->Next(&state->event);
      if (outcome == lcm::LogReader::Outcome::kDamaged) {
        return Error{state->reader->problem()};
      }
      if (outcome == lcm::LogReader::Outcome::kEnd) {
        if (state->images > 0) return false;
        std::string seen;
        for (const auto& [name, count] : state->channels) {
          seen += (seen.empty() ? "" : ", ") + name + " (" + std::to_string(count) + ")";
        }
        return Error{path + ": no " + channel + " events (camera '" + camera + "'); the log has " +
                     (seen.empty() ? std::string("no events") : seen)};
      }
      ++state->channels[state->event.channel];
      if (state->event.channel != channel) continue;
      auto image = state->validator.Decode<image_t>(state->event.channel, state->event.data.data(),
                                                    static_cast<int64_t>(state->event.data.size()));
      if (!image) {
        return Error{path + ": event " + std::to_string(state->event.event_number) + " on " +
                     channel + ": " + image.error()};
      }
      auto frame = pipeline::FrameFromImage(*image, 0);
      if (!frame) {
        return Error{path + ": event " + std::to_string(state->event.event_number) + " on " +
                     channel + ": " + frame.error()};
      }
      const cv::Mat& grey = frame->image;
      out->name = std::to_string(frame->t_ns);
      out->t_ns = frame->t_ns;
      out->width = grey.cols;
      out->height = grey.rows;
      out->pixels.resize(static_cast<size_t>(grey.cols) * static_cast<size_t>(grey.rows));
      for (int r = 0; r < grey.rows; ++r) {
        std::copy(grey.ptr<uint8_t>(r), grey.ptr<uint8_t>(r) + grey.cols,
                  out->pixels.begin() + static_cast<long>(r) * grey.cols);
      }
      ++state->images;
      return true;
    }
  };
}

}  // namespace rigcal::cli
