#pragma once
// image_t (RIGCAL_IMAGE_<camera>, tools/lcm image_message.h) <-> drivers::Frame, the grey image
// the VO takes: the decoding of a recorded image for replay, and the raw GREY encoding of a
// frame.

#include <string>

#include "rigcal/calib/status.h"
#include "rigcal/drivers/frame.h"
#include "rigcal/image_t.hpp"

namespace rigcal::tools {

// The grey 8-bit frame of a checked image_t (MessageValidator::Decode): raw GREY, Y16 (>> 8),
// YUYV (its Y), RGB3 and BGR3 (converted to grey), or JPEG / PNG data (decoded as grey).
// `camera` is the rig index the frame gets; t_ns and seq come from the message. The error names
// the camera and what could not be decoded.
Expected<drivers::Frame> FrameFromImage(const image_t& image, int camera);

// A raw GREY image_t of `frame` (CV_8UC1) for camera `name`, utime = t_ns / 1000.
image_t ImageOfFrame(const drivers::Frame& frame, const std::string& name);

}  // namespace rigcal::tools
