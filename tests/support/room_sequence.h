// SPDX-License-Identifier: Apache-2.0
#pragma once
// One camera moving through the textured room of drivers' simulated rig: the rendered image
// sequences with exact ground truth of the VO tests and the VO benchmark. The images come from
// SimulatedRig (its room scene, renderer and image noise) through a real camera model of
// rigcal_camera (support/ideal_cameras.h); nothing here renders.
//
// World frame: the simulated rig's (z up, floor at z = 0). The room is a closed box of 10 m
// (x) by 8 m (y), 6 m high, centred on the z axis, without furniture (no boxes), its six faces
// textured. Motions are written relative to RoomCentre(): a level camera in the middle of the
// room looking along +x (camera frame x right, y down, z forward).

#include <memory>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/camera/camera_model.h"
#include "rigcal/sim/simulated_rig.h"

namespace rigcal::support {

inline constexpr double kRoomFrameRateHz = 20.0;

// world_from_camera of the level camera at the centre of the room (3 m above the floor) that
// looks along +x.
Pose RoomCentre();

// world_from_camera of frame k (20 Hz) of a smooth general motion around the room's centre:
// RoomCentre() * [yaw 0.35 sin(0.4 t) about y, pitch 0.15 sin(0.6 t + 0.5) about x, roll
// 0.1 sin(0.5 t + 1.3) about z | C = (1.2 sin(0.5 t), 0.4 sin(0.7 t + 0.3),
// 0.9 sin(0.33 t + 1) - 0.5)], t = k / 20 s: a few cm and about half a degree per frame.
Pose RoomPose(int k);

// A simulated rig of one camera "cam0" (model `camera`) whose frame k (20 Hz, stamps k * 50 ms)
// is taken at world_from_camera[k] (at least 2 poses; poses between frames are interpolated),
// with Gaussian image noise of `noise_sigma` grey levels. Frame k: rig.RenderFrame(0, k); its
// truth: rig.WorldFromCameraAt(0, rig.FrameStreamTime(k)). Error when the spec is rejected (a pose
// outside the room's free space, fewer than 2 poses).
Expected<sim::SimulatedRig> MakeRoomSequence(std::shared_ptr<const camera::CameraModel> camera,
                                             const std::vector<Pose>& world_from_camera,
                                             double noise_sigma = 1.0);

}  // namespace rigcal::support
