// SPDX-License-Identifier: Apache-2.0
#pragma once
// What can name a camera: a camera's name becomes part of LCM channel names
// (RIGCAL_POSE_<name>) and of file names (<dir>/<name>.txt), so it is non-empty text of valid
// UTF-8 without control characters or '/', and not "." or "..".

#include <string>

namespace rigcal::io {

// Why `name` cannot name a camera, or "" when it can.
std::string CameraNameProblem(const std::string& name);

}  // namespace rigcal::io
