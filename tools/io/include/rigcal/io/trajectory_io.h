// SPDX-License-Identifier: Apache-2.0
#pragma once
// Per-camera trajectory files (one pose per line) and their matching by time stamp into a
// RigRecording.
//
// Pose semantics in every format: the position is the camera centre C in that camera's own
// world (odometry) frame, in the camera's odometry unit; the quaternion is the rotation
// world_from_camera (TUM convention), so p_world = R(q) p_cam + C.
//
// Formats, detected from the file's leading comment lines and its first data line:
//  - EuRoC / ASL CSV, when the first data line contains a comma:
//      `t_ns,p_x,p_y,p_z,q_w,q_x,q_y,q_z[,...]` (integer nanoseconds; further columns such as
//      velocities and IMU biases are ignored; the header line starts with '#').
//  - rigcal native, when a leading comment line reads `# rigcal poses`, or when the first
//    column of the first data line is an integer (no '.', no exponent) >= 1e12:
//      `t_ns qw qx qy qz Cx Cy Cz [segment]` (integer nanoseconds). The threshold is safe
//      because 1e12 seconds (31,000 years) is no plausible TUM stamp, while any CLOCK_MONOTONIC
//      or Unix time in nanoseconds after the first 17 minutes exceeds it. Native files whose
//      stamps start near 0 need the header (WriteTrajectoryNative writes it).
//  - TUM otherwise: `t tx ty tz qx qy qz qw [segment]`, t in seconds (decimal or exponent
//      notation, converted to nanoseconds exactly, without a double in between).
// Whitespace-separated formats take an optional integer 9th column: the scale segment id (a
// VO re-initialisation opens a new segment); all lines of one file have the same column
// count. Lines whose first non-blank character is '#' and blank lines are ignored.
// KITTI odometry files (3x4 matrices plus a separate time file) have their own reader,
// ReadKittiTrajectory.

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/time_format.h"  // FormatNsAsSeconds, used with these files
#include "rigcal/base/types.h"
#include "rigcal/calib/timed_trajectory.h"

namespace rigcal::io {

enum class TrajectoryFormat { kTum, kEurocCsv, kNative };
std::string ToString(TrajectoryFormat format);  // "TUM", "EuRoC CSV", "rigcal native"

struct TrajectoryReadOptions {
  // A quaternion whose norm differs from 1 by at most this much, or by at most the rounding of
  // its printed digits (0.5e-d per component printed with d decimals, as a vector length), is
  // normalised (one warning per file on the "tools" logger counts such lines); beyond it the
  // line is an error. 1e-3: EuRoC's ground truth prints 6 decimals yet is off by up to 1.5e-4.
  double max_quaternion_norm_error = 1e-3;
};

// Reads one trajectory file, format auto-detected (see above). On error the message starts
// with `<path>:<line>: ` (or `<path>: ` for whole-file problems) and says what is wrong:
// unreadable file, unparsable column (named by number and meaning), NaN/inf, non-unit
// quaternion (with its norm), time going backwards or a duplicate stamp (with the line of
// the earlier stamp), a wrong column count, or a file without poses. `format`, when not
// null, receives the detected format.
Expected<TimedTrajectory> ReadTrajectory(const std::string& path,
                                         const TrajectoryReadOptions& options = {},
                                         TrajectoryFormat* format = nullptr);

// A camera's trajectory argument on the command line: "NAME=FILE" names the camera NAME (EuRoC's
// mav0/cam1/data.csv would otherwise be "data"), "FILE" names it after the file's stem. An
// argument that is an existing file is always a FILE, even with a '=' in it.
struct NamedTrajectoryPath {
  std::string name;  // empty: the file's stem
  std::string path;
};
NamedTrajectoryPath ParseNamedTrajectoryPath(const std::string& argument);

// ReadTrajectory of a "NAME=FILE" or "FILE" argument, the trajectory named NAME when given.
Expected<TimedTrajectory> ReadNamedTrajectory(const std::string& argument,
                                              const TrajectoryReadOptions& options = {},
                                              TrajectoryFormat* format = nullptr);

// Reads a KITTI odometry pose file and its time file: `poses_path` has one pose per line, the
// 12 numbers of the row-major 3x4 matrix [R | t] (camera frame: x right, y down, z forward;
// world = the first camera pose), `times_path` one time in seconds per line (the same count).
// R is world_from_camera and t the camera centre, as in every other format. Rotations are
// projected onto the nearest rotation when orthonormal within 1e-4 (KITTI prints 7 digits),
// else an error. Errors start with `<path>:<line>: ` and name the column; the trajectory
// is named after the pose file's stem.
Expected<TimedTrajectory> ReadKittiTrajectory(const std::string& poses_path,
                                              const std::string& times_path);

// Writes `trajectory` in TUM format (seconds with 9 decimals, so stamps round-trip exactly;
// doubles in shortest round-trip form), with the segment as 9th column when any segment id is
// not 0. `comment`, when not empty, is written instead of the column legend, each line as
// "# <line>". Atomic (WriteFileAtomically). The error names the path.
[[nodiscard]] Status WriteTrajectoryTum(const std::string& path, const TimedTrajectory& trajectory,
                                        const std::string& comment = "");

// Writes `trajectory` in the native format with its `# rigcal poses` header and the segment
// column. Atomic. The error names the path.
[[nodiscard]] Status WriteTrajectoryNative(const std::string& path,
                                           const TimedTrajectory& trajectory);

// Parses a decimal number of seconds ("12.5", "-3", "1.037359e-01") to integer nanoseconds,
// rounding half away from zero at the nanosecond, without floating point. nullopt when the
// text is not a number or the result does not fit in int64.
std::optional<int64_t> ParseSecondsToNs(std::string_view text);

// Matches the slaves' stamps to the master's. Master stamp k and slave stamp j match when
// each is the other's nearest stamp (so no pose is used twice when the rates differ) and
// |t_master - t_slave| <= tolerance_ns. Only master stamps matched in every slave are kept;
// the recording takes the master's stamps, the cameras' names (must be distinct) and their
// segment ids. Errors: the time ranges do not overlap ("no overlapping time range: master
// a..b s, cam1 c..d s"), or fewer than 2 stamps match in all slaves (the message lists how
// many master stamps each slave matched).
Expected<RigRecording> MatchTrajectories(const TimedTrajectory& master,
                                         const std::vector<TimedTrajectory>& slaves,
                                         int64_t tolerance_ns);

}  // namespace rigcal::io
