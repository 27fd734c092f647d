// SPDX-License-Identifier: Apache-2.0
// The 64-bit extension of the board's 32-bit µs counter (firmware/core counter_extension.h):
// started near 2^32 it crosses the wrap without a jump, as VersaVIS's did not (its issue #37),
// and NearestTime places 32-bit capture / compare values next to a 64-bit reference.
#include "rigcal/trigger_core/counter_extension.h"

#include <gtest/gtest.h>

#include <random>

namespace rigcal::trigger_core {
namespace {

constexpr uint64_t kWrap = uint64_t{1} << 32;

TEST(CounterExtension, ACounterStartedNearTheWrapCountsOnPastIt) {
  CounterExtension ext;
  const uint32_t preset = 0xFFFF'FFFFu - 2'000'000;  // 2 s before the wrap
  EXPECT_EQ(ext.Extend(preset), preset);
  // The main loop reads the counter every 997 µs (any step below 2^32 works).
  uint64_t truth = preset;
  uint64_t last = preset;
  for (int i = 0; i < 5'000; ++i) {
    truth += 997;
    const uint64_t t = ext.Extend(static_cast<uint32_t>(truth));
    ASSERT_EQ(t, truth) << "read " << i;
    ASSERT_GT(t, last);
    last = t;
  }
  EXPECT_GT(last, kWrap);
  EXPECT_EQ(ext.wraps(), 1u);
}

TEST(CounterExtension, ManyWrapsWithIrregularReads) {
  CounterExtension ext;
  std::mt19937_64 rng(7);
  uint64_t truth = 0xFFFF'0000u;
  ext.Extend(static_cast<uint32_t>(truth));
  for (int i = 0; i < 100'000; ++i) {
    truth += rng() % 0xFFFF'FFFFu + 1;  // up to one wrap between reads
    ASSERT_EQ(ext.Extend(static_cast<uint32_t>(truth)), truth);
  }
  EXPECT_GT(ext.wraps(), 40'000u);
}

TEST(CounterExtension, AReadAtExactlyTheWrapIsZero) {
  CounterExtension ext;
  ext.Extend(0xFFFF'FFFFu);
  EXPECT_EQ(ext.Extend(0), kWrap);
  EXPECT_EQ(ext.Extend(1), kWrap + 1);
}

TEST(NearestTime, PlacesLowWordsOnEitherSideOfTheReferenceAcrossTheWrap) {
  const uint64_t ref = kWrap - 10;                        // a rise 10 µs before the wrap
  EXPECT_EQ(NearestTime(ref, 5), kWrap + 5);              // a capture after the wrap
  EXPECT_EQ(NearestTime(ref, 0xFFFF'FFF0u), kWrap - 16);  // just before the reference
  EXPECT_EQ(NearestTime(3 * kWrap + 100, 50), 3 * kWrap + 50);
  EXPECT_EQ(NearestTime(5 * kWrap, 0x7FFF'FFFFu), 5 * kWrap + 0x7FFF'FFFFu);
}

}  // namespace
}  // namespace rigcal::trigger_core
