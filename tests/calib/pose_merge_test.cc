// SPDX-License-Identifier: Apache-2.0
// PoseMerge forwards the poses of several VO threads in one canonical order, (frame stamp,
// camera), whatever the thread timing, holds nothing back once every camera has ended, and
// keeps the threads within the lead.
#include "rigcal/calib/pose_merge.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <random>
#include <thread>

namespace rigcal {
namespace {

constexpr int64_t kPeriodNs = 50'000'000;

struct Forwarded {
  int64_t frame_t_ns;
  int camera;
  int64_t t_ns;
};

// Camera c delivers frames 0..frames[c]-1 (stamp k * period + c ns of jitter); every frame
// gives one pose, and every 7th frame also an earlier pose (a segment start, stamped 3 frames
// back). Threads sleep at random to interleave differently in every run.
std::vector<Forwarded> RunCameras(const std::vector<int>& frames, uint64_t seed, int64_t lead_ns,
                                  int64_t* max_spread_ns) {
  std::vector<Forwarded> out;
  std::mutex progress_mutex;
  std::vector<int64_t> progress(frames.size(), -1);
  std::vector<bool> ended(frames.size(), false);
  std::atomic<int64_t> spread{0};
  PoseMerge merge(static_cast<int>(frames.size()), lead_ns, [&](const CameraPose& pose) {
    out.push_back({pose.trigger_seq, pose.camera, pose.t_ns});  // under the merge's lock
  });
  std::vector<std::thread> threads;
  for (size_t c = 0; c < frames.size(); ++c) {
    threads.emplace_back([&, c] {
      std::mt19937_64 rng(seed * 31 + c);
      std::uniform_int_distribution<int> sleep_us(0, 300);
      for (int k = 0; k < frames[c]; ++k) {
        std::this_thread::sleep_for(std::chrono::microseconds(sleep_us(rng)));
        const int64_t t = k * kPeriodNs + static_cast<int64_t>(c);
        {
          // Spread of the frames being worked on: the lead is what bounds it.
          std::lock_guard<std::mutex> lock(progress_mutex);
          progress[c] = t;
          int64_t lo = INT64_MAX, hi = INT64_MIN;
          for (size_t j = 0; j < progress.size(); ++j) {
            if (progress[j] < 0 || ended[j]) continue;
            lo = std::min(lo, progress[j]);
            hi = std::max(hi, progress[j]);
          }
          if (hi > lo) spread = std::max(spread.load(), hi - lo);
        }
        std::vector<CameraPose> poses;
        if (k % 7 == 6) {
          CameraPose start;
          start.camera = static_cast<int>(c);
          start.t_ns = t - 3 * kPeriodNs;
          start.trigger_seq = t;
          poses.push_back(start);
        }
        CameraPose pose;
        pose.camera = static_cast<int>(c);
        pose.t_ns = t;
        pose.trigger_seq = t;  // the frame stamp, to check the order
        poses.push_back(pose);
        merge.Deliver(static_cast<int>(c), t, std::move(poses));
      }
      {
        std::lock_guard<std::mutex> lock(progress_mutex);
        ended[c] = true;
      }
      merge.End(static_cast<int>(c));
    });
  }
  for (auto& t : threads) t.join();
  if (max_spread_ns != nullptr) *max_spread_ns = spread.load();
  return out;
}

TEST(PoseMerge, OrderIsCanonicalAndIndependentOfThreadTiming) {
  const std::vector<int> frames = {60, 60, 45, 60};  // camera 2 ends early (a dead camera)
  int64_t spread = 0;
  const std::vector<Forwarded> first = RunCameras(frames, 1, kPeriodNs, &spread);
  size_t expected = 0;
  for (int n : frames) expected += static_cast<size_t>(n + n / 7);
  ASSERT_EQ(first.size(), expected);
  for (size_t i = 1; i < first.size(); ++i) {
    const bool ordered =
        first[i - 1].frame_t_ns < first[i].frame_t_ns ||
        (first[i - 1].frame_t_ns == first[i].frame_t_ns && first[i - 1].camera <= first[i].camera);
    ASSERT_TRUE(ordered) << "at " << i;
  }
  for (uint64_t seed = 2; seed < 5; ++seed) {
    const std::vector<Forwarded> again = RunCameras(frames, seed, kPeriodNs, nullptr);
    ASSERT_EQ(again.size(), first.size());
    for (size_t i = 0; i < first.size(); ++i) {
      ASSERT_EQ(again[i].camera, first[i].camera) << "seed " << seed << " at " << i;
      ASSERT_EQ(again[i].t_ns, first[i].t_ns) << "seed " << seed << " at " << i;
    }
  }
}

TEST(PoseMerge, ThreadsStayWithinTheLead) {
  int64_t spread = 0;
  RunCameras({80, 80, 80}, 7, kPeriodNs, &spread);
  // A thread waits once it is more than one lead ahead; it may then be one frame further
  // (the frame it has just taken) before the check: lead + period + jitter.
  EXPECT_LE(spread, kPeriodNs + kPeriodNs + 3);
}

TEST(PoseMerge, StopReleasesAWaitingCamera) {
  std::vector<CameraPose> out;
  PoseMerge merge(2, kPeriodNs, [&](const CameraPose& pose) { out.push_back(pose); });
  std::thread ahead([&] {
    CameraPose pose;
    pose.camera = 0;
    pose.t_ns = 10 * kPeriodNs;
    merge.Deliver(0, pose.t_ns, {pose});  // camera 1 never delivers: waits until Stop
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  EXPECT_TRUE(out.empty());  // held: camera 1 could still deliver an earlier frame
  merge.Stop();
  ahead.join();
  merge.End(1);  // camera 1 ends: nothing waits for it any more
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0].t_ns, 10 * kPeriodNs);
}

}  // namespace
}  // namespace rigcal
