// SPDX-License-Identifier: Apache-2.0
// The trigger protocol (firmware/protocol): CRC, COBS, every message round trip, and the
// decoder's behaviour on corrupted, truncated, oversized and misaligned streams.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "rigcal/trigger_protocol/frame_codec.h"

namespace rigcal::trigger_protocol {
namespace {

std::vector<uint8_t> Frame(const Message& m) {
  std::vector<uint8_t> out(kMaxFrameSize);
  out.resize(EncodeFrame(m, out.data(), out.size()));
  return out;
}

std::vector<Message> Decode(MessageDecoder* decoder, const std::vector<uint8_t>& bytes,
                            std::vector<DecodeEvent>* errors = nullptr) {
  std::vector<Message> out;
  for (uint8_t b : bytes) {
    const DecodeEvent e = decoder->Push(b);
    if (e == DecodeEvent::kMessage) {
      out.push_back(decoder->message());
    } else if (e != DecodeEvent::kNone && errors != nullptr) {
      errors->push_back(e);
    }
  }
  return out;
}

Message Pulse(uint32_t seq, uint64_t t_us, uint8_t mask = 0x5) {
  Message m;
  m.type = MessageType::kPulseReport;
  m.pulse.line_mask = mask;
  m.pulse.seq = seq;
  m.pulse.mcu_time_us = t_us;
  return m;
}

// One message of every type, with fields that exercise every byte (and zero bytes for COBS).
std::vector<Message> AllTypes() {
  std::vector<Message> all;
  Message m;
  m.type = MessageType::kHello;
  m.hello = {0x0102, 8, 0x0000'00FF'0000'1234ull, kClockHseFallback | kClockTestImage, 25};
  all.push_back(m);
  m = Message{};
  m.type = MessageType::kExposureReport;
  m.exposure = {0xCAFE'0001, 7, 0x0000'0001'0000'0010ull, 0x00FF'00FF};
  all.push_back(m);
  all.push_back(Pulse(0xDEADBEEF, 0x0102'0304'0506'0708ull, 0xFF));
  m = Message{};
  m.type = MessageType::kHeartbeat;
  m.heartbeat = {123'456'789ull, 77, 1, 3, 0xFFFF, 0, 9};
  all.push_back(m);
  m = Message{};
  m.type = MessageType::kAck;
  m.ack = {0xABCD, MessageType::kSetLine};
  all.push_back(m);
  m = Message{};
  m.type = MessageType::kNack;
  m.nack = {7, 0x11, NackReason::kOutOfRange, Field::kWidth};
  all.push_back(m);
  m = Message{};
  m.type = MessageType::kSetRate;
  m.set_rate = {9, 30'000};
  all.push_back(m);
  m = Message{};
  m.type = MessageType::kSetLine;
  m.set_line = {10, 7, 1, 500, -1234, 8000, ExposureInput::kActiveLow};
  all.push_back(m);
  m = Message{};
  m.type = MessageType::kSetHeartbeat;
  m.set_heartbeat = {11, 250};
  all.push_back(m);
  for (MessageType t : {MessageType::kStart, MessageType::kStop, MessageType::kGetInfo}) {
    m = Message{};
    m.type = t;
    m.simple.command_id = 12;
    all.push_back(m);
  }
  return all;
}

// Field-wise equality of the member `type` selects.
bool SameMessage(const Message& a, const Message& b) {
  if (a.type != b.type) return false;
  std::vector<uint8_t> pa(kMaxPayloadSize), pb(kMaxPayloadSize);
  const size_t na = EncodePayload(a, pa.data(), pa.size());
  const size_t nb = EncodePayload(b, pb.data(), pb.size());
  return na == nb && na > 0 && std::memcmp(pa.data(), pb.data(), na) == 0;
}

// Frames whose CRC is valid but whose payload is refused, as a buggy or newer peer would send.
std::vector<uint8_t> RawFrame(std::vector<uint8_t> payload) {
  const uint16_t crc = Crc16(payload.data(), payload.size());
  payload.push_back(static_cast<uint8_t>(crc & 0xFF));
  payload.push_back(static_cast<uint8_t>(crc >> 8));
  std::vector<uint8_t> out(CobsEncodedSize(payload.size()) + 1);
  const size_t n = CobsEncode(payload.data(), payload.size(), out.data(), out.size());
  out.resize(n);
  out.push_back(0);
  return out;
}

TEST(Crc16, CheckValueOfTheStandard) {
  const char* text = "123456789";
  EXPECT_EQ(Crc16(reinterpret_cast<const uint8_t*>(text), 9), 0x29B1);
  EXPECT_EQ(Crc16(nullptr, 0), kCrc16Initial);
}

TEST(Cobs, RoundTripOfZerosRunsAndLongBlocks) {
  std::mt19937 rng(1);
  for (size_t size : {0u, 1u, 2u, 253u, 254u, 255u, 508u, 600u}) {
    for (int variant = 0; variant < 3; ++variant) {
      std::vector<uint8_t> in(size);
      for (uint8_t& b : in) {
        b = variant == 0   ? 0
            : variant == 1 ? static_cast<uint8_t>(1 + rng() % 255)
                           : static_cast<uint8_t>(rng() % 4 == 0 ? 0 : rng());
      }
      std::vector<uint8_t> enc(CobsEncodedSize(size));
      const size_t n = CobsEncode(in.data(), in.size(), enc.data(), enc.size());
      ASSERT_GT(n, 0u);
      ASSERT_LE(n, CobsEncodedSize(size));
      for (size_t i = 0; i < n; ++i) ASSERT_NE(enc[i], 0) << "size " << size << " byte " << i;
      std::vector<uint8_t> dec(size + 1);
      const long m = CobsDecode(enc.data(), n, dec.data(), dec.size());
      ASSERT_EQ(m, static_cast<long>(size)) << "size " << size << " variant " << variant;
      dec.resize(size);
      EXPECT_EQ(dec, in);
    }
  }
}

TEST(Cobs, RejectsZeroBytesOverrunsAndSmallOutputs) {
  const uint8_t zero_inside[] = {3, 1, 0};
  uint8_t out[8];
  EXPECT_EQ(CobsDecode(zero_inside, 3, out, sizeof(out)), -1);
  const uint8_t overrun[] = {5, 1, 2};  // block claims 4 bytes, 2 present
  EXPECT_EQ(CobsDecode(overrun, 3, out, sizeof(out)), -1);
  const uint8_t fine[] = {3, 1, 2, 2, 3};  // 1 2 0 3
  EXPECT_EQ(CobsDecode(fine, 5, out, 3), -1);
  EXPECT_EQ(CobsDecode(fine, 5, out, 4), 4);
  const uint8_t in[] = {1, 2, 3};
  EXPECT_EQ(CobsEncode(in, 3, out, 3), 0u);  // needs 4
}

TEST(Messages, EveryTypeRoundTripsThroughAFrame) {
  MessageDecoder decoder;
  for (const Message& m : AllTypes()) {
    const std::vector<uint8_t> frame = Frame(m);
    ASSERT_FALSE(frame.empty()) << static_cast<int>(m.type);
    ASSERT_LE(frame.size(), kMaxFrameSize);
    EXPECT_EQ(frame.back(), 0);
    for (size_t i = 0; i + 1 < frame.size(); ++i) ASSERT_NE(frame[i], 0);
    const std::vector<Message> got = Decode(&decoder, frame);
    ASSERT_EQ(got.size(), 1u) << static_cast<int>(m.type);
    EXPECT_TRUE(SameMessage(got[0], m)) << static_cast<int>(m.type);
  }
  EXPECT_EQ(decoder.stats().messages, AllTypes().size());
  EXPECT_EQ(decoder.stats().Errors(), 0u);
}

TEST(Messages, FieldsAreLittleEndianAtFixedOffsets) {
  uint8_t p[kMaxPayloadSize];
  const size_t n = EncodePayload(Pulse(0x04030201, 0x0C0B0A0908070605ull, 0x81), p, sizeof(p));
  ASSERT_EQ(n, 15u);
  const uint8_t want[] = {kProtocolVersion, 0x02, 0x81, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12};
  EXPECT_EQ(std::memcmp(p, want, n), 0);
  Message m;
  m.type = MessageType::kSetLine;
  m.set_line.phase_offset_us = -2;
  m.set_line.exposure_input = ExposureInput::kActiveLow;
  ASSERT_EQ(EncodePayload(m, p, sizeof(p)), 19u);
  EXPECT_EQ(p[10], 0xFE);  // after version, type, id, line, enabled, width: LE two's complement
  EXPECT_EQ(p[13], 0xFF);
  EXPECT_EQ(p[18], 2);  // version 2: exposure_input after the exposure
  // Version 2's Hello: version 1's fields, then clock_status and hse_mhz.
  m = Message{};
  m.type = MessageType::kHello;
  m.hello = {0x0201, 8, 0x0807060504030201ull, kClockPllFailed | kClockTimerMeasured, 8};
  ASSERT_EQ(EncodePayload(m, p, sizeof(p)), 15u);
  const uint8_t hello[] = {2, 0x01, 0x01, 0x02, 8, 1, 2, 3, 4, 5, 6, 7, 8, 0x06, 8};
  EXPECT_EQ(std::memcmp(p, hello, sizeof(hello)), 0);
  m = Message{};
  m.type = MessageType::kExposureReport;
  m.exposure = {0x04030201, 3, 0x0D0C0B0A09080706ull, 0x11100F0E};
  ASSERT_EQ(EncodePayload(m, p, sizeof(p)), 19u);
  const uint8_t exposure[] = {2, 0x06, 1, 2, 3, 4, 3, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 16, 17};
  EXPECT_EQ(std::memcmp(p, exposure, sizeof(exposure)), 0);
  EXPECT_EQ(m.exposure.CentreUs(), 0x0D0C0B0A09080706ull + 0x11100F0E / 2);
}

TEST(Messages, AVersionOneFirmwareIsRecognisedAsSuch) {
  // A version 1 firmware's Hello (11-byte body) as it boots: refused, with its version known,
  // so the host can say which side to update.
  MessageDecoder decoder;
  std::vector<DecodeEvent> errors;
  const std::vector<Message> got =
      Decode(&decoder, RawFrame({1, 0x01, 1, 0, 8, 0x10, 0x27, 0, 0, 0, 0, 0, 0}), &errors);
  EXPECT_TRUE(got.empty());
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0], DecodeEvent::kUnsupportedVersion);
  EXPECT_EQ(decoder.raw_version(), 1);
  EXPECT_EQ(decoder.raw_type(), 0x01);
}

TEST(Messages, RejectsOtherVersionsUnknownTypesAndWrongLengths) {
  uint8_t p[kMaxPayloadSize];
  Message m;
  m.type = MessageType::kSetRate;
  m.set_rate = {0x2211, 5000};
  const size_t n = EncodePayload(m, p, sizeof(p));
  Message out;
  uint16_t id = 0;
  EXPECT_EQ(ParsePayload(p, n, &out, &id), ParseStatus::kOk);
  EXPECT_EQ(out.set_rate.rate_mhz, 5000u);
  EXPECT_EQ(ParsePayload(p, 1, &out), ParseStatus::kTooShort);
  EXPECT_EQ(ParsePayload(p, n - 1, &out, &id), ParseStatus::kBadLength);
  EXPECT_EQ(id, 0x2211);  // the id is still known for the Nack
  p[0] = kProtocolVersion + 1;
  EXPECT_EQ(ParsePayload(p, n, &out), ParseStatus::kUnsupportedVersion);
  p[0] = kProtocolVersion;
  p[1] = 0x7F;
  EXPECT_EQ(ParsePayload(p, n, &out), ParseStatus::kUnknownType);
}

TEST(Decoder, ReportsRejectedFramesWithTheirTypeAndCommandId) {
  MessageDecoder decoder;
  std::vector<DecodeEvent> errors;
  Decode(&decoder, RawFrame({3, 0x10, 0x34, 0x12, 0, 0, 0, 0}), &errors);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0], DecodeEvent::kUnsupportedVersion);
  EXPECT_EQ(decoder.command_id(), 0x1234);
  EXPECT_EQ(decoder.raw_version(), 3);
  errors.clear();
  Decode(&decoder, RawFrame({kProtocolVersion, 0x10, 0x35, 0x12, 1}), &errors);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0], DecodeEvent::kBadLength);
  EXPECT_EQ(decoder.raw_type(), 0x10);
  EXPECT_EQ(decoder.command_id(), 0x1235);
  errors.clear();
  Decode(&decoder, RawFrame({kProtocolVersion, 0x66, 1, 0}), &errors);
  ASSERT_EQ(errors.size(), 1u);
  EXPECT_EQ(errors[0], DecodeEvent::kUnknownType);
  EXPECT_EQ(decoder.stats().rejected, 3u);
}

TEST(Decoder, EveryFlippedBitIsDetectedAndResyncIsImmediate) {
  // A single bit error in a frame is always detected: either the COBS structure breaks, a new
  // delimiter splits the frame (each part fails its framing or CRC), or the CRC fails
  // (CRC-16/CCITT detects every single-bit error). The next frame still arrives, except when
  // the flipped bit is in the delimiter itself: then the frame runs into the next one and both
  // are lost, and the one after arrives.
  const std::vector<uint8_t> good = Frame(Pulse(42, 1'000'000));
  const std::vector<uint8_t> next = Frame(Pulse(43, 1'050'000));
  const std::vector<uint8_t> third = Frame(Pulse(44, 1'100'000));
  for (size_t byte = 0; byte < good.size(); ++byte) {
    for (int bit = 0; bit < 8; ++bit) {
      std::vector<uint8_t> stream = good;
      stream[byte] ^= static_cast<uint8_t>(1u << bit);
      stream.insert(stream.end(), next.begin(), next.end());
      stream.insert(stream.end(), third.begin(), third.end());
      MessageDecoder decoder;
      std::vector<DecodeEvent> errors;
      std::vector<uint32_t> seqs;
      for (const Message& m : Decode(&decoder, stream, &errors)) {
        ASSERT_EQ(m.type, MessageType::kPulseReport);
        seqs.push_back(m.pulse.seq);
      }
      const bool delimiter = byte + 1 == good.size();
      const std::vector<uint32_t> want =
          delimiter ? std::vector<uint32_t>{44} : std::vector<uint32_t>{43, 44};
      EXPECT_EQ(seqs, want) << "byte " << byte << " bit " << bit;
      EXPECT_FALSE(errors.empty()) << "byte " << byte << " bit " << bit;
    }
  }
}

TEST(Decoder, ResynchronisesAfterGarbageTruncationAndOverlongFrames) {
  std::mt19937 rng(7);
  std::vector<uint8_t> stream;
  std::vector<uint32_t> sent_intact;
  uint32_t seq = 0;
  int damaged = 0;
  for (int i = 0; i < 2000; ++i, ++seq) {
    std::vector<uint8_t> f = Frame(Pulse(seq, 1000ull * seq));
    switch (rng() % 10) {
      case 0:  // truncated: the delimiter is lost, the frame runs into the next one
        f.resize(rng() % (f.size() - 1));
        ++damaged;
        break;
      case 1:  // random garbage before the frame, ending in a delimiter
        for (int k = 0, n = 1 + static_cast<int>(rng() % 40); k < n; ++k) {
          stream.push_back(static_cast<uint8_t>(rng()));
        }
        stream.push_back(0);
        sent_intact.push_back(seq);
        break;
      case 2:  // a long run without a delimiter (an overflow), then the frame
        stream.insert(stream.end(), 3 * kMaxFrameSize, 0x55);
        stream.push_back(0);
        sent_intact.push_back(seq);
        break;
      default:
        sent_intact.push_back(seq);
    }
    stream.insert(stream.end(), f.begin(), f.end());
  }
  MessageDecoder decoder;
  std::vector<DecodeEvent> errors;
  const std::vector<Message> got = Decode(&decoder, stream, &errors);
  // Every received message is one that was sent whole, in order, with its content intact; a
  // truncated frame costs itself and the frame it runs into, nothing else.
  std::vector<uint32_t> got_seq;
  for (const Message& m : got) {
    ASSERT_EQ(m.type, MessageType::kPulseReport);
    ASSERT_EQ(m.pulse.mcu_time_us, 1000ull * m.pulse.seq);
    got_seq.push_back(m.pulse.seq);
  }
  size_t j = 0;
  for (uint32_t s : got_seq) {
    while (j < sent_intact.size() && sent_intact[j] != s) ++j;
    ASSERT_LT(j, sent_intact.size()) << "seq " << s << " received but not sent intact";
  }
  EXPECT_GE(got.size(), sent_intact.size() - static_cast<size_t>(damaged));
  EXPECT_GT(decoder.stats().overflows, 0u);
  EXPECT_GT(decoder.stats().crc_errors + decoder.stats().framing_errors, 0u);
  EXPECT_EQ(decoder.stats().messages, got.size());
}

TEST(Decoder, SurvivesRandomBytesWithoutAcceptingAnything) {
  // Random bytes (a fixed seed): a false accept needs valid COBS, a length matching a type and a
  // 16-bit CRC match; over these ~20000 random frames the expected number is well below one.
  std::mt19937 rng(3);
  MessageDecoder decoder;
  int accepted = 0;
  for (int i = 0; i < 400'000; ++i) {
    const uint8_t b = (rng() % 20 == 0) ? 0 : static_cast<uint8_t>(rng());
    if (decoder.Push(b) == DecodeEvent::kMessage) ++accepted;
  }
  EXPECT_EQ(accepted, 0);
}

// The fuzzer's seeds (firmware/tests/fuzz_corpus/) speak the current version: each decodes to
// what its name says, so a version change cannot leave the fuzzer starting from rejected frames.
TEST(FuzzCorpus, SeedsDecodeAsTheirNamesSay) {
  const std::filesystem::path dir =
      std::filesystem::path(RIGCAL_FIRMWARE_DIR) / "tests/fuzz_corpus";
  struct Want {
    std::vector<MessageType> messages;
    DecodeEvent error = DecodeEvent::kNone;
  };
  const std::map<std::string, Want> seeds = {
      {"hello", {{MessageType::kHello}}},
      {"pulse_report", {{MessageType::kPulseReport}}},
      {"exposure_report", {{MessageType::kExposureReport}}},
      {"heartbeat", {{MessageType::kHeartbeat}}},
      {"ack_nack", {{MessageType::kAck, MessageType::kNack}}},
      {"set_line", {{MessageType::kSetLine}}},
      {"commands",
       {{MessageType::kSetRate, MessageType::kSetHeartbeat, MessageType::kStart, MessageType::kStop,
         MessageType::kGetInfo}}},
      {"bad_crc", {{}, DecodeEvent::kCrcError}},
      {"bad_version", {{}, DecodeEvent::kUnsupportedVersion}},
      {"garbage_then_frame", {{MessageType::kPulseReport}, DecodeEvent::kFramingError}},
  };
  size_t files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    ++files;
    const std::string name = entry.path().filename().string();
    ASSERT_TRUE(seeds.count(name)) << "seed without an expectation: " << name;
    std::ifstream in(entry.path(), std::ios::binary);
    const std::vector<uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                     std::istreambuf_iterator<char>());
    MessageDecoder decoder;
    std::vector<DecodeEvent> errors;
    std::vector<MessageType> types;
    for (const Message& m : Decode(&decoder, bytes, &errors)) types.push_back(m.type);
    const Want& want = seeds.at(name);
    EXPECT_EQ(types, want.messages) << name;
    if (want.error == DecodeEvent::kNone) {
      EXPECT_TRUE(errors.empty()) << name;
    } else {
      ASSERT_FALSE(errors.empty()) << name;
      EXPECT_EQ(errors.front(), want.error) << name;
    }
  }
  EXPECT_EQ(files, seeds.size());
}

}  // namespace
}  // namespace rigcal::trigger_protocol
