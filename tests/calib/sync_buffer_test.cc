// SPDX-License-Identifier: Apache-2.0
// SyncBuffer matching, eviction, clock glitches and interpolation; over 600 lines: one fixture
// shared by all the buffer's behaviours, which read best side by side.
#include "rigcal/calib/sync_buffer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <new>
#include <random>
#include <stdexcept>
#include <thread>

// Counts heap allocations of this test binary, to show that Push and Pop allocate nothing.
// Sanitizers bring their own operator new: the count is not available there.
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__) || defined(RIGCAL_ASAN) || \
    defined(RIGCAL_TSAN)
#define RIGCAL_COUNT_ALLOCATIONS 0
#else
#define RIGCAL_COUNT_ALLOCATIONS 1
std::atomic<long> g_allocations{0};
void* operator new(std::size_t n) {
  ++g_allocations;
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t n, std::align_val_t a) {
  ++g_allocations;
  const std::size_t align = static_cast<std::size_t>(a);
  if (void* p = std::aligned_alloc(align, (n + align - 1) / align * align)) return p;
  throw std::bad_alloc();
}
// The replaced operator new allocates with malloc, so free is the matching release; GCC 12
// cannot see that through the replacement and warns.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
#pragma GCC diagnostic pop
#endif

namespace rigcal {
namespace {

using std::chrono::milliseconds;

constexpr int64_t kStart = 1'000'000'000;  // first frame [ns]

// An entry of frame `frame` (stored in C.x so that tests can check which frames were matched).
CameraPose Entry(int camera, int64_t t_ns, int64_t frame = 0, int64_t seq = -1) {
  CameraPose p;
  p.camera = camera;
  p.t_ns = t_ns;
  p.trigger_seq = seq;
  p.pose.C = Eigen::Vector3d(static_cast<double>(frame), camera, 0.0);
  return p;
}

int64_t FrameOf(const CameraPose& p) { return std::llround(p.pose.C.x()); }

std::vector<MatchedSet> Drain(SyncBuffer& buffer) {
  std::vector<MatchedSet> sets;
  MatchedSet set;
  while (buffer.TryPop(&set)) sets.push_back(set);
  return sets;
}

// Every set: master time strictly increasing (also across calls via *last_t), master and
// required members present, members matching the master (same trigger seq, or within
// tolerance), and, with `same_frame`, every member from the master's frame.
void ExpectConsistent(const std::vector<MatchedSet>& sets, const SyncOptions& o,
                      bool same_frame = true, int64_t* last_t = nullptr) {
  int64_t prev = last_t ? *last_t : std::numeric_limits<int64_t>::min();
  const int64_t tol = o.EffectiveToleranceNs();
  for (const MatchedSet& set : sets) {
    ASSERT_EQ(set.poses.size(), static_cast<size_t>(o.num_cameras));
    ASSERT_TRUE(set.poses[0].has_value());
    const CameraPose& m = *set.poses[0];
    EXPECT_EQ(set.t_ns, m.t_ns);
    EXPECT_GT(set.t_ns, prev) << "sets must leave in strictly increasing master time";
    prev = set.t_ns;
    for (int j = 1; j < o.num_cameras; ++j) {
      if (!set.poses[j]) {
        EXPECT_FALSE(o.IsRequired(j)) << "required camera " << j << " missing at " << set.t_ns;
        continue;
      }
      const CameraPose& s = *set.poses[j];
      EXPECT_EQ(s.camera, j);
      if (o.match_by_trigger_seq && s.trigger_seq >= 0 && m.trigger_seq >= 0) {
        EXPECT_EQ(s.trigger_seq, m.trigger_seq);
      } else {
        EXPECT_LE(std::abs(s.t_ns - m.t_ns), tol) << "camera " << j << " at " << set.t_ns;
      }
      if (same_frame) {
        EXPECT_EQ(FrameOf(s), FrameOf(m)) << "camera " << j;
      }
    }
  }
  if (last_t) *last_t = prev;
}

// Each slave entry is used at most once: a camera's members are strictly increasing in time.
void ExpectMembersUsedOnce(const std::vector<MatchedSet>& sets, int num_cameras) {
  for (int j = 0; j < num_cameras; ++j) {
    int64_t prev = std::numeric_limits<int64_t>::min();
    for (const MatchedSet& set : sets) {
      if (!set.poses[j]) continue;
      EXPECT_GT(set.poses[j]->t_ns, prev) << "camera " << j;
      prev = set.poses[j]->t_ns;
    }
  }
}

void ExpectCountsAddUp(const SyncStats& s, const SyncOptions& o) {
  ASSERT_EQ(s.cameras.size(), static_cast<size_t>(o.num_cameras));
  for (int c = 0; c < o.num_cameras; ++c) {
    const SyncCameraStats& k = s.cameras[c];
    EXPECT_EQ(k.pushed, k.used + k.Dropped() + k.fill) << "camera " << c;
    EXPECT_LE(k.fill, static_cast<uint64_t>(o.capacity)) << "camera " << c;
  }
  EXPECT_EQ(s.total.pushed, s.total.used + s.total.Dropped() + s.total.fill);
  EXPECT_EQ(s.sets_emitted, s.sets_popped + s.consumer_overflow + s.ready_fill);
  EXPECT_EQ(s.sets_emitted, s.cameras[0].used);
  EXPECT_LE(s.ready_fill, static_cast<uint64_t>(o.ready_capacity));
}

// A simulated rig: frame k of camera c is stamped kStart + k * period + offset(c) + jitter,
// jitter uniform in [-jitter, jitter]; cameras push in index order, frame by frame.
struct Feed {
  int frames = 100;
  int64_t jitter_ns = 0;
  std::function<bool(int camera, int frame)> missing = [](int, int) { return false; };
  std::function<int64_t(int camera)> offset_ns = [](int) { return int64_t{0}; };
  bool with_seq = false;
  bool expect_accepted = true;  // fail the test on any rejected push
  uint32_t seed = 1;
};

void FeedFrames(SyncBuffer& buffer, const Feed& feed, int first_frame = 0, int last_frame = -1) {
  const SyncOptions& o = buffer.options();
  std::mt19937 rng(feed.seed + first_frame);
  std::uniform_int_distribution<int64_t> jitter(-feed.jitter_ns, feed.jitter_ns);
  if (last_frame < 0) last_frame = feed.frames - 1;
  for (int k = first_frame; k <= last_frame; ++k) {
    for (int c = 0; c < o.num_cameras; ++c) {
      const int64_t t = kStart + k * o.frame_period_ns + feed.offset_ns(c) + jitter(rng);
      if (feed.missing(c, k)) continue;
      const PushResult r = buffer.Push(Entry(c, t, k, feed.with_seq ? k : -1));
      if (feed.expect_accepted) {
        ASSERT_EQ(r, PushResult::kAccepted) << "camera " << c << " frame " << k;
      }
    }
  }
}

// Options for n cameras; the ready queue holds every set of these tests (they pop at the end).
SyncOptions Cameras(int n) {
  SyncOptions o;
  o.num_cameras = n;
  o.ready_capacity = 1024;
  return o;
}

TEST(SyncOptions, DefaultsAreDerivedFromTheFramePeriod) {
  SyncOptions o;
  EXPECT_TRUE(o.Check().ok()) << o.Check().message();
  EXPECT_EQ(o.EffectiveToleranceNs(), o.frame_period_ns / 2);
  EXPECT_EQ(o.EffectiveMaxWaitNs(), 3 * o.frame_period_ns);
  o.frame_period_ns = 100'000'000;
  EXPECT_EQ(o.EffectiveToleranceNs(), 50'000'000);
  o.tolerance_ns = 7;
  o.max_wait_ns = 11;
  EXPECT_EQ(o.EffectiveToleranceNs(), 7);
  EXPECT_EQ(o.EffectiveMaxWaitNs(), 11);
  o.num_cameras = 3;
  EXPECT_TRUE(o.IsRequired(2));
  o.required = {true, true, false};
  EXPECT_TRUE(o.IsRequired(0));
  EXPECT_FALSE(o.IsRequired(2));
}

TEST(SyncOptions, CheckNamesTheOffendingField) {
  const std::vector<std::pair<std::string, std::function<void(SyncOptions&)>>> cases = {
      {"num_cameras", [](SyncOptions& o) { o.num_cameras = 0; }},
      {"capacity", [](SyncOptions& o) { o.capacity = 0; }},
      {"frame_period_ns", [](SyncOptions& o) { o.frame_period_ns = 0; }},
      {"tolerance_ns", [](SyncOptions& o) { o.tolerance_ns = -1; }},
      {"max_wait_ns", [](SyncOptions& o) { o.max_wait_ns = -5; }},
      {"required", [](SyncOptions& o) { o.required = {true}; }},
      {"required[0]",
       [](SyncOptions& o) {
         o.required = {false, true};
       }},
      {"ready_capacity", [](SyncOptions& o) { o.ready_capacity = 0; }},
  };
  for (const auto& [field, spoil] : cases) {
    SyncOptions o;
    spoil(o);
    const Status status = o.Check();
    EXPECT_FALSE(status.ok()) << field;
    EXPECT_EQ(status.message().rfind(field + ": ", 0), 0u) << status.message();
    EXPECT_THROW(SyncBuffer{o}, InvalidOptions) << field;
    try {
      SyncBuffer buffer(o);
    } catch (const InvalidOptions& e) {
      EXPECT_EQ(std::string(e.what()), "SyncOptions: " + status.message());
    }
  }
}

TEST(SyncBuffer, ExactStampsMatchAtOnce) {
  const SyncOptions o = Cameras(3);
  SyncBuffer buffer(o);
  Feed feed;
  FeedFrames(buffer, feed);
  // An exact partner cannot be bettered: every set leaves with its last member.
  const auto sets = Drain(buffer);
  ASSERT_EQ(sets.size(), 100u);
  ExpectConsistent(sets, o);
  for (size_t k = 0; k < sets.size(); ++k) {
    EXPECT_EQ(FrameOf(*sets[k].poses[0]), static_cast<int64_t>(k));
    for (const auto& p : sets[k].poses) EXPECT_EQ(p->t_ns, sets[k].t_ns);
  }
  const SyncStats s = buffer.stats();
  EXPECT_EQ(s.total.Dropped(), 0u);
  EXPECT_EQ(s.total.fill, 0u);
  ExpectCountsAddUp(s, o);
}

TEST(SyncBuffer, JitteredStampsAllMatch) {
  const SyncOptions o = Cameras(4);
  SyncBuffer buffer(o);
  Feed feed;
  feed.frames = 500;
  // Every camera +-40 % of the tolerance: pair differences stay within 80 %, neighbours of
  // another frame are >= period - 80 % tolerance = 120 % tolerance away.
  feed.jitter_ns = o.EffectiveToleranceNs() * 2 / 5;
  FeedFrames(buffer, feed);
  auto sets = Drain(buffer);
  // Only the newest frames may still wait for a closer partner.
  EXPECT_GE(sets.size(), 498u);
  buffer.Flush();
  for (auto& set : Drain(buffer)) sets.push_back(set);
  ASSERT_EQ(sets.size(), 500u);
  ExpectConsistent(sets, o);
  for (size_t k = 0; k < sets.size(); ++k) EXPECT_EQ(FrameOf(*sets[k].poses[0]), int64_t(k));
  const SyncStats s = buffer.stats();
  EXPECT_EQ(s.total.Dropped(), 0u) << s.BriefReport();
  EXPECT_EQ(s.total.fill, 0u);
  ExpectCountsAddUp(s, o);
}

TEST(SyncBuffer, ToleranceIsInclusiveAndStampsBeyondItNeverMatch) {
  SyncOptions o = Cameras(2);
  o.tolerance_ns = o.frame_period_ns * 2 / 5;
  const int64_t tol = o.EffectiveToleranceNs();
  for (const int64_t offset : {tol, -tol, tol + 1, -tol - 1}) {
    SCOPED_TRACE(offset);
    SyncBuffer buffer(o);
    Feed feed;
    feed.frames = 50;
    feed.offset_ns = [&](int c) { return c == 1 ? offset : int64_t{0}; };
    FeedFrames(buffer, feed);
    buffer.Flush();
    const auto sets = Drain(buffer);
    const SyncStats s = buffer.stats();
    ExpectCountsAddUp(s, o);
    if (std::abs(offset) <= tol) {
      EXPECT_EQ(sets.size(), 50u);
      ExpectConsistent(sets, o);
      EXPECT_EQ(s.total.never_matched, 0u);
    } else {
      EXPECT_TRUE(sets.empty());
      EXPECT_EQ(s.cameras[0].never_matched, 50u);
      EXPECT_EQ(s.cameras[1].never_matched + s.cameras[1].fill, 50u);
      EXPECT_LE(s.cameras[1].fill, 1u);  // only the newest can still meet a later master
    }
  }
}

TEST(SyncBuffer, PicksTheNearestPartnerAndWaitsOnlyWhileACloserOneCanArrive) {
  SyncOptions o = Cameras(2);
  o.tolerance_ns = 20'000'000;
  const int64_t ms = 1'000'000;
  const int64_t t = kStart;
  {
    SyncBuffer buffer(o);
    ASSERT_EQ(buffer.Push(Entry(0, t)), PushResult::kAccepted);
    ASSERT_EQ(buffer.Push(Entry(1, t - 15 * ms)), PushResult::kAccepted);
    ASSERT_EQ(buffer.Push(Entry(1, t - 5 * ms)), PushResult::kAccepted);
    MatchedSet set;
    EXPECT_FALSE(buffer.TryPop(&set)) << "an entry in (t - 5 ms, t + 5 ms) may still come";
    ASSERT_EQ(buffer.Push(Entry(1, t + 4 * ms)), PushResult::kAccepted);
    ASSERT_TRUE(buffer.TryPop(&set)) << "a partner after the master is final";
    EXPECT_EQ(set.poses[1]->t_ns, t + 4 * ms);
    EXPECT_EQ(buffer.stats().cameras[1].never_matched, 2u);  // the two older ones
  }
  {
    SyncBuffer buffer(o);
    ASSERT_EQ(buffer.Push(Entry(1, t - 5 * ms)), PushResult::kAccepted);
    ASSERT_EQ(buffer.Push(Entry(0, t)), PushResult::kAccepted);
    MatchedSet set;
    EXPECT_FALSE(buffer.TryPop(&set));
    ASSERT_EQ(buffer.Push(Entry(1, t + 6 * ms)), PushResult::kAccepted);
    ASSERT_TRUE(buffer.TryPop(&set)) << "nothing after t + 6 ms can be closer than 5 ms";
    EXPECT_EQ(set.poses[1]->t_ns, t - 5 * ms);
    // Equal distance on both sides: the earlier entry, decided without waiting further.
    ASSERT_EQ(buffer.Push(Entry(0, t + 50 * ms)), PushResult::kAccepted);
    ASSERT_EQ(buffer.Push(Entry(1, t + 40 * ms)), PushResult::kAccepted);
    EXPECT_FALSE(buffer.TryPop(&set));
    ASSERT_EQ(buffer.Push(Entry(1, t + 60 * ms)), PushResult::kAccepted);
    ASSERT_TRUE(buffer.TryPop(&set));
    EXPECT_EQ(set.poses[1]->t_ns, t + 40 * ms);
  }
}

TEST(SyncBuffer, MissingSlaveFramesDropMastersAfterMaxWaitAndLaterSetsFlow) {
  const SyncOptions o = Cameras(3);
  const int64_t frames_waited = o.EffectiveMaxWaitNs() / o.frame_period_ns;  // 3
  SyncBuffer buffer(o);
  Feed feed;
  feed.frames = 60;
  feed.missing = [](int c, int k) { return c == 2 && k >= 10 && k < 30; };  // camera 2 silent
  FeedFrames(buffer, feed, 0, 9);
  auto sets = Drain(buffer);
  EXPECT_EQ(sets.size(), 10u);
  for (int k = 10; k < 30; ++k) {
    FeedFrames(buffer, feed, k, k);
    // Master k' is dropped once the stream has passed k' + max_wait, i.e. k - k' > 3 frames.
    const SyncStats s = buffer.stats();
    const int64_t expected_dropped = std::max<int64_t>(0, k - 10 - frames_waited);
    EXPECT_EQ(s.cameras[0].never_matched, static_cast<uint64_t>(expected_dropped)) << k;
    EXPECT_EQ(s.cameras[0].fill, static_cast<uint64_t>(k - 9 - expected_dropped)) << k;
    EXPECT_EQ(s.sets_emitted, 10u);
  }
  FeedFrames(buffer, feed, 30, 59);
  const SyncStats s = buffer.stats();
  EXPECT_EQ(s.cameras[0].never_matched, 20u);
  EXPECT_EQ(s.cameras[1].never_matched, 20u);
  EXPECT_EQ(s.sets_emitted, 40u);
  ExpectCountsAddUp(s, o);
  for (auto& set : Drain(buffer)) sets.push_back(set);
  ExpectConsistent(sets, o);
  ASSERT_EQ(sets.size(), 40u);
  EXPECT_EQ(FrameOf(*sets[9].poses[0]), 9);
  EXPECT_EQ(FrameOf(*sets[10].poses[0]), 30);
}

TEST(SyncBuffer, MissingOptionalSlaveIsLeftOutAndCounted) {
  SyncOptions o = Cameras(4);
  o.required = {true, true, true, false};
  SyncBuffer buffer(o);
  Feed feed;
  feed.frames = 100;
  feed.jitter_ns = o.EffectiveToleranceNs() * 2 / 5;
  // Camera 3 drops frames 20..24, and dies at frame 60.
  feed.missing = [](int c, int k) { return c == 3 && ((k >= 20 && k < 25) || k >= 60); };
  FeedFrames(buffer, feed);
  auto sets = Drain(buffer);
  EXPECT_GE(sets.size(), 98u) << "a dead optional camera must not hold the sets back";
  buffer.Flush();
  for (auto& set : Drain(buffer)) sets.push_back(set);
  ASSERT_EQ(sets.size(), 100u);
  ExpectConsistent(sets, o);
  for (int k = 0; k < 100; ++k) {
    EXPECT_EQ(sets[k].poses[3].has_value(), !feed.missing(3, k)) << k;
  }
  const SyncStats s = buffer.stats();
  EXPECT_EQ(s.cameras[3].optional_missing, 45u);
  EXPECT_EQ(s.cameras[1].optional_missing, 0u);
  EXPECT_EQ(s.total.never_matched, 0u);
  ExpectCountsAddUp(s, o);
}

TEST(SyncBuffer, DuplicatesOutOfOrderAndLateAreCountedByCause) {
  const SyncOptions o = Cameras(2);
  const int64_t ms = 1'000'000;
  const int64_t t = kStart;
  SyncBuffer buffer(o);
  EXPECT_EQ(buffer.Push(Entry(1, t)), PushResult::kAccepted);
  EXPECT_EQ(buffer.Push(Entry(1, t)), PushResult::kDuplicate);
  EXPECT_EQ(buffer.Push(Entry(1, t + 100 * ms, 0, 7)), PushResult::kAccepted);
  EXPECT_EQ(buffer.Push(Entry(1, t + 200 * ms, 0, 7)), PushResult::kDuplicate);  // same seq
  EXPECT_EQ(buffer.Push(Entry(1, t + 75 * ms)), PushResult::kOutOfOrder);
  EXPECT_EQ(buffer.Push(Entry(0, t)), PushResult::kAccepted);  // set at t
  MatchedSet set;
  ASSERT_TRUE(buffer.TryPop(&set));
  EXPECT_EQ(buffer.Push(Entry(0, t)), PushResult::kLate);
  EXPECT_EQ(buffer.Push(Entry(0, t - 100 * ms)), PushResult::kLate);
  EXPECT_EQ(buffer.Push(Entry(1, t)), PushResult::kLate);
  EXPECT_EQ(buffer.Push(Entry(1, t - ms)), PushResult::kLate);
  // A master at t + 150 ms has no partner (t + 100 ms and t + 300 ms are 50 and 150 ms away)
  // and none can come any more: dropped at once, and t + 100 ms with it.
  EXPECT_EQ(buffer.Push(Entry(1, t + 300 * ms)), PushResult::kAccepted);
  EXPECT_EQ(buffer.Push(Entry(0, t + 150 * ms)), PushResult::kAccepted);
  EXPECT_EQ(buffer.Push(Entry(0, t + 125 * ms)), PushResult::kOutOfOrder);
  EXPECT_EQ(buffer.Push(Entry(0, t + 150 * ms)), PushResult::kDuplicate);
  // Too old for any master after t + 150 ms: late although newer than camera 1's last member.
  EXPECT_EQ(buffer.Push(Entry(1, t + 120 * ms)), PushResult::kLate);
  const SyncStats s = buffer.stats();
  EXPECT_EQ(s.cameras[0].late, 2u);
  EXPECT_EQ(s.cameras[1].late, 3u);
  EXPECT_EQ(s.cameras[0].duplicate, 1u);
  EXPECT_EQ(s.cameras[1].duplicate, 2u);
  EXPECT_EQ(s.cameras[0].out_of_order, 1u);
  EXPECT_EQ(s.cameras[1].out_of_order, 1u);
  EXPECT_EQ(s.cameras[0].never_matched, 1u);
  EXPECT_EQ(s.cameras[1].never_matched, 1u);  // t + 100 ms
  EXPECT_EQ(s.cameras[1].fill, 1u);           // t + 300 ms
  EXPECT_EQ(s.total.late, 5u);
  EXPECT_EQ(s.sets_emitted, 1u);
  ExpectCountsAddUp(s, o);
}

TEST(SyncBuffer, FullRingsDropTheOldestAndNeverGrow) {
  SyncOptions o = Cameras(3);
  o.capacity = 8;
  o.max_wait_ns = 3'600'000'000'000;  // masters wait (almost) for ever for camera 1
  SyncBuffer buffer(o);
  auto t = [&](int k) { return kStart + k * o.frame_period_ns; };
  for (int k = 0; k < 100; ++k) {
    ASSERT_EQ(buffer.Push(Entry(0, t(k), k)), PushResult::kAccepted);
    ASSERT_EQ(buffer.stats().cameras[0].fill, std::min<uint64_t>(k + 1, 8));
  }
  for (int k = 0; k < 100; ++k) {
    ASSERT_EQ(buffer.Push(Entry(2, t(k), k)), PushResult::kAccepted);
    ASSERT_EQ(buffer.stats().cameras[2].fill, std::min<uint64_t>(k + 1, 8));
  }
  SyncStats s = buffer.stats();
  EXPECT_EQ(s.cameras[0].overflow, 92u) << s.BriefReport();
  EXPECT_EQ(s.cameras[2].overflow, 92u);
  EXPECT_EQ(s.sets_emitted, 0u);
  ExpectCountsAddUp(s, o);
  // Camera 1 delivers: the 8 buffered frames (92..99) still make sets.
  for (int k = 0; k < 100; ++k) {
    ASSERT_EQ(buffer.Push(Entry(1, t(k), k)), PushResult::kAccepted);
    ASSERT_LE(buffer.stats().cameras[1].fill, 8u);
  }
  const auto sets = Drain(buffer);
  ASSERT_EQ(sets.size(), 8u);
  EXPECT_EQ(FrameOf(*sets[0].poses[0]), 92);
  ExpectConsistent(sets, o);
  s = buffer.stats();
  EXPECT_EQ(s.cameras[1].overflow + s.cameras[1].never_matched, 92u);
  EXPECT_EQ(s.total.fill, 0u);
  ExpectCountsAddUp(s, o);
}

// A required partner lost to overflow makes its master unmatchable.
TEST(SyncBuffer, OverflowOfASlaveRingDropsItsMasters) {
  SyncOptions o = Cameras(2);
  o.capacity = 4;
  SyncBuffer buffer(o);
  for (int k = 0; k < 10; ++k)
    ASSERT_EQ(buffer.Push(Entry(1, kStart + k * o.frame_period_ns, k)), PushResult::kAccepted);
  for (int k = 0; k < 10; ++k)
    ASSERT_EQ(buffer.Push(Entry(0, kStart + k * o.frame_period_ns, k)), PushResult::kAccepted);
  const auto sets = Drain(buffer);
  ASSERT_EQ(sets.size(), 4u);
  EXPECT_EQ(FrameOf(*sets[0].poses[0]), 6);
  const SyncStats s = buffer.stats();
  EXPECT_EQ(s.cameras[1].overflow, 6u);
  EXPECT_EQ(s.cameras[0].never_matched, 6u);
  ExpectCountsAddUp(s, o);
}

TEST(SyncBuffer, PushAndPopDoNotAllocate) {
#if !RIGCAL_COUNT_ALLOCATIONS
  GTEST_SKIP() << "allocation counting is off under sanitizers";
#else
  SyncOptions o = Cameras(3);
  o.capacity = 16;
  o.ready_capacity = 8;
  o.required = {true, true, false};
  SyncBuffer buffer(o);
  std::mt19937 rng(3);
  std::uniform_int_distribution<int64_t> jitter(-o.EffectiveToleranceNs() / 2,
                                                o.EffectiveToleranceNs() / 2);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  MatchedSet set;
  set.poses.resize(o.num_cameras);  // the consumer's storage, reused by every Pop
  const long before = g_allocations.load();
  int popped = 0;
  for (int k = 0; k < 2000; ++k) {
    for (int c = 0; c < o.num_cameras; ++c) {
      if (u(rng) < 0.05) continue;  // lost frames: timeouts and never-matched entries
      buffer.Push(Entry(c, kStart + k * o.frame_period_ns + jitter(rng), k));
    }
    if (k % 3 == 0) buffer.Push(Entry(1, kStart));  // late
    if (k % 10 != 0) {  // and sometimes a slow consumer: ready-queue overflow
      while (buffer.TryPop(&set)) ++popped;
    }
  }
  const long allocations = g_allocations.load() - before;
  EXPECT_EQ(allocations, 0);
  EXPECT_GT(popped, 1500);
#endif
}

TEST(SyncBuffer, SlowConsumerLosesTheOldestReadySets) {
  SyncOptions o = Cameras(2);
  o.ready_capacity = 4;
  SyncBuffer buffer(o);
  Feed feed;
  feed.frames = 10;
  FeedFrames(buffer, feed);
  const SyncStats s = buffer.stats();
  EXPECT_EQ(s.sets_emitted, 10u);
  EXPECT_EQ(s.consumer_overflow, 6u);
  EXPECT_EQ(s.ready_fill, 4u);
  const auto sets = Drain(buffer);
  ASSERT_EQ(sets.size(), 4u);
  EXPECT_EQ(FrameOf(*sets[0].poses[0]), 6);
  ExpectCountsAddUp(buffer.stats(), o);
}

TEST(SyncBuffer, TriggerSeqMatchesDespiteLargeStampOffsets) {
  SyncOptions o = Cameras(3);
  o.match_by_trigger_seq = true;
  Feed feed;
  feed.frames = 200;
  feed.with_seq = true;
  // Slave clocks 10 s ahead and 7 s behind (all stamps stay positive), and jitter of 45 % of a
  // frame period (each stream stays increasing).
  feed.offset_ns = [](int c) -> int64_t {
    const int64_t base = 10'000'000'000;
    return base + (c == 1 ? 10'000'000'000 : c == 2 ? -7'000'000'000 : 0);
  };
  feed.jitter_ns = o.frame_period_ns * 9 / 20;
  feed.missing = [](int c, int k) { return c == 2 && k >= 50 && k < 53; };
  SyncBuffer buffer(o);
  FeedFrames(buffer, feed);
  buffer.Flush();
  const auto sets = Drain(buffer);
  ASSERT_EQ(sets.size(), 197u);
  ExpectConsistent(sets, o);
  ExpectMembersUsedOnce(sets, o.num_cameras);
  const SyncStats s = buffer.stats();
  EXPECT_EQ(s.cameras[0].never_matched, 3u);
  EXPECT_EQ(s.cameras[1].never_matched, 3u);
  ExpectCountsAddUp(s, o);

  // The same stream matched by stamps finds nothing: the offsets are far beyond tolerance.
  o.match_by_trigger_seq = false;
  feed.expect_accepted = false;
  SyncBuffer by_stamp(o);
  FeedFrames(by_stamp, feed);
  by_stamp.Flush();
  EXPECT_EQ(by_stamp.stats().sets_emitted, 0u);
}

TEST(SyncBuffer, RejectsUnknownCamerasAndInvalidPoses) {
  const SyncOptions o = Cameras(2);
  SyncBuffer buffer(o);
  EXPECT_EQ(buffer.Push(Entry(-1, kStart)), PushResult::kUnknownCamera);
  EXPECT_EQ(buffer.Push(Entry(2, kStart)), PushResult::kUnknownCamera);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  CameraPose p = Entry(1, kStart);
  p.pose.q.w() = nan;
  EXPECT_EQ(buffer.Push(p), PushResult::kInvalid);
  p = Entry(1, kStart);
  p.pose.C.y() = inf;
  EXPECT_EQ(buffer.Push(p), PushResult::kInvalid);
  p = Entry(1, kStart);
  p.pose.q.coeffs().setZero();
  EXPECT_EQ(buffer.Push(p), PushResult::kInvalid);
  p = Entry(0, kStart);
  p.quality = nan;
  EXPECT_EQ(buffer.Push(p), PushResult::kInvalid);
  EXPECT_EQ(buffer.Push(Entry(0, -1)), PushResult::kInvalid);
  EXPECT_EQ(buffer.Push(Entry(1, kStart)), PushResult::kAccepted);
  const SyncStats s = buffer.stats();
  EXPECT_EQ(s.unknown_camera, 2u);
  EXPECT_EQ(s.cameras[0].invalid, 2u);
  EXPECT_EQ(s.cameras[1].invalid, 3u);
  EXPECT_EQ(s.cameras[1].fill, 1u);
  ExpectCountsAddUp(s, o);
  EXPECT_STREQ(ToString(PushResult::kInvalid), "invalid");
}

TEST(SyncBuffer, PopTimesOutWhenNothingIsReady) {
  SyncBuffer buffer(Cameras(2));
  MatchedSet set;
  EXPECT_FALSE(buffer.TryPop(&set));
  const auto start = std::chrono::steady_clock::now();
  EXPECT_FALSE(buffer.Pop(&set, milliseconds(30)));
  EXPECT_GE(std::chrono::steady_clock::now() - start, milliseconds(29));
}

TEST(SyncBuffer, StopWakesABlockedPopAndRejectsPushes) {
  const SyncOptions o = Cameras(2);
  SyncBuffer buffer(o);
  std::atomic<bool> returned{false};
  bool popped = true;
  std::chrono::steady_clock::duration waited{};
  std::thread consumer([&] {
    MatchedSet set;
    const auto start = std::chrono::steady_clock::now();
    popped = buffer.Pop(&set, milliseconds(20'000));
    waited = std::chrono::steady_clock::now() - start;
    returned = true;
  });
  std::this_thread::sleep_for(milliseconds(50));
  EXPECT_FALSE(returned) << "Pop must block while nothing is ready";
  buffer.Stop();
  consumer.join();
  EXPECT_FALSE(popped);
  EXPECT_LT(waited, milliseconds(10'000));
  EXPECT_TRUE(buffer.stopped());
  EXPECT_EQ(buffer.Push(Entry(0, kStart)), PushResult::kStopped);
  EXPECT_EQ(buffer.stats().cameras[0].stopped, 1u);
  ExpectCountsAddUp(buffer.stats(), o);
}

TEST(SyncBuffer, PopDrainsReadySetsAfterStop) {
  SyncBuffer buffer(Cameras(2));
  Feed feed;
  feed.frames = 2;
  FeedFrames(buffer, feed);
  buffer.Stop();
  MatchedSet set;
  EXPECT_TRUE(buffer.Pop(&set, milliseconds(20'000)));
  EXPECT_TRUE(buffer.Pop(&set, milliseconds(20'000)));
  EXPECT_EQ(FrameOf(*set.poses[0]), 1);
  const auto start = std::chrono::steady_clock::now();
  EXPECT_FALSE(buffer.Pop(&set, milliseconds(20'000)));
  EXPECT_LT(std::chrono::steady_clock::now() - start, milliseconds(10'000));
}

// Random interleavings with duplicates, reordering, losses, stamps beyond tolerance, small rings
// and a slow consumer: whatever happens, sets are consistent and the counts add up.
TEST(SyncBuffer, RandomStreamsKeepTheInvariants) {
  for (uint32_t seed = 1; seed <= 20; ++seed) {
    SCOPED_TRACE(seed);
    std::mt19937 rng(seed);
    SyncOptions o = Cameras(4);
    o.capacity = 8;
    o.ready_capacity = 8;
    o.required = {true, true, seed % 2 == 0, true};
    o.match_by_trigger_seq = seed % 3 == 0;
    SyncBuffer buffer(o);
    const int64_t tol = o.EffectiveToleranceNs();
    std::uniform_int_distribution<int64_t> jitter(-tol * 3 / 5, tol * 3 / 5);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    std::vector<CameraPose> pending;  // pushed in random order within a short window
    std::vector<MatchedSet> sets;
    int64_t last_t = std::numeric_limits<int64_t>::min();
    MatchedSet set;
    for (int k = 0; k < 2000; ++k) {
      for (int c = 0; c < o.num_cameras; ++c) {
        if (u(rng) < 0.05) continue;
        const int seq = u(rng) < 0.9 ? k : -1;  // drawn before the jitter (RandomVector3)
        CameraPose p = Entry(c, kStart + k * o.frame_period_ns + jitter(rng), k, seq);
        pending.push_back(p);
        if (u(rng) < 0.03) pending.push_back(p);  // duplicate
      }
      std::shuffle(pending.begin(), pending.end(), rng);
      const size_t n = pending.size() > 8 ? pending.size() - 8 : pending.size() / 2;
      for (size_t i = 0; i < n; ++i) {
        const PushResult r = buffer.Push(pending[i]);
        ASSERT_NE(r, PushResult::kInvalid);
        ASSERT_NE(r, PushResult::kUnknownCamera);
      }
      pending.erase(pending.begin(), pending.begin() + n);
      if (u(rng) < 0.5) {
        while (buffer.TryPop(&set)) sets.push_back(set);
      }
      if (k % 100 == 0) ExpectCountsAddUp(buffer.stats(), o);
    }
    buffer.Flush();
    while (buffer.TryPop(&set)) sets.push_back(set);
    ExpectConsistent(sets, o, /*same_frame=*/false, &last_t);
    ExpectMembersUsedOnce(sets, o.num_cameras);
    const SyncStats s = buffer.stats();
    ExpectCountsAddUp(s, o);
    EXPECT_GT(s.sets_emitted, 100u) << s.BriefReport();
    EXPECT_GT(s.total.duplicate + s.total.out_of_order + s.total.late, 0u);
  }
}

}  // namespace
}  // namespace rigcal
