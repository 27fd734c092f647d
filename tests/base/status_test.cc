// SPDX-License-Identifier: Apache-2.0
// The error vocabulary: Status, Expected<T> with a checked value(), RequireValid.
#include "rigcal/base/status.h"

#include <gtest/gtest.h>

#include <memory>
#include <string>

namespace rigcal {
namespace {

TEST(Status, SuccessAndError) {
  const Status ok;
  EXPECT_TRUE(ok.ok());
  EXPECT_TRUE(ok.message().empty());
  const Status bad = Error{"window_size: must be >= 1, is 0"};
  EXPECT_FALSE(bad.ok());
  EXPECT_FALSE(static_cast<bool>(bad));
  EXPECT_EQ(bad.message(), "window_size: must be >= 1, is 0");
  EXPECT_EQ(bad.Prefixed("estimator").message(), "estimator: window_size: must be >= 1, is 0");
  EXPECT_TRUE(ok.Prefixed("estimator").ok());
}

TEST(Expected, ValueOfAnErrorThrowsWithTheMessage) {
  Expected<int> bad = Error{"poses.txt:3: 7 fields, expected 8"};
  EXPECT_FALSE(bad.ok());
  EXPECT_EQ(bad.error(), "poses.txt:3: 7 fields, expected 8");
  EXPECT_EQ(bad.status().message(), bad.error());
  try {
    (void)bad.value();
    FAIL() << "value() of an error returned";
  } catch (const BadExpectedAccess& e) {
    EXPECT_NE(std::string(e.what()).find("poses.txt:3"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)*bad, BadExpectedAccess);
  const Expected<std::string> bad_string = Error{"x"};
  EXPECT_THROW((void)bad_string->size(), BadExpectedAccess);
  EXPECT_THROW((void)std::move(bad).value(), BadExpectedAccess);
}

TEST(Expected, ValueAndMove) {
  Expected<std::unique_ptr<int>> good = std::make_unique<int>(42);
  ASSERT_TRUE(good.ok());
  EXPECT_TRUE(good.error().empty());
  EXPECT_EQ(*good.value(), 42);
  std::unique_ptr<int> moved = std::move(good).value();
  EXPECT_EQ(*moved, 42);
}

TEST(Expected, FromStatus) {
  const Expected<double> bad = Status(Error{"scale: not finite"});
  EXPECT_EQ(bad.error(), "scale: not finite");
  EXPECT_THROW((void)Expected<double>(Status::Ok()), std::logic_error);
}

TEST(RequireValid, ThrowsInvalidOptionsNamingTheType) {
  EXPECT_NO_THROW(RequireValid(Status::Ok(), "VoOptions"));
  try {
    RequireValid(Error{"max_features: must be > 0, is -1"}, "VoOptions");
    FAIL() << "no throw";
  } catch (const InvalidOptions& e) {
    EXPECT_STREQ(e.what(), "VoOptions: max_features: must be > 0, is -1");
  }
}

}  // namespace
}  // namespace rigcal
