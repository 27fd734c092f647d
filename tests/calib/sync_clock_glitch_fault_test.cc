// SPDX-License-Identifier: Apache-2.0
// Clock glitches in the SyncBuffer: a pose stamped far in the future (up to INT64_MAX) or in the
// past, a clock that alone steps by 10 s or by 1 s (the camera's own rate), duplicates: rejected
// against the other cameras' clocks and counted, warned about once per burst, and matching goes
// on; a real jump of the stream is accepted once confirmed; poses consumed before a restart are
// skipped.
#include <gtest/gtest.h>
#include <spdlog/sinks/ringbuffer_sink.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "rigcal/base/logging.h"
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

// The calib logger's warnings while in scope.
class WarningCapture {
 public:
  WarningCapture() : sink_(std::make_shared<spdlog::sinks::ringbuffer_sink_mt>(1000)) {
    sink_->set_level(spdlog::level::warn);
    ModuleLogger("calib")->sinks().push_back(sink_);
  }
  ~WarningCapture() {
    auto& sinks = ModuleLogger("calib")->sinks();
    sinks.erase(std::remove(sinks.begin(), sinks.end(), sink_), sinks.end());
  }
  // Warnings that contain `text`.
  int Count(const std::string& text) const {
    int n = 0;
    for (const std::string& line : sink_->last_formatted())
      n += line.find(text) != std::string::npos;
    return n;
  }

 private:
  std::shared_ptr<spdlog::sinks::ringbuffer_sink_mt> sink_;
};

