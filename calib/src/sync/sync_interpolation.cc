// SPDX-License-Identifier: Apache-2.0
// SyncBuffer's interpolation mode (cameras that run free): the partner of a master entry in a
// slave is the slave's pose interpolated at the master's instant on the slave's clock. See the
// rule in rigcal/calib/sync_buffer.h. Runs with the buffer's mutex held; never allocates.
#include <algorithm>

#include "rigcal/calib/pose_interpolation.h"
#include "sync/sync_buffer_impl.h"

namespace rigcal {

int64_t SyncBuffer::Impl::NewestOnMasterClock(int c) const {
  const CameraState& cam = cameras_[c];
  return cam.any ? OnMasterClock(c, cam.newest_t) : stream_start_ns_;
}

SyncBuffer::Impl::Candidate SyncBuffer::Impl::FindInterpolation(int j, const CameraPose& m) const {
  const CameraState& cam = cameras_[j];
  const FixedRing<CameraPose>& ring = cam.ring;
  Candidate c;
  const int64_t ts = SaturatedAdd(m.t_ns, cam.offset_ns);
  c.target_ns = ts;
  const int n = static_cast<int>(ring.size());
  int hi = 0;  // first entry at or after the instant
  while (hi < n && ring[hi].t_ns < ts) ++hi;
  // An entry (nearly) at the instant is taken as it is; it is final once no closer one can come.
  for (const int k : {hi - 1, hi}) {
    if (k < 0 || k >= n) continue;
    const int64_t d = ring[k].t_ns >= ts ? ring[k].t_ns - ts : ts - ring[k].t_ns;
    if (d <= snap_ns_ && (c.index < 0 || d < c.distance)) {
      c.index = c.first = k;
      c.count = 1;
      c.distance = d;
    }
  }
  if (c.index >= 0) {
    c.final = c.distance == 0 || cam.newest_t - ts >= c.distance - 1;
    return c;
  }
  if (hi == n) return c;  // the instant is not bracketed yet: wait
  c.final = true;
  if (hi == 0) return c;  // nothing before the instant any more: no partner
  const int lo = hi - 1;
  auto joined = [&](int a, int b) {
    return ring[b].t_ns - ring[a].t_ns <= max_gap_ns_ && ring[a].segment == ring[b].segment;
  };
  if (!joined(lo, hi)) return c;  // a gap or a new segment: no partner
  c.index = c.first = lo;
  c.count = 2;
  c.distance = ts - ring[lo].t_ns;
  if (lo == 0 || !joined(lo - 1, lo)) return c;  // linear is all there will be
  if (hi + 1 == n) {
    c.final = false;  // the entry after next may still come: cubic then
    return c;
  }
  if (joined(hi, hi + 1)) {
    c.first = lo - 1;
    c.count = 4;
  }
  return c;
}

CameraPose SyncBuffer::Impl::TakeInterpolation(int j, const Candidate& c) {
  CameraState& cam = cameras_[j];
  const int before = c.count == 4 ? c.first + 1 : c.first;
  CameraPose out = cam.ring[before];
  out.trigger_seq = -1;
  if (c.count > 1) {
    int64_t t[4];
    Pose poses[4];
    for (int i = 0; i < c.count; ++i) {
      const CameraPose& e = cam.ring[c.first + i];
      t[i] = e.t_ns;
      poses[i] = e.pose;
      out.quality = std::min(out.quality, e.quality);
    }
    out.pose = InterpolateAround(t, poses, c.count, c.target_ns);
    out.t_ns = c.target_ns;
  }
  for (int i = 0; i < c.count; ++i) cam.contributed[c.first + i] = 1;
  return out;
}

void SyncBuffer::Impl::PopOldest(int c, uint64_t SyncCameraStats::*unused) {
  CameraState& cam = cameras_[c];
  if (cam.contributed.front())
    ++cam.stats.used;
  else
    ++(cam.stats.*unused);
  cam.ring.PopFront();
  cam.contributed.PopFront();
}

void SyncBuffer::Impl::ResolvedInterpolated(int j, const SyncKey& m) {
  CameraState& cam = cameras_[j];
  // A later master's instant is later: it needs at most the entry before the last one at or
  // before this instant (the cubic's first), so the entries before that one go.
  const int64_t ts = SaturatedAdd(m.t_ns, cam.offset_ns);
  while (cam.ring.size() >= 3 && cam.ring[2].t_ns <= ts) {
    PopOldest(j, &SyncCameraStats::never_matched);
  }
}

}  // namespace rigcal
