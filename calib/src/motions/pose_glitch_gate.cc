// SPDX-License-Identifier: Apache-2.0
// The online glitch gate of the recursive estimator (pose_glitch_gate.h).
#include "motions/pose_glitch_gate.h"

#include <algorithm>
#include <cmath>

#include "rigcal/base/quaternion.h"
#include "rigcal/base/robust_statistics.h"

namespace rigcal::internal {
namespace {

void Push(FixedRing<double>* ring, double value) {
  if (ring->full()) ring->PopFront();
  ring->PushBack() = value;
}

RobustStats StatsOf(const FixedRing<double>& ring) {
  std::vector<double> values(ring.size());
  for (size_t i = 0; i < ring.size(); ++i) values[i] = ring[i];
  return MedianAndSigma(std::move(values));
}

bool Finite(const CameraPose& p) { return p.pose.q.coeffs().allFinite() && p.pose.C.allFinite(); }

}  // namespace

PoseGlitchGate::PoseGlitchGate(int cameras, GlitchTest test) : test_(test) {
  const size_t window = static_cast<size_t>(std::max(test_.window, 1));
  for (int c = 0; c < cameras; ++c) {
    cameras_.emplace_back(2 * window + 1);
    cameras_.back().run.reserve(static_cast<size_t>(std::max(test_.max_run, 0)) + 1);
  }
  for (int c = 1; c < cameras; ++c) pairs_.emplace_back(10 * window + 1);
}

PoseGlitchGate::Verdict PoseGlitchGate::Check(int64_t t_ns,
                                              const std::vector<std::optional<CameraPose>>& poses) {
  SetSteps steps(std::min(poses.size(), cameras_.size()));
  Verdict out;
  out.rejected.assign(poses.size(), GlitchCause::kNone);
  out.confirmed.resize(poses.size());
  out.warming_up.assign(poses.size(), false);
  TestSteps(t_ns, poses, &steps, &out);
  TestAngles(poses, &steps, &out);
  AcceptCameras(t_ns, poses, steps, &out);
  AcceptPairs(poses, steps, out);
  return out;
}

bool PoseGlitchGate::Present(const std::vector<std::optional<CameraPose>>& poses,
                             const SetSteps& steps, size_t c) {
  return c < steps.speed.size() && poses[c] && Finite(*poses[c]);
}

void PoseGlitchGate::TestSteps(int64_t t_ns, const std::vector<std::optional<CameraPose>>& poses,
                               SetSteps* steps, Verdict* out) const {
  std::vector<GlitchCause>& verdict = out->rejected;
  for (size_t c = 0; c < steps->speed.size(); ++c) {
    if (!Present(poses, *steps, c)) continue;
    const Camera& cam = cameras_[c];
    const CameraPose& p = *poses[c];
    out->warming_up[c] = static_cast<int>(cam.speeds.size()) < test_.min_steps || !cam.have ||
                         p.segment != cam.segment;
    if (!cam.have || p.segment != cam.segment || t_ns <= cam.t_ns) continue;
    steps->continues[c] = true;
    const double dt = 1e-9 * static_cast<double>(t_ns - cam.t_ns);
    steps->speed[c] = (p.pose.C - cam.pose.C).norm() / dt;
    steps->turn[c] = AngleBetween(cam.pose.q, p.pose.q) / dt;
    if (static_cast<int>(cam.speeds.size()) < test_.min_steps) continue;
    const RobustStats s = StatsOf(cam.speeds), w = StatsOf(cam.turns);
    const double speed_limit =
        OutlierSpeed(test_, std::max(s.median, cam.last_speed), s.median, s.sigma,
                     kGlitchResolution * (1.0 + cam.pose.C.norm()) / dt);
    const double turn_limit = OutlierSpeed(test_, std::max(w.median, cam.last_turn), w.median,
                                           w.sigma, kGlitchResolution / dt);
    steps->turn_ratio[c] = steps->turn[c] / turn_limit;
    if (steps->speed[c] > speed_limit) {
      verdict[c] = GlitchCause::kPositionJump;
    } else if (steps->turn[c] > turn_limit) {
      verdict[c] = GlitchCause::kRotationJump;
    }
  }
}

void PoseGlitchGate::TestAngles(const std::vector<std::optional<CameraPose>>& poses,
                                SetSteps* steps, Verdict* out) const {
  std::vector<GlitchCause>& verdict = out->rejected;
  for (size_t c = 1; c < steps->speed.size(); ++c) {
    const Pair& pair = pairs_[c - 1];
    if (!Present(poses, *steps, 0) || !Present(poses, *steps, c) || !pair.have ||
        pair.master_segment != poses[0]->segment || pair.slave_segment != poses[c]->segment) {
      continue;
    }
    steps->diff[c] =
        AngleBetween(pair.master, poses[0]->pose.q) - AngleBetween(pair.slave, poses[c]->pose.q);
    steps->has_diff[c] = true;
    if (verdict[0] != GlitchCause::kNone || verdict[c] != GlitchCause::kNone) continue;
    if (!pair.diffs.full()) continue;  // σ from fewer steps is too uncertain for 8 σ
    const RobustStats d = StatsOf(pair.diffs);
    if (std::abs(steps->diff[c] - d.median) > test_.outlier_sigmas * d.sigma + kGlitchResolution) {
      verdict[steps->turn_ratio[0] > steps->turn_ratio[c] ? 0 : c] = GlitchCause::kAngleMismatch;
    }
  }
}

void PoseGlitchGate::AcceptCameras(int64_t t_ns,
                                   const std::vector<std::optional<CameraPose>>& poses,
                                   const SetSteps& steps, Verdict* out) {
  std::vector<GlitchCause>& verdict = out->rejected;
  for (size_t c = 0; c < steps.speed.size(); ++c) {
    if (!Present(poses, steps, c)) continue;
    Camera& cam = cameras_[c];
    bool continues = steps.continues[c];
    if (verdict[c] != GlitchCause::kNone) {
      if (++cam.rejected_in_row <= test_.max_run) {
        if (cam.run.empty()) {  // the jump into the run, for the bridged test below
          cam.run_jump = verdict[c] == GlitchCause::kPositionJump ? steps.speed[c] : steps.turn[c];
        }
        cam.run.push_back(verdict[c]);
        continue;
      }
      verdict[c] = GlitchCause::kNone;
      out->warming_up[c] = true;
      continues = false;
      cam.run.clear();
      while (!cam.speeds.empty()) cam.speeds.PopFront();
      while (!cam.turns.empty()) cam.turns.PopFront();
    }
    if (continues) {
      Push(&cam.speeds, steps.speed[c]);
      Push(&cam.turns, steps.turn[c]);
      cam.last_speed = steps.speed[c];
      cam.last_turn = steps.turn[c];
      // Back on the trajectory: real motion bridges at about its steps' rate, a glitch far
      // below the jump into it (pose_glitches.h).
      if (!cam.run.empty()) {
        const GlitchCause first = cam.run.front();
        const double bridge = first == GlitchCause::kPositionJump ? steps.speed[c] : steps.turn[c];
        if (first == GlitchCause::kAngleMismatch || !(test_.jump_factor * bridge > cam.run_jump)) {
          out->confirmed[c].swap(cam.run);
        }
      }
    } else if (cam.have && poses[c]->segment != cam.segment) {
      while (!cam.speeds.empty()) cam.speeds.PopFront();
      while (!cam.turns.empty()) cam.turns.PopFront();
    }
    cam.run.clear();
    cam.have = true;
    cam.t_ns = t_ns;
    cam.pose = poses[c]->pose;
    cam.segment = poses[c]->segment;
    cam.rejected_in_row = 0;
  }
}

void PoseGlitchGate::AcceptPairs(const std::vector<std::optional<CameraPose>>& poses,
                                 const SetSteps& steps, const Verdict& out) {
  const std::vector<GlitchCause>& verdict = out.rejected;
  for (size_t c = 1; c < steps.speed.size(); ++c) {
    if (!Present(poses, steps, 0) || !Present(poses, steps, c) ||
        verdict[0] != GlitchCause::kNone || verdict[c] != GlitchCause::kNone) {
      continue;
    }
    Pair& pair = pairs_[c - 1];
    if (steps.has_diff[c]) {
      Push(&pair.diffs, steps.diff[c]);
    } else {
      while (!pair.diffs.empty()) pair.diffs.PopFront();
    }
    pair.have = true;
    pair.master = poses[0]->pose.q;
    pair.slave = poses[c]->pose.q;
    pair.master_segment = poses[0]->segment;
    pair.slave_segment = poses[c]->segment;
  }
}

bool CountGlitch(const PoseGlitchGate::Verdict& verdict, int slave, GlitchCounts* counts) {
  const size_t c = static_cast<size_t>(slave) + 1;
  auto count = [&](size_t camera, int* where) {
    if (camera >= verdict.confirmed.size()) return;
    for (const GlitchCause cause : verdict.confirmed[camera]) {
      counts->position_jump += cause == GlitchCause::kPositionJump;
      counts->rotation_jump += cause == GlitchCause::kRotationJump;
      counts->angle_mismatch += cause == GlitchCause::kAngleMismatch;
      ++*where;
    }
  };
  count(0, &counts->in_master);
  count(c, &counts->in_slave);
  auto rejected = [&](size_t camera) {
    return camera < verdict.rejected.size() && verdict.rejected[camera] != GlitchCause::kNone;
  };
  auto warming_up = [&](size_t camera) {
    return camera < verdict.warming_up.size() && verdict.warming_up[camera];
  };
  return rejected(0) || rejected(c) || warming_up(0) || warming_up(c);
}

}  // namespace rigcal::internal
