// SPDX-License-Identifier: Apache-2.0
// The validator's checks of a received buffer, on every message type: wrong type and schema
// version, truncated, oversize and malformed buffers, and its counters by cause.
#include "rigcal/lcm/message_validation.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <climits>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "lcm/message_fixtures.h"
#include "rigcal/lcm/channels.h"

namespace rigcal::lcm::lcm_test {
namespace {

TEST(LcmValidation, WrongType) {
  MessageValidator validator(kNames);
  ExpectRejected<rig_extrinsics_t>(&validator, kExtrinsicsChannel, Encode("X", MakePoseMsg()),
                                   RejectCause::kWrongType,
                                   {"rig_extrinsics_t.fingerprint", "does not hold"});
  ExpectRejected<camera_pose_t>(&validator, PoseChannel("back"), Encode("X", MakeImageMsg()),
                                RejectCause::kWrongType, {"camera_pose_t.fingerprint"});
}

TEST(LcmValidation, WrongVersion) {
  MessageValidator validator(kNames);
  camera_pose_t pose = MakePoseMsg();
  pose.version = camera_pose_t::VERSION + 1;
  ExpectRejected<camera_pose_t>(&validator, "RIGCAL_POSE_left", RawEncode(pose),
                                RejectCause::kWrongVersion,
                                {"camera_pose_t.version", "schema version 2"});
  rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  extrinsics.version = 0;
  ExpectRejected<rig_extrinsics_t>(&validator, kExtrinsicsChannel, RawEncode(extrinsics),
                                   RejectCause::kWrongVersion, {"rig_extrinsics_t.version"});
  rig_status_t status = MakeStatusMsg();
  status.version = -1;
  ExpectRejected<rig_status_t>(&validator, kStatusChannel, RawEncode(status),
                               RejectCause::kWrongVersion, {"rig_status_t.version"});
  image_t image = MakeImageMsg();
  image.version = 7;
  ExpectRejected<image_t>(&validator, "RIGCAL_IMAGE_back", RawEncode(image),
                          RejectCause::kWrongVersion, {"image_t.version"});
  // EncodeMessage refuses to produce it.
  Expected<std::vector<uint8_t>> encoded = EncodeMessage("RIGCAL_POSE_left", kNames, pose);
  ASSERT_FALSE(encoded.ok());
  EXPECT_THAT(encoded.error(), HasSubstr("(wrong_version)"));
  EXPECT_EQ(validator.stats().Rejected(RejectCause::kWrongVersion), 4);
}

TEST(LcmValidation, Truncated) {
  MessageValidator validator(kNames);
  const auto chop = [](std::vector<uint8_t> buffer, size_t bytes) {
    buffer.resize(buffer.size() - bytes);
    return buffer;
  };
  ExpectRejected<camera_pose_t>(&validator, "P", chop(Encode("P", MakePoseMsg()), 1),
                                RejectCause::kTruncated, {"camera_pose_t.buffer"});
  ExpectRejected<rig_extrinsics_t>(&validator, "E", chop(Encode("E", MakeExtrinsicsMsg()), 1),
                                   RejectCause::kTruncated, {"rig_extrinsics_t."});
  ExpectRejected<rig_status_t>(&validator, "S", chop(Encode("S", MakeStatusMsg()), 1),
                               RejectCause::kTruncated, {"rig_status_t."});
  ExpectRejected<image_t>(&validator, "I", chop(Encode("I", MakeImageMsg()), 1),
                          RejectCause::kTruncated, {"image_t.size", "15 elements"});
  // Shorter than the fingerprint, than the version, ending inside a string.
  ExpectRejected<camera_pose_t>(&validator, "P", std::vector<uint8_t>(5, 0),
                                RejectCause::kTruncated, {"camera_pose_t.fingerprint"});
  std::vector<uint8_t> pose = Encode("P", MakePoseMsg());
  ExpectRejected<camera_pose_t>(&validator, "P", chop(pose, pose.size() - 9),
                                RejectCause::kTruncated, {"camera_pose_t.version"});
  ExpectRejected<camera_pose_t>(&validator, "P", chop(pose, pose.size() - kPoseCameraLength - 5),
                                RejectCause::kTruncated, {"camera_pose_t.camera"});
  ExpectRejected<camera_pose_t>(&validator, "P", {}, RejectCause::kTruncated, {});
  // An array length that points past the end of the buffer.
  const rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  std::vector<uint8_t> buffer = Encode("E", extrinsics);
  ASSERT_EQ(GetInt32(buffer, ExtrinsicsNumSlavesOffset(extrinsics)), 2);
  PutInt32(&buffer, ExtrinsicsNumSlavesOffset(extrinsics), 1'000'000'000);
  ExpectRejected<rig_extrinsics_t>(&validator, "E", buffer, RejectCause::kTruncated,
                                   {"rig_extrinsics_t.num_slaves", "1000000000 elements"});
  PutInt32(&buffer, ExtrinsicsNumSlavesOffset(extrinsics), 3);
  ExpectRejected<rig_extrinsics_t>(&validator, "E", buffer, RejectCause::kTruncated, {});
  EXPECT_EQ(validator.stats().Rejected(RejectCause::kTruncated), 10);
}

TEST(LcmValidation, Oversize) {
  MessageValidator validator(kNames);
  std::vector<uint8_t> buffer = Encode("P", MakePoseMsg());
  buffer.push_back(0);
  ExpectRejected<camera_pose_t>(&validator, "P", buffer, RejectCause::kOversize,
                                {"camera_pose_t.buffer", "1 bytes left over"});
  // One slave fewer announced than encoded: the second one is left over.
  const rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  buffer = Encode("E", extrinsics);
  PutInt32(&buffer, ExtrinsicsNumSlavesOffset(extrinsics), 1);
  ExpectRejected<rig_extrinsics_t>(&validator, "E", buffer, RejectCause::kOversize,
                                   {"rig_extrinsics_t.buffer", "left over"});
  buffer = Encode("S", MakeStatusMsg());
  buffer.insert(buffer.end(), 100, 0xab);
  ExpectRejected<rig_status_t>(&validator, "S", buffer, RejectCause::kOversize,
                               {"100 bytes left over"});
}

TEST(LcmValidation, Malformed) {
  MessageValidator validator(kNames);
  std::vector<uint8_t> buffer = Encode("P", MakePoseMsg());
  PutInt32(&buffer, kPoseCameraLength, 0);  // a string length < 1
  ExpectRejected<camera_pose_t>(&validator, "P", buffer, RejectCause::kMalformed,
                                {"camera_pose_t.camera", "string length 0"});
  // The same in a nested string, refused before LCM's own decode meets it.
  const rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  buffer = Encode("E", extrinsics);
  const size_t slave_name = ExtrinsicsNumSlavesOffset(extrinsics) + 4;
  ASSERT_EQ(GetInt32(buffer, slave_name), 5);  // "left" + NUL
  PutInt32(&buffer, slave_name, -3);
  ExpectRejected<rig_extrinsics_t>(&validator, "E", buffer, RejectCause::kMalformed,
                                   {"rig_extrinsics_t.slaves[0].name", "string length -3"});
  // A NUL inside a camera name.
  buffer = Encode("P", MakePoseMsg());
  buffer[kPoseCameraLength + 4 + 1] = 0;  // "l\0ft"
  ExpectRejected<camera_pose_t>(&validator, "P", buffer, RejectCause::kMalformed,
                                {"camera_pose_t.camera", "NUL"});
}

// `buffer` with the '#' of the string `text` (encoded in it) replaced by a NUL.
std::vector<uint8_t> WithNulAt(std::vector<uint8_t> buffer, const std::string& text) {
  const auto it = std::search(buffer.begin(), buffer.end(), text.begin(), text.end());
  EXPECT_NE(it, buffer.end()) << text;
  if (it != buffer.end()) *(it + static_cast<std::ptrdiff_t>(text.find('#'))) = 0;
  return buffer;
}

// A string length of INT32_MIN in a nested string or after the last array (found by the lcm_log
// fuzz target: LCM's decode computed length - 1, an overflow) is refused before LCM decodes.
TEST(LcmValidation, MostNegativeStringLengthIsMalformed) {
  MessageValidator validator(kNames);
  const rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  std::vector<uint8_t> buffer = Encode("E", extrinsics);
  const std::string& text = extrinsics.slaves[0].message;
  auto it = std::search(buffer.begin(), buffer.end(), text.begin(), text.end());
  ASSERT_NE(it, buffer.end());
  PutInt32(&buffer, static_cast<size_t>(it - buffer.begin()) - 4, INT32_MIN);
  ExpectRejected<rig_extrinsics_t>(&validator, "E", buffer, RejectCause::kMalformed,
                                   {"slaves[0].message", "string length -2147483648"});
  const rig_status_t status = MakeStatusMsg();
  buffer = Encode("S", status);
  it = std::search(buffer.begin(), buffer.end(), status.estimator_message.begin(),
                   status.estimator_message.end());
  ASSERT_NE(it, buffer.end());
  PutInt32(&buffer, static_cast<size_t>(it - buffer.begin()) - 4, INT32_MIN);
  ExpectRejected<rig_status_t>(&validator, "S", buffer, RejectCause::kMalformed,
                               {"estimator_message", "string length -2147483648"});
}

// A NUL inside any other string (found by the lcm_rig_status fuzz target): LCM decodes the
// announced length but encodes up to the first NUL, so such a message, once accepted, could not
// be encoded again (EncodeMessage failed).
TEST(LcmValidation, NulInsideAStringIsMalformed) {
  MessageValidator validator(kNames);
  rig_status_t status = MakeStatusMsg();
  status.estimator_message = "back: insufficient#motion";
  ExpectRejected<rig_status_t>(
      &validator, "S", WithNulAt(Encode("S", status), status.estimator_message),
      RejectCause::kMalformed, {"rig_status_t.estimator_message", "NUL byte at 18 of 25"});
  rig_extrinsics_t extrinsics = MakeExtrinsicsMsg();
  extrinsics.slaves[1].message = "initialising#";
  ExpectRejected<rig_extrinsics_t>(&validator, "E",
                                   WithNulAt(Encode("E", extrinsics), "initialising#"),
                                   RejectCause::kMalformed, {"message", "NUL byte"});
  image_t image = MakeImageMsg();
  image.pixel_format = "GR#Y";
  ExpectRejected<image_t>(&validator, "I", WithNulAt(Encode("I", image), "GR#Y"),
                          RejectCause::kMalformed, {"image_t.pixel_format", "NUL byte at 2 of 4"});
  // Without the NUL each is accepted and encodes again.
  Expected<rig_status_t> accepted =
      validator.Decode<rig_status_t>("S", Encode("S", status).data(), Encode("S", status).size());
  ASSERT_TRUE(accepted.ok()) << accepted.error();
  EXPECT_TRUE(EncodeMessage("S", kNames, *accepted).ok());
}

TEST(LcmValidation, StatsSummaryCountsByCause) {
  MessageValidator validator(kNames);
  const std::vector<uint8_t> good = Encode("P", MakePoseMsg());
  EXPECT_TRUE(validator.Decode<camera_pose_t>("P", good.data(), good.size()).ok());
  EXPECT_TRUE(validator.DecodeCameraPose("P", good.data(), good.size()).ok());
  camera_pose_t bad = MakePoseMsg();
  bad.version = 3;
  const std::vector<uint8_t> wrong_version = RawEncode(bad);
  EXPECT_FALSE(validator.DecodeCameraPose("P", wrong_version.data(), wrong_version.size()).ok());
  bad = MakePoseMsg();
  bad.C[0] = kNaN;
  for (int i = 0; i < 2; ++i) {
    const std::vector<uint8_t> nan = RawEncode(bad);
    EXPECT_FALSE(validator.Decode<camera_pose_t>("P", nan.data(), nan.size()).ok());
  }
  EXPECT_EQ(validator.stats().Summary(), "accepted 2, rejected 3 (wrong_version 1, non_finite 2)");
  validator.ResetStats();
  EXPECT_EQ(validator.stats().Summary(), "accepted 0, rejected 0");
  EXPECT_FALSE(validator.stats().last_rejection.has_value());
}

}  // namespace
}  // namespace rigcal::lcm::lcm_test
