// SPDX-License-Identifier: Apache-2.0
// SyncBuffer under concurrency: one producer thread per camera, one consumer thread. Meant to
// run under ThreadSanitizer too (-DRIGCAL_TSAN_ENABLED=ON).

#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <random>
#include <thread>
#include <vector>

#include "rigcal/calib/sync_buffer.h"

namespace rigcal {
namespace {

using std::chrono::milliseconds;

constexpr int kCameras = 4;
constexpr int kFrames = 20'000;
constexpr int64_t kStart = 1'000'000'000;

// Per camera and frame: the stamp (+-40 % tolerance jitter) and whether the frame is lost (1 %).
struct Streams {
  std::array<std::vector<int64_t>, kCameras> t_ns;
  std::array<std::vector<char>, kCameras> missing;

  Streams(const SyncOptions& o, uint32_t seed) {
    std::mt19937 rng(seed);
    const int64_t j = o.EffectiveToleranceNs() * 2 / 5;
    std::uniform_int_distribution<int64_t> jitter(-j, j);
    std::bernoulli_distribution lost(0.01);
    for (int c = 0; c < kCameras; ++c) {
      for (int k = 0; k < kFrames; ++k) {
        t_ns[c].push_back(kStart + k * o.frame_period_ns + jitter(rng));
        missing[c].push_back(lost(rng));
      }
    }
  }
  bool Complete(int k) const {
    for (int c = 0; c < kCameras; ++c)
      if (missing[c][k]) return false;
    return true;
  }
};

CameraPose Entry(int camera, int64_t t_ns, int frame, bool with_seq) {
  CameraPose p;
  p.camera = camera;
  p.t_ns = t_ns;
  p.trigger_seq = with_seq ? frame : -1;
  p.pose.C = Eigen::Vector3d(frame, camera, 0.0);
  return p;
}

int FrameOf(const CameraPose& p) { return static_cast<int>(std::lround(p.pose.C.x())); }

// Results of Push per camera, tallied by the producers.
struct Tally {
  // One column per PushResult (kConsumed is the last value).
  static constexpr int kResults = static_cast<int>(PushResult::kConsumed) + 1;
  std::array<std::array<uint64_t, kResults>, kCameras> by_result{};
  uint64_t Count(int camera, PushResult r) const { return by_result[camera][static_cast<int>(r)]; }
};

// Pops until Stop; checks every set as it comes.
struct Consumer {
  std::vector<MatchedSet> sets;
  std::atomic<int> last_frame{-1};  // frame of the newest popped set, read by paced producers

