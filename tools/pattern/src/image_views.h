// SPDX-License-Identifier: Apache-2.0
#pragma once
// The image half of the target readers (target_views.cc): every image of a source through one
// detector, with the checks every image target shares (readable, one size, some target).
#include <functional>
#include <optional>
#include <string>

#include "opencv.h"
#include "rigcal/pattern/target_views.h"

namespace rigcal::pattern::internal {

// The views `detect` finds in the images at `source` (a folder or folder/pattern, see
// target_views.h), or in `images` when given (`source` then names them in messages); `detect`
// fills pixels and target_points (file and t_ns are set here) or returns nullopt (the image is
// listed in `none`). Errors name the path: no images, an unreadable image, mixed resolutions,
// or no `target_name` in any image (followed by `hint`); a stream's own error.
Expected<CameraViews> DetectImageViews(
    const std::string& camera, const std::string& source,
    const std::function<std::optional<TargetView>(const cv::Mat& grey)>& detect,
    const std::string& target_name, const std::string& hint, const ImageStream& images);

}  // namespace rigcal::pattern::internal
