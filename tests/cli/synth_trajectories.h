// SPDX-License-Identifier: Apache-2.0
#pragma once
// TUM trajectories of the rig of SynthLogTest (command_test.h: master front, slave left) for the
// tests that give `rigcal solve` or `rigcal import tum` files of it.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "rigcal/calib/synthetic.h"
#include "rigcal/io/trajectory_io.h"

namespace rigcal::cli_test {

// Writes dir/front.txt and dir/left.txt (a synthetic drive of the rig, by default the default
// one).
inline void WriteSynthTrajectories(const std::filesystem::path& dir,
                                   const DriveOptions& options = DriveOptions{}) {
  const Similarity left{Eigen::Quaterniond(0.9238795, 0, 0.3826834, 0).normalized(),
                        Eigen::Vector3d(0.3, 0.05, -0.2), 1.0};
  const SyntheticDrive drive = GenerateDrive({"front", "left"}, {left}, options);
  const RigRecording& rec = drive.recording;
  for (const CameraTrack* track : {&rec.master, &rec.slaves[0]}) {
    TimedTrajectory t;
    t.name = track->name;
    t.t_ns = rec.t_ns;
    t.poses = track->poses;
    t.segment = track->segment;
    ASSERT_TRUE(io::WriteTrajectoryTum((dir / (track->name + ".txt")).string(), t).ok());
  }
}

}  // namespace rigcal::cli_test
