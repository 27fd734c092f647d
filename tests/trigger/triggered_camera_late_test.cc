// SPDX-License-Identifier: Apache-2.0
// Why a TriggeredCamera frame has no pulse: a frame whose pulse report has not arrived within the
// camera's wait (a busy host or a slow link) counts as a late report; a frame between two known
// pulses (a spurious frame) does not. Both are unmatched; a matched frame is neither.
#include <gtest/gtest.h>

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "rigcal/trigger/trigger_timeline.h"
#include "rigcal/trigger/triggered_camera.h"

namespace rigcal::trigger {
namespace {

namespace proto = ::rigcal::trigger_protocol;

constexpr int64_t kBootNs = 5'000'000'000;  // host time of MCU time 0
constexpr int64_t kDelayNs = 40'000;        // every message arrives 40 µs after it was sent
constexpr uint64_t kPeriodUs = 50'000;      // 20 Hz

int64_t HostNs(uint64_t mcu_us) { return kBootNs + static_cast<int64_t>(mcu_us) * 1000; }
uint64_t TickUs(uint32_t k) { return kPeriodUs * (k + 1); }

// A timeline whose messages the test has delivered already.
class FedTimeline final : public TriggerTimeline {
 public:
  explicit FedTimeline(int pulses) {
    TriggerMatcherOptions o;
    o.clock.min_samples = 2;
    matcher_ = std::make_unique<TriggerMatcher>(o);
    for (int k = 0; k < pulses; ++k) {
      proto::Message m;
      m.type = proto::MessageType::kPulseReport;
      m.pulse = {0x01, static_cast<uint32_t>(k), TickUs(k)};
      matcher_->OnMessage(m, HostNs(TickUs(k)) + kDelayNs);
    }
  }
  void AdvanceTo(int64_t /*t_ns*/) override {}
  const TriggerMatcher& matcher() const override { return *matcher_; }

 private:
  std::unique_ptr<TriggerMatcher> matcher_;
};

// A camera whose frames carry the given stamps.
class StampedFrames final : public capture::CameraDevice {
 public:
  explicit StampedFrames(std::vector<int64_t> stamps_ns) : stamps_ns_(std::move(stamps_ns)) {}
  const std::string& name() const override { return name_; }
  double frame_rate_hz() const override { return 20.0; }
  Expected<std::optional<capture::Frame>> Grab() override {
    if (next_ >= stamps_ns_.size()) return std::optional<capture::Frame>();
    capture::Frame frame;
    frame.t_ns = stamps_ns_[next_++];
    return std::optional<capture::Frame>(std::move(frame));
  }
  void Interrupt() override {}

 private:
  std::string name_ = "cam0";
  std::vector<int64_t> stamps_ns_;
  size_t next_ = 0;
};

TEST(TriggeredCameraLate, AReportNotYetArrivedIsLateAFrameBetweenPulsesIsNot) {
  constexpr int kPulses = 20;
  auto timeline = std::make_shared<FedTimeline>(kPulses);
  const std::vector<int64_t> stamps = {
      HostNs(TickUs(10)) + 300'000,        // pulse 10, 0.3 ms off: matched
      HostNs(TickUs(10) + kPeriodUs / 2),  // half-way to pulse 11: no pulse, not late
      HostNs(TickUs(kPulses + 5)),         // a pulse not reported yet: late
  };
  constexpr int64_t kWaitNs = 20'000'000;
  TriggeredCamera camera(std::make_unique<StampedFrames>(stamps), timeline,
                         CameraTriggerSpec{0, 0, 0}, kWaitNs);
  std::vector<int64_t> seqs;
  for (size_t i = 0; i < stamps.size(); ++i) {
    Expected<std::optional<capture::Frame>> frame = camera.Grab();
    ASSERT_TRUE(frame.ok()) << frame.error();
    ASSERT_TRUE(frame->has_value());
    seqs.push_back((*frame)->seq);
  }
  EXPECT_EQ(seqs, (std::vector<int64_t>{10, -1, -1}));
  EXPECT_EQ(camera.matched(), 1);
  EXPECT_EQ(camera.unmatched(), 2);
  EXPECT_EQ(camera.late_reports(), 1);
  EXPECT_EQ(camera.wait_ns(), kWaitNs);
}

}  // namespace
}  // namespace rigcal::trigger
