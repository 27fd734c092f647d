// SPDX-License-Identifier: Apache-2.0
// `rigcal trigger --hello`'s query (drivers trigger_hello.h) against scripted peers: a version-2
// generator answers with its Hello and clock status; a generator built for protocol version 1 is
// named as such instead of timing out silently; DescribeClockStatus says what each bit means.
#include "rigcal/trigger/trigger_hello.h"

#include <gtest/gtest.h>

#include <deque>
#include <memory>
#include <vector>

namespace rigcal::trigger {
namespace {

namespace proto = ::rigcal::trigger_protocol;

std::vector<uint8_t> Frame(const proto::Message& m) {
  std::vector<uint8_t> f(proto::kMaxFrameSize);
  f.resize(proto::EncodeFrame(m, f.data(), f.size()));
  return f;
}
// A frame of another version (CRC valid): what an older firmware sends.
std::vector<uint8_t> RawFrame(std::vector<uint8_t> payload) {
  const uint16_t crc = proto::Crc16(payload.data(), payload.size());
  payload.push_back(static_cast<uint8_t>(crc & 0xFF));
  payload.push_back(static_cast<uint8_t>(crc >> 8));
  std::vector<uint8_t> out(proto::CobsEncodedSize(payload.size()) + 1);
  out.resize(proto::CobsEncode(payload.data(), payload.size(), out.data(), out.size()));
  out.push_back(0);
  return out;
}

// Answers every frame written to it with `answer(command)`; simulated time 1 ms per read.
class ScriptedPeer final : public ByteStream {
 public:
  explicit ScriptedPeer(int version) : version_(version) {}
  Expected<size_t> Read(uint8_t* data, size_t size, int timeout_ms) override {
    now_ns_ += (pending_.empty() ? timeout_ms : 1) * 1'000'000ll;
    size_t n = 0;
    while (n < size && !pending_.empty()) {
      data[n++] = pending_.front();
      pending_.pop_front();
    }
    return n;
  }
  Status Write(const uint8_t* data, size_t size) override {
    for (size_t i = 0; i < size; ++i) {
      if (decoder_.Push(data[i]) != proto::DecodeEvent::kMessage) continue;
      const uint16_t id = decoder_.message().simple.command_id;
      if (version_ == 1) {  // its Nack of the unknown version, in version 1's framing
        Append(RawFrame(
            {1, 0x05, static_cast<uint8_t>(id), static_cast<uint8_t>(id >> 8), 0x15, 1, 0}));
        continue;
      }
      proto::Message ack;
      ack.type = proto::MessageType::kAck;
      ack.ack = {id, proto::MessageType::kGetInfo};
      Append(Frame(ack));
      proto::Message hello;
      hello.type = proto::MessageType::kHello;
      hello.hello = {2, 8, 12'345'678, proto::kClockHseFallback, 25};
      Append(Frame(hello));
    }
    return Status::Ok();
  }
  int64_t NowNs() const override { return now_ns_; }

 private:
  void Append(const std::vector<uint8_t>& bytes) {
    pending_.insert(pending_.end(), bytes.begin(), bytes.end());
  }
  int version_;
  proto::MessageDecoder decoder_;
  std::deque<uint8_t> pending_;
  int64_t now_ns_ = 0;
};

TEST(TriggerHello, AVersionTwoGeneratorAnswersWithItsClockStatus) {
  TriggerLink link(std::make_unique<ScriptedPeer>(2));
  const Expected<TriggerHelloInfo> info = QueryTriggerHello(&link, 500);
  ASSERT_TRUE(info.ok()) << info.error();
  EXPECT_EQ(info->hello.mcu_time_us, 12'345'678u);
  EXPECT_EQ(info->hello.clock_status, proto::kClockHseFallback);
  EXPECT_EQ(info->hello.hse_mhz, 25);
}

TEST(TriggerHello, AVersionOneGeneratorIsNamed) {
  TriggerLink link(std::make_unique<ScriptedPeer>(1));
  const Expected<TriggerHelloInfo> info = QueryTriggerHello(&link, 200);
  ASSERT_FALSE(info.ok());
  EXPECT_NE(info.error().find("protocol version 1, this host version 2"), std::string::npos)
      << info.error();
}

TEST(TriggerHello, ClockStatusInWords) {
  EXPECT_EQ(DescribeClockStatus(0, 8), "crystal 8 MHz -> PLL 168 MHz, timers as configured");
  const std::string fallback = DescribeClockStatus(proto::kClockHseFallback, 25);
  EXPECT_NE(fallback.find("HSE (25 MHz crystal) did not start"), std::string::npos) << fallback;
  EXPECT_NE(fallback.find("+-1 %"), std::string::npos);
  const std::string qemu = DescribeClockStatus(0x07, 8);
  EXPECT_NE(qemu.find("PLL not locked"), std::string::npos) << qemu;
  EXPECT_NE(qemu.find("prescaler from its measurement"), std::string::npos) << qemu;
  EXPECT_NE(DescribeClockStatus(proto::kClockTestImage, 8).find("TEST IMAGE"), std::string::npos);
}

}  // namespace
}  // namespace rigcal::trigger
