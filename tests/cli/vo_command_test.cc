// SPDX-License-Identifier: Apache-2.0
// `rigcal vo`: the VO of one camera of a rig config alone. A camera the config does not name is
// an error; on the real visp_rbt_sequence (config/real_visp_rbt.yaml) the command prints where
// the VO initialised, the posed share and one scale segment, and writes as many poses as it
// reports, in the native format with the segment column.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "command_test.h"
#include "support/real_mono_sequence.h"
#include "support/skip.h"

namespace rigcal::cli_test {
namespace {

const std::string kRbtConfig = std::string(RIGCAL_SOURCE_DIR) + "/config/real_visp_rbt.yaml";

using VoCommandTest = CommandTest;

TEST_F(VoCommandTest, UnknownCameraIsAnError) {
  const RunResult r = Run("vo --config " + Quote(kRbtConfig) + " --camera nope");
  EXPECT_EQ(r.exit_code, 1) << r.Explain();
  EXPECT_NE(r.err.find("no camera 'nope'"), std::string::npos) << r.Explain();
}

TEST_F(VoCommandTest, RealSequencePosesOneSegment) {
  if (!support::RealMonoAvailable("visp_rbt_sequence")) {
    RIGCAL_SKIP_MISSING() << "no " << support::RealMonoFolder("visp_rbt_sequence");
  }
  const RunResult r = Run("vo --config " + Quote(kRbtConfig) + " --camera cam0 --poses-out " +
                          Quote(Path("cam0.txt")));
  ASSERT_EQ(r.exit_code, 0) << r.Explain();
  EXPECT_NE(r.out.find("99 frames, first pose at frame"), std::string::npos) << r.Explain();
  EXPECT_NE(r.out.find("(100.00 %), 1 scale segment(s)"), std::string::npos) << r.Explain();
  std::ifstream in(Path("cam0.txt"));
  std::string line;
  int poses = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    ++poses;
    EXPECT_EQ(line.substr(line.rfind(' ') + 1), "0") << line;  // segment 0
  }
  EXPECT_GT(poses, 0);
  EXPECT_NE(r.out.find(std::to_string(poses) + " poses written"), std::string::npos) << r.Explain();
}

}  // namespace
}  // namespace rigcal::cli_test
