// SPDX-License-Identifier: Apache-2.0
#include "image_folder_listing.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <set>

namespace rigcal::capture::internal {
namespace {

namespace fs = std::filesystem;

std::string Trim(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  const auto last = s.find_last_not_of(" \t\r\n");
  return s.substr(first, last - first + 1);
}

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

bool IsImageFile(const fs::path& path) {
  static const std::set<std::string> kExtensions = {".png", ".jpg", ".jpeg", ".pgm", ".ppm",
                                                    ".pnm", ".bmp", ".tif",  ".tiff"};
  return kExtensions.count(Lower(path.extension().string())) > 0;
}

// A stamp: integer nanoseconds, or seconds with a decimal point (exact, no floating point).
std::optional<int64_t> ParseStampNs(const std::string& text) {
  const auto dot = text.find('.');
  const std::string whole = dot == std::string::npos ? text : text.substr(0, dot);
  const std::string fraction = dot == std::string::npos ? "" : text.substr(dot + 1);
  if (whole.empty() || fraction.size() > 9 ||
      !std::all_of(fraction.begin(), fraction.end(), [](char c) { return std::isdigit(c); })) {
    return std::nullopt;
  }
  int64_t value = 0;
  const auto [end, ec] = std::from_chars(whole.data(), whole.data() + whole.size(), value);
  if (ec != std::errc() || end != whole.data() + whole.size() || value < 0) return std::nullopt;
  if (dot == std::string::npos) return value;
  constexpr int64_t kMaxSeconds = std::numeric_limits<int64_t>::max() / 1'000'000'000 - 1;
  if (value > kMaxSeconds) return std::nullopt;
  int64_t ns = 0;
  for (size_t i = 0; i < 9; ++i) ns = 10 * ns + (i < fraction.size() ? fraction[i] - '0' : 0);
  return value * 1'000'000'000 + ns;
}

}  // namespace

bool NaturalLess(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const bool da = std::isdigit(static_cast<unsigned char>(a[i])) != 0;
    const bool db = std::isdigit(static_cast<unsigned char>(b[j])) != 0;
    if (da && db) {
      size_t ei = i, ej = j;
      while (ei < a.size() && std::isdigit(static_cast<unsigned char>(a[ei]))) ++ei;
      while (ej < b.size() && std::isdigit(static_cast<unsigned char>(b[ej]))) ++ej;
      // Compare the runs by value: without leading zeros, the longer is larger.
      size_t si = i, sj = j;
      while (si + 1 < ei && a[si] == '0') ++si;
      while (sj + 1 < ej && b[sj] == '0') ++sj;
      if (ei - si != ej - sj) return ei - si < ej - sj;
      const int order = a.compare(si, ei - si, b, sj, ej - sj);
      if (order != 0) return order < 0;
      if (ei - i != ej - j) return ei - i < ej - j;  // "01" after "1": fewer zeros first
      i = ei;
      j = ej;
      continue;
    }
    if (a[i] != b[j]) return static_cast<unsigned char>(a[i]) < static_cast<unsigned char>(b[j]);
    ++i;
    ++j;
  }
  return a.size() - i < b.size() - j;
}

Expected<FolderListing> ListAslFolder(const std::string& folder, const std::string& camera) {
  const fs::path dir(folder);
  const fs::path csv = dir / "data.csv";
  std::ifstream in(csv);
  if (!in) {
    return Error{"camera " + camera + ": cannot open " + csv.string() + ": " +
                 std::strerror(errno)};
  }
  FolderListing listing;
  listing.layout = "ASL data.csv";
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const std::string text = Trim(line);
    if (text.empty() || text[0] == '#') continue;
    auto problem = [&](const std::string& reason) {
      listing.problems.push_back(csv.string() + ":" + std::to_string(line_number) + ": " + reason);
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
    if (!listing.entries.empty() && t_ns <= listing.entries.back().t_ns) {
      problem("timestamp " + stamp + " not after the previous one");
      continue;
    }
    FolderEntry entry;
    entry.t_ns = t_ns;
    entry.path = (dir / "data" / file).string();
    std::error_code exists_error;
    entry.exists = fs::is_regular_file(entry.path, exists_error);
    if (!entry.exists) listing.missing.push_back(entry.path);
    listing.entries.push_back(std::move(entry));
  }
  if (listing.entries.empty()) {
    return Error{"camera " + camera + ": " + csv.string() + " lists no valid image"};
  }
  return listing;
}