  void Run(SyncBuffer& buffer) {
    sets.reserve(kFrames);
    MatchedSet set;
    while (true) {
      if (!buffer.Pop(&set, milliseconds(50))) {
        if (buffer.stopped()) break;
        continue;
      }
      sets.push_back(set);
      last_frame.store(FrameOf(*set.poses[0]), std::memory_order_release);
    }
  }
};

void ExpectConsistent(const std::vector<MatchedSet>& sets, const SyncOptions& o, bool same_frame) {
  int64_t prev = -1;
  std::array<int64_t, kCameras> prev_member;
  prev_member.fill(-1);
  int bad = 0;
  for (const MatchedSet& set : sets) {
    const CameraPose& m = *set.poses[0];
    bool ok = set.t_ns == m.t_ns && set.t_ns > prev;
    prev = set.t_ns;
    for (int c = 0; c < kCameras; ++c) {
      if (!set.poses[c]) {
        ok = ok && !o.IsRequired(c);
        continue;
      }
      const CameraPose& s = *set.poses[c];
      ok = ok && s.camera == c && s.t_ns > prev_member[c];  // each entry used once
      prev_member[c] = s.t_ns;
      if (o.match_by_trigger_seq && s.trigger_seq >= 0 && m.trigger_seq >= 0)
        ok = ok && s.trigger_seq == m.trigger_seq;
      else
        ok = ok && std::abs(s.t_ns - m.t_ns) <= o.EffectiveToleranceNs();
      if (same_frame) ok = ok && FrameOf(s) == FrameOf(m);
    }
    if (!ok && ++bad <= 5) ADD_FAILURE() << "inconsistent set at " << set.t_ns;
  }
  EXPECT_EQ(bad, 0);
}

void ExpectCountsAddUp(const SyncStats& s, const Tally& tally, const Streams& streams) {
  for (int c = 0; c < kCameras; ++c) {
    const SyncCameraStats& k = s.cameras[c];
    uint64_t pushes = 0;
    for (int f = 0; f < kFrames; ++f) pushes += !streams.missing[c][f];
    EXPECT_EQ(k.pushed, pushes) << c;
    EXPECT_EQ(k.pushed, k.used + k.Dropped() + k.fill) << c;
    EXPECT_EQ(k.late, tally.Count(c, PushResult::kLate)) << c;
    EXPECT_EQ(k.duplicate, tally.Count(c, PushResult::kDuplicate)) << c;
    EXPECT_EQ(k.out_of_order, tally.Count(c, PushResult::kOutOfOrder)) << c;
    EXPECT_EQ(k.stopped + k.invalid, 0u) << c;
  }
  EXPECT_EQ(s.sets_emitted, s.sets_popped + s.consumer_overflow + s.ready_fill);
  EXPECT_EQ(s.ready_fill, 0u);
  EXPECT_EQ(s.sets_emitted, s.cameras[0].used);
}

// One producer thread per camera pushing its stream. Producer c handles frame k (pushes it
// unless lost) only when every camera has handled frames 0..k-ahead-1 and, when
// ahead_of_consumer >= 0, when the consumer has popped a set of frame >= k - ahead_of_consumer.
// All producers start together. Returns false when a producer waited for over a minute.
bool RunProducers(SyncBuffer& buffer, const Streams& streams, const Consumer& consumer, int ahead,
                  int ahead_of_consumer, bool with_seq, Tally* tally) {
  std::array<std::atomic<int>, kCameras> progress{};  // frames handled per camera
  std::atomic<int> ready{0};
  std::atomic<bool> stuck{false};
  std::vector<std::thread> producers;
  for (int c = 0; c < kCameras; ++c) {
    producers.emplace_back([&, c] {
      ++ready;
      while (ready.load() < kCameras) std::this_thread::yield();
      const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
      auto may_go = [&](int k) {
        for (const auto& p : progress)
          if (p.load(std::memory_order_acquire) < k - ahead) return false;
        return ahead_of_consumer < 0 ||
               k <= consumer.last_frame.load(std::memory_order_acquire) + ahead_of_consumer;
      };
      for (int k = 0; k < kFrames && !stuck; ++k) {
        while (!may_go(k)) {
          if (std::chrono::steady_clock::now() > give_up) {
            stuck = true;
            return;
          }
          std::this_thread::yield();
        }
        if (!streams.missing[c][k]) {
          const PushResult r = buffer.Push(Entry(c, streams.t_ns[c][k], k, with_seq));
          ++tally->by_result[c][static_cast<int>(r)];  // row c: this thread only
        }
        if (k % 256 == 0) (void)buffer.stats();  // snapshots race with pushes and pops
        progress[c].store(k + 1, std::memory_order_release);
      }
    });
  }
  for (auto& t : producers) t.join();
  return !stuck;
}

// Producers run at the pace of a real rig: no camera gets more than two frames ahead of the
// slowest one, nor more than 40 frames ahead of the consumer. Then the outcome is exact: one set
// per frame that no camera lost, nothing dropped but the lost frames' partners.
TEST(SyncBufferThreads, PacedProducersAndConsumer) {
  SyncOptions o;
  o.num_cameras = kCameras;
  o.ready_capacity = 64;
  const Streams streams(o, 7);
  SyncBuffer buffer(o);
  Consumer consumer;
  std::thread consumer_thread([&] { consumer.Run(buffer); });
  Tally tally;
  const bool finished = RunProducers(buffer, streams, consumer, /*ahead=*/2,
                                     /*ahead_of_consumer=*/40, /*with_seq=*/false, &tally);
  buffer.Flush();
  buffer.Stop();
  consumer_thread.join();
  ASSERT_TRUE(finished) << "producers waited for over a minute";

  int complete = 0;
  int master_only = 0;  // master present, some slave lost
  for (int k = 0; k < kFrames; ++k) {
    complete += streams.Complete(k);
    master_only += !streams.missing[0][k] && !streams.Complete(k);
  }
  const SyncStats s = buffer.stats();
  ExpectConsistent(consumer.sets, o, /*same_frame=*/true);
  ExpectCountsAddUp(s, tally, streams);
  EXPECT_EQ(s.sets_emitted, static_cast<uint64_t>(complete)) << s.BriefReport();
  EXPECT_EQ(consumer.sets.size(), static_cast<size_t>(complete));
  EXPECT_EQ(s.consumer_overflow, 0u);
  EXPECT_EQ(s.cameras[0].never_matched, static_cast<uint64_t>(master_only));
  // A slave entry may come after the next master was already resolved (its own master lost),
  // and is then late; nothing else is dropped.
  EXPECT_EQ(s.total.duplicate + s.total.out_of_order + s.total.overflow, 0u) << s.BriefReport();
  EXPECT_EQ(s.cameras[0].late, 0u);
  for (int c = 0; c < kCameras; ++c) {
    EXPECT_EQ(tally.Count(c, PushResult::kAccepted) + s.cameras[c].late, s.cameras[c].pushed);
  }
}

// Loosely paced producers (up to 100 frames apart: rings overflow, masters time out, entries
// come late) and a consumer that cannot keep up with the small ready queue. Whatever the
// interleaving, every set is consistent and every push is accounted for.
TEST(SyncBufferThreads, LooselyPacedProducersKeepTheInvariants) {
  for (const bool by_seq : {false, true}) {
    SCOPED_TRACE(by_seq);
    SyncOptions o;
    o.num_cameras = kCameras;
    o.match_by_trigger_seq = by_seq;
    o.required = {true, true, true, false};
    o.ready_capacity = 4;
    const Streams streams(o, by_seq ? 11 : 13);
    SyncBuffer buffer(o);
    Consumer consumer;
    std::thread consumer_thread([&] { consumer.Run(buffer); });
    Tally tally;
    const bool finished = RunProducers(buffer, streams, consumer, /*ahead=*/100,
                                       /*ahead_of_consumer=*/-1, by_seq, &tally);
    buffer.Flush();
    buffer.Stop();
    consumer_thread.join();
    ASSERT_TRUE(finished);
    const SyncStats s = buffer.stats();
    ExpectConsistent(consumer.sets, o, /*same_frame=*/true);
    ExpectCountsAddUp(s, tally, streams);
    EXPECT_EQ(consumer.sets.size(), s.sets_popped);
    EXPECT_GT(s.sets_emitted, 0u) << s.BriefReport();
  }
}

}  // namespace
}  // namespace rigcal
