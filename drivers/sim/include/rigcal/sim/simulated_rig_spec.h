// SPDX-License-Identifier: Apache-2.0
#pragma once
// SimulatedRigSpec: what the simulated rig (simulated_rig.h) simulates: its cameras and their
// true mountings, timing, the rig's trajectory, the scene, imaging and device behaviour; and
// its check.
//
// Scenes (all textures are procedural, generated from the seed at start-up: scale-invariant
// "dead leaves" of opaque rectangles, rotated rectangles and discs of random grey, from 1.5
// texels to 1/8 of a 1024-texel tile, mip-mapped; rich in corners at every scale and distance):
//   room    closed box [-x/2, x/2] x [-y/2, y/2] x [0, z] (floor z = 0), every face textured,
//           with `boxes` textured boxes standing on the floor along the walls, in the outer 30%
//           of each horizontal half-extent: the inner 70% of the floor plan is free.
//   yard    the same without a ceiling (uniform sky above the walls): ground, facades, boxes.
//   street  a yard with a long default size (a street between two rows of facades).
//   pipe    a pipe (cylinder seen from inside) along world x through y = z = 0, from x = 0 to
//           x = length, with textured end caps.
// MakeSimulatedRig checks that every camera stays in the free space for the whole run (inside
// the room/pipe, outside every static box, at least kMinClearance from any surface); moving
// objects instead keep clear of the cameras (kMovingObjectClearance) by the choice of their lines.
//
// `source:` section of a rig config (docs/config.md) for `type: simulated`. Every key is
// optional except `trajectory`; unknown keys are errors.
//
//   source:
//     type: simulated
//     frame_rate_hz: 20           # frames per second, (0, 1000]
//     num_frames: 468             # frames per camera; or duration_s: 23.4 (not both);
//                                 # neither: the whole trajectory
//     seed: 1                     # textures, scene layout, noise, drops, jitter (integer >= 0)
//     realtime: false             # true: Grab waits for each frame's time (rigcal run); stamps
//                                 # are CLOCK_MONOTONIC from the first Grab. false: as fast as
//                                 # consumed, stamps start at 0.
//     trajectory:                 # the master camera's motion; either waypoints ...
//       waypoint_interval_s: 2    # time between waypoints, > 0
//       waypoints:                # >= 2; each: p (world position, m) and the orientation as
//         - {p: [0, 0, 3], ypr_deg: [0, 0, 0]}    # yaw about world z, pitch (+ = looking down),
//         - {p: [1, 0, 3], q_wxyz: [1, 0, 0, 0]}  # roll about the viewing direction, from a
//                                 # level camera looking along +x; or q_wxyz = world_from_master.
//                                 # The path is a C2 cumulative cubic B-spline (position and
//                                 # rotation) that starts at the first waypoint, ends at the last,
//                                 # and passes near (not exactly through) the ones in between;
//                                 # waypoint i belongs to time i * waypoint_interval_s.
//       # ... or a trajectory file:
//       file: traj.txt            # TUM or EuRoC CSV (relative to the config file); its first
//                                 # stamp is time 0; poses are interpolated (linear + slerp)
//       body_from_master: {q_wxyz: [w, x, y, z], C: [x, y, z]}  # optional: the master camera's
//                                 # pose in the file's body frame (default identity)
//     scene:
//       type: room                # room | yard | street | pipe
//       size: [20, 16, 6]         # room/yard/street: x, y extent and height, m
//                                 # (defaults: room [20, 16, 6], yard [60, 60, 8],
//                                 # street [200, 16, 10])
//       boxes: 8                  # room/yard/street: number of boxes along the walls, [0, 64]
//       diameter: 0.6             # pipe: inner diameter, m
//       length: 40                # pipe: length, m
//       texel_m: 0.01             # texture resolution (finest level), m per texel; default
//                                 # room 0.01, yard/street 0.02, pipe 0.002 (a texture tile
//                                 # is 1024 texels wide and repeats)
//       textures: [wall.png, box.jpg]  # optional: real photographs (any format OpenCV reads,
//                                 # colour or grey, 8 or 16 bit; paths relative to the config
//                                 # file) as the surfaces' textures, in turn, instead of the
//                                 # procedural ones: each is cropped to its centre square,
//                                 # scaled to half a tile and mirrored into a seamless tile
//       moving_objects:           # optional (room, yard, street): textured boxes standing on
//         count: 6                # the floor that slide back and forth at a constant speed
//         size: [0.6, 0.6, 1.8]   # along straight lines across the free floor (the inner 70%),
//         speed_mps: 1.4          # each on its own line and phase from the seed; size: x, y, z
//                                 # extent in m (axis-aligned; they do not turn). count [0, 64]
//                                 # (default 0), size each (0, 100] m, speed (0, 100] m/s.
//                                 # Rendered at each frame's (each row's, each blur sample's)
//                                 # time; the free-space check keeps every camera clear of the
//                                 # static scene, and each object's line is redrawn (up to 100
//                                 # times) until the object keeps 0.5 m clear of every camera
//     noise_sigma: 2.0            # Gaussian image noise, grey levels, [0, 100]
//     motion_blur:                # absent or `false`: off
//       exposure_ms: 8            # (0, frame period); images average `samples` renders
//       samples: 4                # spread over the exposure, [2, 32] (cost: samples x)
//     rolling_shutter_ms: 0       # row readout time of the whole frame (top row to bottom
//                                 # row), [0, frame period); 0: global shutter. Row r of an
//                                 # H-row image is exposed (r / (H - 1)) x readout after the
//                                 # frame's stamp: the stamp is the top row's exposure time (as
//                                 # a trigger pulse or a V4L2 start-of-frame stamp). Combines
//                                 # with motion_blur (each row's exposure is blurred around its
//                                 # own time). A VO compensates it with the camera's
//                                 # `rolling_shutter_ms` (docs/config.md)
//     drop_probability: 0.0       # each frame of each camera is dropped with this probability
//     timestamp_jitter_ms: 0.0    # sigma of Gaussian stamp noise (clipped at 3 sigma; 3 sigma
//                                 # must stay below half a frame period)
//     fail_after_s: {cam1: 5.0}   # the camera dies: Grab returns an error for every frame at
//                                 # or after this stream time (seconds since frame 0)
//     blackout_s: {cam0: [8, 9]}  # the camera sees nothing (lens covered): its images are black
//                                 # for stream times in [from, to) s; its VO loses tracking and
//                                 # re-initialises in a new scale segment afterwards
//     blur_burst_s: {cam0: [8, 9]}  # the camera's frames in [from, to) s are blurred by its
//                                 # motion over 90 % of the frame period (8 renders, or
//                                 # motion_blur.samples when more): a burst of poorly tracked
//                                 # frames (RigEstimator's pose quality gate)
//     vignetting: 0.3             # [0, 1): the light at the image corner falls to (1 - x) of
//                                 # the centre's, quadratically with the radius
//     exposure_steps:             # auto-exposure: every interval_s (> 0) the camera's gain
//       interval_s: 2             # jumps to a factor in [1/max_factor, max_factor] (log-
//       max_factor: 1.5           # uniform, drawn per camera and step; [1, 8]), which scales
//                                 # the image and its noise (gain noise); absent: gain 1
//     render_block: 4             # 1: ray cast every pixel (exact, ~5x slower). N > 1: cast
//                                 # every Nth pixel and interpolate texture coordinates and
//                                 # mip level inside N x N blocks whose corners see the same
//                                 # surface; other blocks are cast per pixel. With 4: mean
//                                 # difference to exact casting ~0.1 grey level, < 1% of the
//                                 # pixels off by more than 2 (grazing surfaces, depth edges)

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/camera/camera_model.h"

