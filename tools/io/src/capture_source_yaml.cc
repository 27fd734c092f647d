// SPDX-License-Identifier: Apache-2.0
#include "capture_source_yaml.h"

#include <algorithm>
#include <filesystem>
#include <initializer_list>
#include <set>
#include <vector>

namespace rigcal::io {
namespace {

const std::set<std::string> kV4l2Keys = {
    "pixel_formats", "frame_rate_hz",           "buffers",        "exposure_us",
    "gain",          "external_trigger",        "readout_us",     "controls",
    "reconnect",     "reconnect_max_backoff_s", "frame_timeout_s"};

// The optional field `key` of `node` (named `prefix` + key in errors) into *out; unchanged
// when absent.
std::optional<Error> OptionalBool(const FieldReader& r, const YAML::Node& node,
                                  const std::string& prefix, const char* key, bool* out) {
  const YAML::Node n = node[key];
  if (!n) return std::nullopt;
  auto v = r.Bool(n, prefix + key);
  if (!v) return Error{v.error()};
  *out = *v;
  return std::nullopt;
}

std::optional<Error> OptionalBuffers(const FieldReader& r, const YAML::Node& node,
                                     const std::string& prefix, int lowest, int* out) {
  const YAML::Node n = node["buffers"];
  if (!n) return std::nullopt;
  auto v = r.Integer(n, prefix + "buffers");
  if (!v) return Error{v.error()};
  if (*v < lowest || *v > 32) {
    return r.Fail(n, prefix + "buffers", "must be in [" + std::to_string(lowest) + ", 32]");
  }
  *out = *v;
  return std::nullopt;
}

// The optional list `pixel_formats` of `node` into *out (replaced when present); formats in
// `unsupported` are refused, naming the `supported` ones.
std::optional<Error> OptionalPixelFormats(const FieldReader& r, const YAML::Node& node,
                                          const std::string& prefix,
                                          std::initializer_list<capture::PixelFormat> unsupported,
                                          const std::string& supported,
                                          std::vector<capture::PixelFormat>* out) {
  const YAML::Node n = node["pixel_formats"];
  if (!n) return std::nullopt;
  if (!n.IsSequence() || n.size() == 0) {
    return r.Fail(n, prefix + "pixel_formats", "expected a list such as [GREY, YUYV]");
  }
  out->clear();
  for (size_t i = 0; i < n.size(); ++i) {
    const std::string item = prefix + "pixel_formats[" + std::to_string(i) + "]";
    auto name = r.String(n[i], item);
    if (!name) return Error{name.error()};
    const auto format = capture::ParsePixelFormat(*name);
    if (!format ||
        std::find(unsupported.begin(), unsupported.end(), *format) != unsupported.end()) {
      return r.Fail(n[i], item, "'" + *name + "' is not one of " + supported);
    }
    out->push_back(*format);
  }
  return std::nullopt;
}

}  // namespace

std::optional<Error> ParseV4l2Keys(const FieldReader& r, const YAML::Node& node,
                                   const std::string& field, bool is_source,
                                   capture::V4l2Options* options) {
  if (!node.IsMap()) return r.Fail(node, field, "expected a map");
  std::set<std::string> known = kV4l2Keys;
  if (is_source) known.insert("type");
  if (auto e = r.CheckKeys(node, field + ".", known)) return e;
  const std::string p = field + ".";
  if (auto e = OptionalPixelFormats(r, node, p,
                                    {capture::PixelFormat::kBgr24, capture::PixelFormat::kRgb24},
                                    "GREY, Y10, Y16, YUYV, NV12, MJPEG", &options->formats))
    return e;
  auto number = [&](const char* key, double low, double high, bool open_low,
                    double* out) -> std::optional<Error> {
    const YAML::Node n = node[key];
    if (!n) return std::nullopt;
    auto v = r.Number(n, p + key);
    if (!v) return Error{v.error()};
    if (!((open_low ? *v > low : *v >= low) && *v <= high)) {
      return r.Fail(n, p + key,
                    "must be in " + std::string(open_low ? "(" : "[") + std::to_string(low) + ", " +
                        std::to_string(high) + "]");
    }
    *out = *v;
    return std::nullopt;
  };
  if (auto e = number("frame_rate_hz", 0, 10000, true, &options->frame_rate_hz)) return e;
  if (auto e = number("readout_us", 0, 1e6, false, &options->readout_us)) return e;
  if (auto e =
          number("reconnect_max_backoff_s", 0, 3600, true, &options->reconnect_max_backoff_s)) {
    return e;
  }
  if (auto e = number("frame_timeout_s", 0, 3600, false, &options->frame_timeout_s)) return e;
  if (node["exposure_us"]) {
    double exposure = 0;
    if (auto e = number("exposure_us", 0, 1e7, true, &exposure)) return e;
    options->exposure_us = exposure;
  }
  if (auto e = OptionalBuffers(r, node, p, 2, &options->buffers)) return e;
  if (const YAML::Node n = node["gain"]) {
    auto v = r.Integer64(n, p + "gain");
    if (!v) return Error{v.error()};
    options->gain = *v;
  }
  if (auto e = OptionalBool(r, node, p, "external_trigger", &options->external_trigger)) return e;
  if (auto e = OptionalBool(r, node, p, "reconnect", &options->reconnect)) return e;
  if (const YAML::Node n = node["controls"]) {
    if (!n.IsMap()) return r.Fail(n, p + "controls", "expected a map of control name: value");
    for (auto it = n.begin(); it != n.end(); ++it) {
      const std::string key = it->first.Scalar();
      auto v = r.Integer64(it->second, p + "controls." + key);
      if (!v) return Error{v.error()};
      options->controls[key] = *v;
    }
  }
  return std::nullopt;
}

std::optional<Error> ParseLibcameraKeys(const FieldReader& r, const YAML::Node& node,
                                        const std::string& field, bool is_source,
                                        capture::LibcameraOptions* options) {
  if (!node.IsMap()) return r.Fail(node, field, "expected a map");
  std::set<std::string> known = {"role", "pixel_formats", "buffers", "reconnect",
                                 "reconnect_max_backoff_s"};
  if (is_source) known.insert("type");
  if (auto e = r.CheckKeys(node, field + ".", known)) return e;
  const std::string p = field + ".";
  if (const YAML::Node n = node["role"]) {
    auto v = r.String(n, p + "role");
    if (!v) return Error{v.error()};
    if (*v != "video" && *v != "viewfinder" && *v != "still" && *v != "raw") {
      return r.Fail(n, p + "role", "'" + *v + "' is not one of video, viewfinder, still, raw");
    }
    options->role = *v;
  }
  if (auto e =
          OptionalPixelFormats(r, node, p, {capture::PixelFormat::kY10, capture::PixelFormat::kY16},
                               "GREY, YUYV, NV12, BGR24, RGB24, MJPEG", &options->formats))
    return e;
  if (auto e = OptionalBuffers(r, node, p, 1, &options->buffers)) return e;
  if (auto e = OptionalBool(r, node, p, "reconnect", &options->reconnect)) return e;
  if (const YAML::Node n = node["reconnect_max_backoff_s"]) {
    auto v = r.Number(n, p + "reconnect_max_backoff_s");
    if (!v) return Error{v.error()};
    if (!(*v > 0.0 && *v <= 3600.0)) {
      return r.Fail(n, p + "reconnect_max_backoff_s", "must be in (0, 3600]");
    }
    options->reconnect_max_backoff_s = *v;
  }
  return std::nullopt;
}

std::optional<Error> ParseImageFolderKeys(const FieldReader& r, const YAML::Node& node,
                                          const std::string& field, bool is_source,
                                          const std::string& base_dir,
                                          capture::ImageFolderOptions* options) {
  if (!node.IsMap()) return r.Fail(node, field, "expected a map");
  std::set<std::string> known = {"rate_hz", "timestamps"};
  if (is_source) known.insert("type");
  if (auto e = r.CheckKeys(node, field + ".", known)) return e;
  const std::string p = field + ".";
  if (const YAML::Node n = node["rate_hz"]) {
    auto v = r.Number(n, p + "rate_hz");
    if (!v) return Error{v.error()};
    if (!(*v > 0.0 && *v <= 10000.0)) return r.Fail(n, p + "rate_hz", "must be in (0, 10000]");
    options->rate_hz = *v;
  }
  if (const YAML::Node n = node["timestamps"]) {
    auto v = r.String(n, p + "timestamps");
    if (!v) return Error{v.error()};
    if (v->empty()) return r.Fail(n, p + "timestamps", "must name a file");
    const std::filesystem::path file(*v);
    options->timestamps_file =
        file.is_absolute() ? file.string() : (std::filesystem::path(base_dir) / file).string();
  }
  return std::nullopt;
}

}  // namespace rigcal::io
