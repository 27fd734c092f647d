// SPDX-License-Identifier: Apache-2.0
// libFuzzer entry for the trigger protocol's receiving side (firmware/protocol): arbitrary bytes
// through MessageDecoder, as both the MCU (commands) and the host (reports) receive them.
// Properties checked on every input (a violation aborts, which the fuzzer reports):
//   - the decoder never reads or writes out of bounds (ASan) and accepts only whole messages;
//   - every accepted message re-encodes to a frame that decodes to the same payload;
//   - the counters add up: each 0x00 ends at most one frame, messages + errors <= delimiters.
// Built as fuzz_trigger_protocol in the ASan tree (tests/fuzz/CMakeLists.txt; ctest
// fuzz/trigger_protocol, label fuzz), seeds in firmware/tests/fuzz_corpus/.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "rigcal/trigger_protocol/frame_codec.h"

namespace proto = rigcal::trigger_protocol;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  proto::MessageDecoder decoder;
  uint32_t delimiters = 0;
  for (size_t i = 0; i < size; ++i) {
    delimiters += data[i] == 0;
    if (decoder.Push(data[i]) != proto::DecodeEvent::kMessage) continue;
    const proto::Message& m = decoder.message();
    uint8_t frame[proto::kMaxFrameSize];
    const size_t n = proto::EncodeFrame(m, frame, sizeof(frame));
    if (n == 0 || frame[n - 1] != 0) std::abort();
    proto::MessageDecoder again;
    int accepted = 0;
    for (size_t j = 0; j < n; ++j) {
      if (again.Push(frame[j]) == proto::DecodeEvent::kMessage) {
        ++accepted;
        uint8_t a[proto::kMaxPayloadSize], b[proto::kMaxPayloadSize];
        const size_t na = proto::EncodePayload(m, a, sizeof(a));
        const size_t nb = proto::EncodePayload(again.message(), b, sizeof(b));
        if (na != nb || std::memcmp(a, b, na) != 0) std::abort();
      }
    }
    if (accepted != 1) std::abort();
  }
  const proto::DecoderStats& s = decoder.stats();
  if (s.messages + s.Errors() > delimiters) std::abort();
  return 0;
}