Expected<std::vector<int64_t>> ReadStampsFile(const std::string& path,
                                              std::vector<std::string>* names) {
  std::ifstream in(path);
  if (!in) return Error{"cannot open " + path + ": " + std::strerror(errno)};
  std::vector<int64_t> stamps;
  names->clear();
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const std::string text = Trim(line);
    if (text.empty() || text[0] == '#') continue;
    const auto split = text.find_first_of(" \t,");
    const std::string stamp = text.substr(0, split);
    const std::string rest = split == std::string::npos ? "" : Trim(text.substr(split + 1));
    const auto t_ns = ParseStampNs(stamp);
    const bool increasing = t_ns && (stamps.empty() || *t_ns > stamps.back());
    if (!increasing) {
      std::string message = path;
      message.append(":").append(std::to_string(line_number)).append(": ");
      message.append(t_ns ? "stamp " + stamp + " not after the previous one"
                          : "bad stamp \"" + stamp +
                                "\" (integer nanoseconds, or seconds with a decimal point)");
      return Error{message};
    }
    stamps.push_back(*t_ns);
    names->push_back(rest.substr(0, rest.find_first_of(" \t,")));
  }
  if (stamps.empty()) return Error{path + ": no stamp"};
  return stamps;
}

Expected<FolderListing> ListPlainFolder(const std::string& folder, double rate_hz,
                                        const std::string& timestamps_file) {
  std::error_code ec;
  std::vector<std::string> files;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder, ec)) {
    if (entry.is_regular_file(ec) && IsImageFile(entry.path())) {
      files.push_back(entry.path().filename().string());
    }
  }
  if (ec) return Error{folder + ": cannot list: " + ec.message()};
  if (files.empty()) {
    return Error{folder +
                 ": no data.csv (ASL layout) and no image files (png, jpg, pgm, ppm, bmp, tif)"};
  }
  std::sort(files.begin(), files.end(), NaturalLess);
  FolderListing listing;
  std::vector<int64_t> stamps;
  if (!timestamps_file.empty()) {
    std::vector<std::string> names;
    auto read = ReadStampsFile(timestamps_file, &names);
    if (!read) return Error{read.error()};
    stamps = std::move(*read);
    if (stamps.size() != files.size()) {
      return Error{timestamps_file + ": " + std::to_string(stamps.size()) + " stamps for " +
                   std::to_string(files.size()) + " images in " + folder};
    }
    for (size_t i = 0; i < names.size(); ++i) {
      if (!names[i].empty() && fs::path(names[i]).filename().string() != files[i]) {
        return Error{timestamps_file + ": stamp " + std::to_string(i + 1) + " names " + names[i] +
                     ", but image " + std::to_string(i + 1) + " in name order is " + files[i]};
      }
    }
    listing.layout = "plain folder stamped by " + timestamps_file;
  } else if (rate_hz > 0.0 && std::isfinite(rate_hz)) {
    for (size_t i = 0; i < files.size(); ++i) {
      stamps.push_back(static_cast<int64_t>(std::llround(static_cast<double>(i) * 1e9 / rate_hz)));
    }
    char rate[32];
    std::snprintf(rate, sizeof(rate), "%g", rate_hz);
    listing.layout = std::string("plain folder stamped at ") + rate + " Hz";
  } else {
    return Error{folder + ": a plain image folder needs rate_hz or a timestamps file"};
  }
  for (size_t i = 0; i < files.size(); ++i) {
    listing.entries.push_back({stamps[i], (fs::path(folder) / files[i]).string(), true});
  }
  return listing;
}

}  // namespace rigcal::capture::internal
