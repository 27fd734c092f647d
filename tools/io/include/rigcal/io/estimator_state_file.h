// SPDX-License-Identifier: Apache-2.0
#pragma once
// The estimator state file: a RigEstimatorState (calib/estimator_state.h) as versioned plain
// text with a checksum, so that `rigcal calib --resume` continues where a previous run stopped.
//
//   rigcal-estimator-state <version>
//   cameras <count> <name>...
//   master_segment <segment> <0|1>
//   consumed <count> <t_ns>...   (version 4: per camera the newest stamp consumed, -1 none)
//   clocks <count>               (version 5: 0, or one line per slave when the cameras run free)
//   clock <i> <initialised 0|1> <offset_s> <drift> <P00> <P01> <P11> <t_ns> <measurements> <jumps>
//   fingerprints <count>         (version 6: 0, or one line per camera)
//   fingerprint <c> <t_ns> <qw qx qy qz> <Cx Cy Cz> <t_ns> <q> <C>   (first, newest pose taken)
//   slave <i>            then its counts, noise levels, segment, model and the long and short
//   ...                  statistics (every sum, 17 significant digits: exact round trip), and
//                        (version 6) the published estimate and what its σ rest on
//                        (SlavePublishedState; src/estimator_state_published.h; version 7:
//                        with the decalibration alarm)
//   checksum <FNV-1a 64 of the lines between the header and this one, hex>
//
// Version 3 holds the translation-direction moments (Ddir, the translational model's σ);
// version-2 files are read too, with those moments derived from the others
// (DirectionMomentsFromCrossMoments). Version 4 adds the consumed stamps (how far each input
// was consumed: a resume skips those poses); older files resume without them. Version 5 adds
// the clock offsets of free-running slaves (ClockOffsetState); a version-4 file resumes with
// them estimated afresh. Version 6 adds per slave the published estimate (a refinement the
// statistics cannot reproduce: the batch calibrator's on the pose history), the inputs of its σ
// inflation and the convergence count, so that a resume without new data publishes the same
// estimate; an older file resumes with the estimate re-solved from the statistics. Version 7 adds
// to it the decalibration alarm (DecalibrationAlarmState), so that a slave found decalibrated
// before a restart is still reported decalibrated after it; a version-6 file resumes without
// an alarm. Version 8 adds to the statistics the weight of the motions in the position sums
// ("posweight", MotionSums::position_weight: fewer than "weight" once the master odometry
// re-initialised, as a resumed run's restarted VO does), which the σ of C divides by; an older
// file resumes with it equal to "weight" (its σ of C too small by sqrt(posweight / weight)
// until the next re-initialisation).

#include <string>
#include <string_view>

#include "rigcal/base/status.h"
#include "rigcal/calib/estimator_state.h"

namespace rigcal::io {

inline constexpr int kEstimatorStateVersion = 8;        // written
inline constexpr int kOldestEstimatorStateVersion = 2;  // oldest read

// The state as the text of a state file (version kEstimatorStateVersion).
std::string FormatEstimatorState(const RigEstimatorState& state);

// The state in the text of a state file. Errors: not a state file, a version this build does
// not read, a checksum mismatch (corrupt or truncated file), malformed content, a value out of
// range even with a valid checksum (a negative count, a sum beyond 1e100, a non-finite number:
// the error names the slave and the field). Whether the
// state fits an estimator (its cameras) is RigEstimator::RestoreState's to say.
Expected<RigEstimatorState> ParseEstimatorState(std::string_view text);

// `text` (a state file, or any text) with its checksum line, the last "checksum " and what
// follows, made right for the lines between the first line and it (appended when there is
// none): what ParseEstimatorState checks first. For tools that edit a state file by hand, and
// for the fuzz target, which reaches the parser behind the checksum with it.
std::string WithEstimatorStateChecksum(std::string_view text);

}  // namespace rigcal::io
