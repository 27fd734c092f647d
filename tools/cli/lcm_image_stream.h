// SPDX-License-Identifier: Apache-2.0
#pragma once
// The images of one camera in an LCM log (RIGCAL_IMAGE_<camera>, image_t: raw, PNG or JPEG, as
// `rigcal record` and `rigcal import euroc` write them) as a target ImageStream for
// `rigcal intrinsics --camera NAME=LOG`.

#include <string>

#include "rigcal/pattern/target_views.h"

namespace rigcal::cli {

// True when `source` is an existing regular file that is not an image (an LCM log; a split
// log's first part `LOG.00` counts through LOG).
bool IsLcmImageLog(const std::string& source);

// Reads the log at `path` on the first call. Each image_t on RIGCAL_IMAGE_<camera> becomes a
// GreyImage named "<t_ns>" with t_ns its capture stamp (so several cameras of one log pair by
// their stamps). Errors: the log cannot be opened, is damaged (the byte offset), an image does
// not decode (the event's channel and reason), or no image of the camera is in the log (the
// channels it has are listed).
pattern::ImageStream LcmImageStream(const std::string& path, const std::string& camera);

}  // namespace rigcal::cli
