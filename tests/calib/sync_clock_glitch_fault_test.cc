// Clock glitches in the SyncBuffer: a pose stamped far in the future (up to INT64_MAX) is
// rejected against the other cameras' clocks and counted, and matching goes on; a real jump of
// the stream is accepted once confirmed.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <vector>

#include "rigcal/calib/sync_buffer.h"

namespace rigcal {
namespace {

constexpr int64_t kStart = 1'000'000'000;
constexpr int64_t kPeriod = 50'000'000;  // 20 Hz

CameraPose Entry(int camera, int64_t t_ns) {
  CameraPose p;
  p.camera = camera;
  p.t_ns = t_ns;
  return p;
}

SyncOptions TwoCameras() {
  SyncOptions o;
  o.num_cameras = 2;
  o.frame_period_ns = kPeriod;
  o.ready_capacity = 4096;
  return o;
}

uint64_t Sets(SyncBuffer* buffer) {
  buffer->Flush();
  return buffer->stats().sets_emitted;
}

void ExpectCountsAddUp(const SyncStats& s) {
  for (const SyncCameraStats& k : s.cameras) {
    EXPECT_EQ(k.pushed, k.used + k.Dropped() + k.fill);
  }
}

// 200 frames of both cameras; `glitch(k, camera)` may push extra poses before frame k.
template <typename Glitch>
void Feed(SyncBuffer* buffer, int frames, Glitch glitch, int64_t offset = 0) {
  for (int k = 0; k < frames; ++k) {
    const int64_t t = offset + kStart + k * kPeriod;
    for (int c = 0; c < 2; ++c) {
      glitch(k, c);
      buffer->Push(Entry(c, t));
    }
  }
}

TEST(SyncClockGlitch, FutureStampsAreRejectedAndMatchingGoesOn) {
  SyncBuffer buffer(TwoCameras());
  std::vector<PushResult> glitches;
  Feed(&buffer, 200, [&](int k, int c) {
    if (k == 50 && c == 1) {
      glitches.push_back(buffer.Push(Entry(1, std::numeric_limits<int64_t>::max())));
    }
    if (k == 80 && c == 0) {  // the master, 1000 s ahead
      glitches.push_back(buffer.Push(Entry(0, kStart + 80 * kPeriod + 1'000'000'000'000)));
    }
    if (k == 120 && c == 1) {  // a burst of three, 10 s ahead
      for (int i = 1; i <= 3; ++i) {
        glitches.push_back(buffer.Push(Entry(1, kStart + 120 * kPeriod + 10'000'000'000 + i)));
      }
    }
  });
  EXPECT_EQ(glitches, std::vector<PushResult>(5, PushResult::kClockGlitch));
  EXPECT_EQ(Sets(&buffer), 200u);  // without the check: none after frame 50
  const SyncStats s = buffer.stats();
  EXPECT_EQ(s.cameras[0].clock_glitch, 1u);
  EXPECT_EQ(s.cameras[1].clock_glitch, 4u);
  EXPECT_EQ(s.cameras[1].out_of_order, 0u);
  EXPECT_NE(s.BriefReport().find("clock_glitch 4"), std::string::npos) << s.BriefReport();
  ExpectCountsAddUp(s);
}

TEST(SyncClockGlitch, ARealJumpOfEveryCameraIsAcceptedOnceConfirmed) {
  SyncBuffer buffer(TwoCameras());
  Feed(&buffer, 100, [](int, int) {});
  // Both cameras resume 10 s later (a pause of the recording): the first poses after the gap
  // are held back until each camera confirms its new timeline, then matching goes on.
  Feed(
      &buffer, 100, [](int, int) {}, 10'000'000'000 + 100 * kPeriod);
  const uint64_t sets = Sets(&buffer);
  EXPECT_GE(sets, 195u);
  EXPECT_LE(buffer.stats().cameras[0].clock_glitch, 4u);
  ExpectCountsAddUp(buffer.stats());
}

TEST(SyncClockGlitch, ACameraCatchingUpWithTheOthersIsNoGlitch) {
  SyncOptions o = TwoCameras();
  o.num_cameras = 3;
  o.required = {true, true, false};
  SyncBuffer buffer(o);
  // Camera 2 is silent for 8 s, then comes back on the common clock.
  for (int k = 0; k < 300; ++k) {
    const int64_t t = kStart + k * kPeriod;
    for (int c = 0; c < 3; ++c) {
      if (c == 2 && k >= 20 && k < 180) continue;
      EXPECT_EQ(buffer.Push(Entry(c, t)), PushResult::kAccepted)
          << "camera " << c << " frame " << k;
    }
  }
  EXPECT_GE(Sets(&buffer), 295u);
  EXPECT_EQ(buffer.stats().total.clock_glitch, 0u);
}

TEST(SyncClockGlitch, TriggerModeIgnoresStampOffsets) {
  SyncOptions o = TwoCameras();
  o.match_by_trigger_seq = true;
  SyncBuffer buffer(o);
  for (int k = 0; k < 50; ++k) {
    for (int c = 0; c < 2; ++c) {
      CameraPose p = Entry(c, kStart + k * kPeriod + (c == 1 ? 100'000'000'000 : 0));
      p.trigger_seq = k;
      EXPECT_EQ(buffer.Push(p), PushResult::kAccepted);
    }
  }
  EXPECT_EQ(Sets(&buffer), 50u);
}

}  // namespace
}  // namespace rigcal
