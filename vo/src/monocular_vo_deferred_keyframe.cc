// SPDX-License-Identifier: Apache-2.0
// MonocularVo keyframe work spread over two frames: a keyframe frame triangulates and runs the
// local bundle adjustment; the landmarks' descriptors (for relocalisation) and the new tracks
// wait for the start of the next frame. Nothing changes the tracks or the map in between, so
// the VO's results are those of doing it all at the keyframe, and the keyframe frames, the
// slowest, are shorter (issue 34: the time per frame's 90th percentile).

#include "monocular_vo_impl.h"

namespace rigcal::vo {

void MonocularVo::Impl::DeferKeyframeWork(const cv::Mat& grey, int kf) {
  FinishKeyframeWork();  // one keyframe per frame: nothing is left, but never lose work
  deferred_.views = CollectLandmarkViews();
  grey.copyTo(deferred_.grey);
  deferred_.keyframe = kf;
  deferred_.pending = true;
}

void MonocularVo::Impl::FinishKeyframeWork() {
  if (!deferred_.pending) return;
  deferred_.pending = false;
  AddLandmarkDescriptors(deferred_.grey, deferred_.views);
  AddNewTracks(deferred_.grey, deferred_.keyframe);
  deferred_.views = LandmarkViews();
}

}  // namespace rigcal::vo