TEST(SyncClockGlitch, PastStampsAreRejectedAndCounted) {
  WarningCapture warnings;
  SyncBuffer buffer(TwoCameras());
  std::vector<PushResult> glitches;
  Feed(&buffer, 200, [&](int k, int c) {
    if (k == 60 && c == 1) {  // a burst: stamp 0, then 2.5 s back
      glitches.push_back(buffer.Push(Entry(1, 0)));
      glitches.push_back(buffer.Push(Entry(1, kStart + 60 * kPeriod - 2'500'000'000)));
    }
    if (k == 90 && c == 0) {  // the master, 3 s back
      glitches.push_back(buffer.Push(Entry(0, kStart + 90 * kPeriod - 3'000'000'000)));
    }
  });
  EXPECT_EQ(glitches, std::vector<PushResult>(3, PushResult::kClockGlitch));
  EXPECT_EQ(Sets(&buffer), 200u);
  const SyncStats s = buffer.stats();
  EXPECT_EQ(s.cameras[0].clock_glitch, 1u);
  EXPECT_EQ(s.cameras[1].clock_glitch, 2u);
  EXPECT_EQ(s.total.late + s.total.out_of_order, 0u);
  EXPECT_EQ(warnings.Count("clock glitch"), 2);  // one per burst
  ExpectCountsAddUp(s);
}

// One camera's clock steps 10 s ahead for 40 frames while the master keeps its clock: its poses
// are rejected for as long as the others disagree (the old rule accepted the jump after 5 poses
// and then lost every later pose of that camera as out of order), and matching goes on when the
// clock comes back.
TEST(SyncClockGlitch, AClockThatAloneJumpsIsRejectedUntilTheOthersAgree) {
  WarningCapture warnings;
  SyncBuffer buffer(TwoCameras());
  int glitched = 0;
  for (int k = 0; k < 200; ++k) {
    const int64_t t = kStart + k * kPeriod;
    EXPECT_EQ(buffer.Push(Entry(0, t)), PushResult::kAccepted) << k;
    const bool stepped = k >= 100 && k < 140;
    const PushResult r = buffer.Push(Entry(1, t + (stepped ? 10'000'000'000 : 0)));
    EXPECT_EQ(r, stepped ? PushResult::kClockGlitch : PushResult::kAccepted) << k;
    glitched += r == PushResult::kClockGlitch;
  }
  EXPECT_EQ(glitched, 40);
  EXPECT_EQ(Sets(&buffer), 160u);  // the 40 masters without a partner are never matched
  const SyncStats s = buffer.stats();
  EXPECT_EQ(s.cameras[1].clock_glitch, 40u);
  EXPECT_EQ(s.cameras[0].never_matched, 40u);
  EXPECT_EQ(s.total.out_of_order + s.total.late, 0u);
  EXPECT_EQ(warnings.Count("clock glitch"), 1);
  ExpectCountsAddUp(s);
}

// Ten master poses stamped 4e18 ns on, at the camera's own rate, back to back (in a log: no other
// camera's event between them), then the drive goes on on its clock. The run is rejected as
// clock glitches and named once, and moves no clock: every later pose is matched (the old rule
// took five such poses in a row while the others were silent as a restart of the stream, and
// every later pose was then 4e18 ns in the past).
TEST(SyncClockGlitch, AShortRunOnItsOwnTimelineIsNoRestart) {
  WarningCapture warnings;
  SyncBuffer buffer(TwoCameras());
  std::vector<PushResult> glitches;
  Feed(&buffer, 200, [&](int k, int c) {
    if (k != 100 || c != 0) return;
    for (int i = 0; i < 10; ++i) {
      glitches.push_back(buffer.Push(Entry(0, 4'000'000'000'000'000'000 + i * kPeriod)));
    }
  });
  EXPECT_EQ(glitches, std::vector<PushResult>(10, PushResult::kClockGlitch));
  EXPECT_EQ(Sets(&buffer), 200u);
  const SyncStats s = buffer.stats();
  EXPECT_EQ(s.cameras[0].clock_glitch, 10u);
  EXPECT_EQ(s.total.clock_glitch, 10u);
  EXPECT_EQ(warnings.Count("that no other camera shares: clock glitches"), 1);
  ExpectCountsAddUp(s);
}

// A restart of the stream where one camera resumes alone for longer than the glitch horizon at
// its rate (the other's first poses on the new clock come 3 s later): followed after 40 poses.
TEST(SyncClockGlitch, ARestartOfOneCameraWhileTheOthersAreSilentIsFollowed) {
  SyncBuffer buffer(TwoCameras());
  Feed(&buffer, 100, [](int, int) {});
  const int64_t resume = kStart + 100 * kPeriod + 10'000'000'000;
  std::vector<PushResult> master;
  for (int k = 0; k < 60; ++k) master.push_back(buffer.Push(Entry(0, resume + k * kPeriod)));
  EXPECT_EQ(std::count(master.begin(), master.end(), PushResult::kClockGlitch), 39);
  EXPECT_EQ(master[39], PushResult::kAccepted);
  for (int k = 60; k < 160; ++k) {
    for (int c = 0; c < 2; ++c) {
      EXPECT_EQ(buffer.Push(Entry(c, resume + k * kPeriod)), PushResult::kAccepted) << k;
    }
  }
  EXPECT_GE(Sets(&buffer), 200u);
  ExpectCountsAddUp(buffer.stats());
}

// A step of 1 s stays within the 2 s horizon of the other cameras' clocks, but is 20 frame
// intervals beyond the camera's own rate and ahead of every other camera.
TEST(SyncClockGlitch, AStepBeyondTheCamerasOwnRateIsRejected) {
  SyncBuffer buffer(TwoCameras());
  int glitched = 0;
  for (int k = 0; k < 200; ++k) {
    const int64_t t = kStart + k * kPeriod;
    buffer.Push(Entry(0, t));
    const bool stepped = k >= 100 && k < 110;
    glitched +=
        buffer.Push(Entry(1, t + (stepped ? 1'100'000'000 : 0))) == PushResult::kClockGlitch;
  }
  EXPECT_EQ(glitched, 10);
  EXPECT_EQ(Sets(&buffer), 190u);
  EXPECT_EQ(buffer.stats().total.out_of_order, 0u);
  ExpectCountsAddUp(buffer.stats());
}

TEST(SyncClockGlitch, DuplicatesAreCountedAndWarnedOncePerBurst) {
  WarningCapture warnings;
  SyncBuffer buffer(TwoCameras());
  for (int k = 0; k < 200; ++k) {
    const int64_t t = kStart + k * kPeriod;
    // The slave first, then (in two bursts) the same pose again, then the master.
    EXPECT_EQ(buffer.Push(Entry(1, t)), PushResult::kAccepted);
    if ((k > 60 && k <= 70) || (k > 150 && k <= 152)) {
      EXPECT_EQ(buffer.Push(Entry(1, t)), PushResult::kDuplicate);
      EXPECT_EQ(buffer.Push(Entry(1, t)), PushResult::kDuplicate);
    }
    EXPECT_EQ(buffer.Push(Entry(0, t)), PushResult::kAccepted);
  }
  EXPECT_EQ(Sets(&buffer), 200u);
  EXPECT_EQ(buffer.stats().cameras[1].duplicate, 24u);
  // A burst ends after 50 accepted poses of the camera in a row: two bursts.
  EXPECT_EQ(warnings.Count("a duplicate"), 2);
  ExpectCountsAddUp(buffer.stats());
}

// After a restart the poses the estimator consumed before it are skipped, counted `consumed`.
TEST(SyncClockGlitch, PosesConsumedBeforeARestartAreSkipped) {
  SyncBuffer buffer(TwoCameras());
  buffer.SkipConsumed({kStart + 99 * kPeriod, kStart + 99 * kPeriod});
  Feed(&buffer, 200, [](int, int) {});
  EXPECT_EQ(Sets(&buffer), 100u);
  const SyncStats s = buffer.stats();
  EXPECT_EQ(s.cameras[0].consumed, 100u);
  EXPECT_EQ(s.cameras[1].consumed, 100u);
  ExpectCountsAddUp(s);
}

}  // namespace
}  // namespace rigcal