namespace rigcal::sim {

// The smallest texture photograph (px per side): smaller ones hold too little texture to tile.
inline constexpr int kMinTextureImagePx = 16;

struct SimulatedRigSpec {
  // --- Cameras (from `cameras:`); index 0 is the master. ---------------------------------
  std::vector<std::string> names;
  std::vector<std::shared_ptr<const camera::CameraModel>> cameras;
  // True mounting of camera i in the master frame; [0] must be the identity.
  std::vector<Pose> master_from_camera;

  // --- Timing -------------------------------------------------------------------------------
  double frame_rate_hz = 20.0;  // (0, 1000]
  int64_t num_frames = 0;       // > 0: frames per camera
  double duration_s = 0.0;      // > 0: num_frames = round(duration_s * frame_rate_hz)
                                // neither: every frame time inside the trajectory
  uint64_t seed = 1;
  bool realtime = false;      // pace Grab at the frame rate; stamps from CLOCK_MONOTONIC
  int64_t start_time_ns = 0;  // stamp of frame 0 when not realtime

  // --- Trajectory: waypoints, or poses loaded from a file (exactly one of them) ------------
  struct Waypoint {
    Eigen::Vector3d position = Eigen::Vector3d::Zero();  // world, m
    Eigen::Quaterniond world_from_master = Eigen::Quaterniond::Identity();
  };
  std::vector<Waypoint> waypoints;  // >= 2 when used
  double waypoint_interval_s = 2.0;
  // A sampled trajectory (TUM/EuRoC file, read by the config loader): world_from_body poses at
  // strictly increasing stamps; the first stamp is stream time 0.
  std::string trajectory_file;  // informational (log messages)
  std::vector<int64_t> trajectory_t_ns;
  std::vector<Pose> trajectory_world_from_body;
  Pose body_from_master;  // master camera pose in the file's body frame

  // An 8-bit grey image, row-major (a texture photograph; `name` says where it came from), at
  // least kMinTextureImagePx on each side.
  struct GreyImage {
    std::string name;
    int width = 0;
    int height = 0;
    std::vector<uint8_t> pixels;
  };

