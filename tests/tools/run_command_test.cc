// `rigcal run` end to end through the built binary: the real static EuRoC frames (the drone
// stands still: the run must say "insufficient motion" and list the missing images, not
// crash), and the thesis virtual scene config with --eval.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace {

namespace fs = std::filesystem;

struct RunResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

std::string Slurp(const fs::path& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

class RunCommandTest : public ::testing::Test {
 protected:
  void SetUp() override {
#ifndef RIGCAL_BINARY
    FAIL() << "RIGCAL_BINARY is not defined: tests/CMakeLists.txt must pass the rigcal path";
#else
    binary_ = RIGCAL_BINARY;
#endif
    std::string pattern = (fs::path(::testing::TempDir()) / "run_command_XXXXXX").string();
    ASSERT_NE(::mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    std::error_code ec;
    if (!HasFailure()) fs::remove_all(dir_, ec);
  }

  RunResult Run(const std::string& args) {
    const std::string out = (dir_ / "stdout.txt").string();
    const std::string err = (dir_ / "stderr.txt").string();
    const std::string command = "'" + binary_ + "' " + args + " > '" + out + "' 2> '" + err + "'";
    RunResult r;
    const int status = std::system(command.c_str());
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    r.out = Slurp(out);
    r.err = Slurp(err);
    return r;
  }

  std::string binary_;
  fs::path dir_;
};

TEST_F(RunCommandTest, StaticEurocFramesGiveInsufficientMotion) {
  const fs::path mav0 = fs::path(RIGCAL_SHARED_DATA_DIR) / "euroc_v101_static" / "mav0";
  if (!fs::exists(mav0)) GTEST_SKIP() << mav0 << " not found";
  const std::string config = (dir_ / "euroc.yaml").string();
  std::ofstream(config) << "rig: {name: euroc_static, master: cam0}\n"
                           "cameras:\n"
                           "  - name: cam0\n"
                           "    model: pinhole\n"
                           "    resolution: [752, 480]\n"
                           "    intrinsics: [458.654, 457.296, 367.215, 248.375]\n"
                           "    distortion: [-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05]\n"
                           "    device: "
                        << (mav0 / "cam0").string()
                        << "\n"
                           "  - name: cam1\n"
                           "    model: pinhole\n"
                           "    resolution: [752, 480]\n"
                           "    intrinsics: [457.587, 456.134, 379.999, 255.238]\n"
                           "    distortion: [-0.28368365, 0.07451284, -0.00010473, -3.55590700e-05]\n"
                           "    device: "
                        << (mav0 / "cam1").string()
                        << "\n"
                           "source: {type: image_folders}\n";
  const RunResult r =
      Run("run --config '" + config + "' --out '" + (dir_ / "result.yaml").string() + "'");
  EXPECT_EQ(r.exit_code, 3) << r.out << r.err;  // no slave calibrated
  EXPECT_NE(r.out.find("insufficient motion"), std::string::npos) << r.out;
  EXPECT_NE(r.err.find("4 listed images missing or unreadable"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("1403715278012143104"), std::string::npos) << r.err;
  EXPECT_TRUE(fs::exists(dir_ / "result.yaml"));  // the (unusable) result is still written
}

TEST_F(RunCommandTest, MissingSourceIsAClearError) {
  const std::string config = (dir_ / "rig.yaml").string();
  std::ofstream(config) << "rig: {master: a}\ncameras:\n  - name: a\n  - name: b\n";
  const RunResult r = Run("run --config '" + config + "'");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("no `source:` section"), std::string::npos) << r.err;
}

}  // namespace
