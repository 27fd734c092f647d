// SPDX-License-Identifier: Apache-2.0
#pragma once
// A RIGCAL_STATUS and a RIGCAL_EXTRINSICS with every field `rigcal status` shows set, for the
// monitor's tests (in-process) and the command's (through an LCM log).

#include <cmath>

#include "rigcal/lcm/extrinsics_message.h"
#include "rigcal/lcm/status_message.h"

namespace rigcal::monitor {

// Cameras front (tracking) and left (lost): 19.5 fps, 1234 frames, drops late 3 and never
// matched 7, pose age 42 ms; sync 999 sets, 5 / 64; CPU 87.5 %, RSS 123 MiB.
inline rig_status_t MakeStatus(int8_t state, int64_t utime = 1000) {
  rig_status_t s{};
  s.version = rig_status_t::VERSION;
  s.utime = utime;
  for (const char* name : {"front", "left"}) {
    camera_status_t c{};
    c.name = name;
    c.fps = 19.5;
    c.frames_received = 1234;
    c.dropped_late = 3;
    c.dropped_never_matched = 7;
    c.vo_state = camera_status_t::VO_TRACKING;
    c.last_pose_age_ms = 42;
    c.vo_segment = 1;
    c.relocalisations = 0;
    c.time_offset_std_s = -1.0;  // synchronised stamps: no clock offset
    c.clock_drift_std_ppm = -1.0;
    s.cameras.push_back(c);
  }
  s.cameras[1].vo_state = camera_status_t::VO_LOST;
  s.cameras[1].relocalisations = 3;
  s.num_cameras = 2;
  s.sync_sets_emitted = 999;
  s.sync_fill = 5;
  s.sync_capacity = 64;
  s.estimator_state = state;
  s.estimator_message = "left holds the rig back";
  s.cpu_percent = 87.5;
  s.rss_bytes = 123 << 20;
  return s;
}

// Slave left of master front: 90 degrees about y, C (-1, 1, 3), scale 0.5 in segment 4, σ as
// given for the rotation (-1 = unknown), position σ (0.01, unknown, 0.03), 321 motions used and 9
// rejected, refined.
inline rig_extrinsics_t MakeExtrinsics(int8_t state, double rot_std_deg) {
  rig_extrinsics_t e{};
  e.version = rig_extrinsics_t::VERSION;
  e.utime = 2000;
  e.t_ns = 5'000'000'000;
  e.master = "front";
  e.distance_unit = rig_extrinsics_t::UNIT_MASTER_ODOMETRY;
  slave_extrinsics_t s{};
  s.name = "left";
  const double h = std::sqrt(0.5);
  s.q[0] = h;  // 90 degrees about y
  s.q[2] = h;
  s.C[0] = -1.0;
  s.C[1] = 1.0;
  s.C[2] = 3.0;
  s.scale = 0.5;
  s.segment = 4;
  s.rot_std_deg = rot_std_deg;
  s.pos_std[0] = 0.01;
  s.pos_std[1] = -1;
  s.pos_std[2] = 0.03;
  s.scale_std = 0.002;
  s.motions_used = 321;
  s.motions_rejected = 9;
  s.state = state;
  s.flags = lcm::kWireFlagRefined;
  s.axis_offset_std = -1;
  s.message = "solved: fine";
  e.slaves.push_back(s);
  e.num_slaves = 1;
  return e;
}

}  // namespace rigcal::monitor
