// SPDX-License-Identifier: Apache-2.0
#pragma once
// Private to drivers/capture: the frame lists of ImageFolderDevice's two layouts. An ASL (EuRoC)
// camera folder lists its frames in data.csv; a plain folder is its image files in name order,
// stamped by a rate or a timestamps file.

#include <cstdint>
#include <string>
#include <vector>

#include "rigcal/base/status.h"

namespace rigcal::capture::internal {

struct FolderEntry {
  int64_t t_ns = 0;
  std::string path;
  bool exists = true;
};

struct FolderListing {
  std::vector<FolderEntry> entries;
  std::vector<std::string> problems;  // "file:line: reason" of every skipped index line
  std::vector<std::string> missing;   // listed images that do not exist
  std::string layout;                 // "ASL data.csv", "plain folder at 30 Hz", ...
};

// data.csv of an ASL camera folder ("timestamp_ns,filename" lines, images in data/); malformed
// and out-of-order lines are skipped and listed. Error when data.csv cannot be read.
Expected<FolderListing> ListAslFolder(const std::string& folder, const std::string& camera);

// The image files of `folder` (png, jpg, jpeg, pgm, ppm, pnm, bmp, tif, tiff; any case) in
// natural name order (digit runs compare by value: img2 before img10). Stamped from
// `timestamps_file` when not empty (ReadStampsFile), else frame i at i / rate_hz seconds.
// Errors: no image, neither a rate nor a file, a stamps file that does not fit the images.
Expected<FolderListing> ListPlainFolder(const std::string& folder, double rate_hz,
                                        const std::string& timestamps_file);

// One stamp per non-blank, non-'#' line, in nanoseconds: an integer is nanoseconds, a number
// with a decimal point is seconds (converted exactly: "1403636579.763555584"). The first field
// (up to a blank or a comma) is the stamp; a second field, when present, is returned in *names
// (empty string otherwise). Stamps must increase. Errors name the file and line.
Expected<std::vector<int64_t>> ReadStampsFile(const std::string& path,
                                              std::vector<std::string>* names);

// Natural order of file names: digit runs compare by value, the rest byte-wise.
bool NaturalLess(const std::string& a, const std::string& b);

}  // namespace rigcal::capture::internal