  // --- Scene --------------------------------------------------------------------------------
  enum class SceneType { kRoom, kYard, kStreet, kPipe };
  struct Scene {
    SceneType type = SceneType::kRoom;
    // room/yard/street: x, y extent and height, m; zero = the type's default.
    Eigen::Vector3d size = Eigen::Vector3d::Zero();
    int boxes = 8;               // [0, 64]
    double pipe_diameter = 0.6;  // m
    double pipe_length = 40.0;   // m
    double texel_m = 0.0;        // m per texel; zero = the type's default
    // Real-photo textures (source.scene.textures): the surfaces take their texture tiles from
    // these grey images in turn instead of the procedural dead leaves; empty = procedural.
    std::vector<GreyImage> textures;
    // Moving objects (source.scene.moving_objects; room, yard, street): textured boxes that
    // slide back and forth along straight lines across the free floor, independently of the
    // rig (people, cars: features a VO must reject as outliers).
    struct MovingObjects {
      int count = 0;                             // [0, 64]; 0: none
      Eigen::Vector3d size_m = {0.6, 0.6, 1.8};  // x, y, z extent, each (0, 100] m
      double speed_mps = 1.4;                    // (0, 100] m/s
    } moving_objects;
  } scene;

  // --- Imaging and device behaviour -----------------------------------------------------------
  double noise_sigma = 2.0;      // grey levels, [0, 100]
  double blur_exposure_s = 0.0;  // 0: no motion blur; else (0, frame period)
  int blur_samples = 4;          // [2, 32] when blurring
  // Rolling shutter: time from the exposure of the top row to the bottom row's; row r is
  // exposed r / (height - 1) of it after the frame's stamp. 0: global shutter; else
  // [0, frame period).
  double rolling_shutter_s = 0.0;
  double drop_probability = 0.0;               // [0, 1)
  double timestamp_jitter_s = 0.0;             // sigma; 3 sigma < half a frame period
  std::map<std::string, double> fail_after_s;  // camera name -> stream time of failure, >= 0
  // camera name -> [from, to) stream seconds of black images, 0 <= from < to
  std::map<std::string, std::pair<double, double>> blackout_s;
  // camera name -> [from, to) stream seconds of frames blurred over 90 % of the frame period
  std::map<std::string, std::pair<double, double>> blur_burst_s;
  double vignetting = 0.0;  // [0, 1): corner light 1 - vignetting of the centre's (quadratic)
  struct ExposureSteps {
    double interval_s = 0.0;  // 0: off; else > 0
    double max_factor = 1.0;  // [1, 8]
  } exposure_steps;
  int render_block = 4;  // [1, 32]

  // --- Hardware trigger (`source.trigger`, simulated_trigger_timeline.h) ---------------------
  // Camera i hangs on line i of a simulated trigger generator (the firmware core on a drifting
  // MCU clock, its reports on a link with one-sided delay jitter); every frame gets the pulse's
  // sequence number and mapped exposure centre. The cameras still expose on the rig's clock, so
  // a drift shifts the mapped time from the rendered one by drift x time.
  struct Trigger {
    bool enabled = false;
    double drift_ppm = 0.0;            // [-1000, 1000]
    double link_jitter_ms = 2.0;       // one-sided delay, uniform [0, x], [0, 20]
    double exposure_ms = 0.0;          // [0, frame period): rises lead the centre by half
    double corrupt_probability = 0.0;  // per link byte, [0, 0.01]
  } trigger;

  // Ok when consistent; else the first violated constraint as "<field>: <constraint>".
  // Checks the cameras too (names, models, mountings), so it is meant for a complete spec.
  Status Check() const;

  // The scene size / texel size in use (the type's defaults when zero).
  Eigen::Vector3d SceneSize() const;
  double TexelSize() const;
  // Duration of the trajectory, seconds (0 when it has neither waypoints nor >= 2 samples).
  double TrajectoryDuration() const;
  // Frames per camera in use: num_frames, else round(duration_s * frame_rate_hz), else every
  // frame time inside the trajectory.
  int64_t FrameCount() const;
};

// Smallest distance between any camera centre and any surface that MakeSimulatedRig accepts, m.
inline constexpr double kMinClearance = 0.05;
// Smallest distance between any camera centre and any moving object's box, m (their lines are
// drawn until they keep it).
inline constexpr double kMovingObjectClearance = 0.5;

std::string ToString(SimulatedRigSpec::SceneType type);  // "room", "yard", "street", "pipe"
std::optional<SimulatedRigSpec::SceneType> SceneTypeFromString(const std::string& name);

// World-from-master orientation of a waypoint from yaw, pitch, roll in degrees (see the
// `ypr_deg` key above): a level master camera looking along world +x is ypr = (0, 0, 0).
Eigen::Quaterniond WaypointOrientationFromYpr(double yaw_deg, double pitch_deg, double roll_deg);

}  // namespace rigcal::sim
