// SPDX-License-Identifier: Apache-2.0
// A full disk while `rigcal replay` saves its state and result and while `rigcal record` writes a
// log: a clear error naming the file (exit 1), the files of the previous run intact, no
// temporary file left. The disk is a 512 KiB tmpfs mounted in a private mount namespace
// (unshare -m, needs root); without that the test is skipped (a failure under CI=true).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "cli/command_test.h"
#include "support/simulated_rig_config.h"
#include "support/skip.h"

namespace rigcal {
namespace {

namespace fs = std::filesystem;
using cli_test::Quote;
using cli_test::RunResult;
using cli_test::Slurp;

// Runs in the private mount namespace: $1 the mount point, $2 the test directory (outside the
// tmpfs: inputs, and copies of what the tmpfs held after each step), $3 rigcal.
constexpr const char* kScript = R"(set -u
D="$1"; T="$2"; R="$3"
mount -t tmpfs -o size=512k tmpfs "$D" || { echo "SKIP: cannot mount a tmpfs"; exit 77; }
files="--out $D/r.yaml --state $D/s.state"
# 1: a good run and a good recording.
"$R" replay "$T/poses.lcmlog" --config "$T/rig.yaml" --no-progress $files >/dev/null 2>"$T/err1.txt"
echo "replay1 $?"
"$R" record --config "$T/sim.yaml" -o "$D/drive.lcmlog" --no-vo --fast >/dev/null 2>"$T/err_rec1.txt"
echo "record1 $?"
cp "$D/r.yaml" "$T/r1.yaml"; cp "$D/s.state" "$T/s1.state"; cp "$D/drive.lcmlog" "$T/drive1.lcmlog"
# 2: the disk is full.
head -c 16M /dev/zero > "$D/fill" 2>/dev/null
df -k "$D" | tail -1 > "$T/df.txt"
"$R" replay "$T/poses.lcmlog" --config "$T/rig.yaml" --no-progress --to 20 $files >/dev/null 2>"$T/err2.txt"
echo "replay2 $?"
"$R" record --config "$T/sim.yaml" -o "$D/drive2.lcmlog" --no-vo --fast >/dev/null 2>"$T/err_rec2.txt"
echo "record2 $?"
cp "$D/r.yaml" "$T/r2.yaml"; cp "$D/s.state" "$T/s2.state"; cp "$D/drive.lcmlog" "$T/drive2.lcmlog"
ls -A "$D" > "$T/listing.txt"
umount "$D"
)";

// Resume on a full disk: $1 the mount point, $2 the test directory, $3 rigcal. The state is saved
// every 0.05 s of log time (800 saves of the 40 s drive), each one failing.
constexpr const char* kResumeScript = R"(set -u
D="$1"; T="$2"; R="$3"
mount -t tmpfs -o size=512k tmpfs "$D" || { echo "SKIP: cannot mount a tmpfs"; exit 77; }
"$R" replay "$T/poses.lcmlog" --config "$T/rig.yaml" --no-progress --out "$D/r.yaml" --state "$D/s.state" >/dev/null 2>"$T/err1.txt"
echo "replay1 $?"
cp "$D/s.state" "$T/s1.state"
head -c 16M /dev/zero > "$D/fill" 2>/dev/null
for command in "replay --no-progress" "calib --log"; do
  "$R" $command "$T/poses.lcmlog" --config "$T/fast_saves.yaml" --out "$D/r.yaml" --state "$D/s.state" --resume >/dev/null 2>"$T/err2.txt"
  echo "resume $?"
  cat "$T/err2.txt" >> "$T/err_resume.txt"
  cmp -s "$D/s.state" "$T/s1.state" && echo "state kept"
done
ls -A "$D" > "$T/listing.txt"
umount "$D"
)";

class DiskFullFault : public cli_test::SynthLogTest {
 protected:
  // Whether a tmpfs can be mounted in a private mount namespace (root or CAP_SYS_ADMIN).
  std::string CannotMount() {
    const RunResult probe = cli_test::RunShell(
        "unshare -m sh -c 'mount -t tmpfs -o size=64k tmpfs " + Quote(Path("")) + "'", dir_);
    return probe.exit_code == 0 ? std::string() : probe.err + " ";
  }
  // `script` run with unshare -m (arguments: the mount point, the test directory, rigcal), or
  // why it cannot be (`cannot` not empty: no tmpfs can be mounted here).
  struct ScriptRun {
    std::string cannot;
    RunResult result;
  };
  ScriptRun RunOnSmallDisk(const char* script) {
    ScriptRun run;
    run.cannot = CannotMount();
    if (!run.cannot.empty()) return run;
    std::ofstream(Path("script.sh")) << script;
    fs::create_directory(Path("mnt"));
    run.result =
        cli_test::RunShell("unshare -m sh " + Quote(Path("script.sh")) + " " + Quote(Path("mnt")) +
                               " " + Quote(dir_.string()) + " " + Quote(binary_),
                           dir_);
    return run;
  }
};

constexpr char kCannotMount[] =
    "cannot mount a tmpfs in a private mount namespace (unshare -m, needs root or "
    "CAP_SYS_ADMIN): ";

// --resume with --state on a full disk: every save fails the same way. The failure is reported
// once with the path and the errno text (one error per save, 800 here, grew without bound in
// memory and on stderr), counted, retried on the save schedule; the run ends with exit 1 and
// a line saying the final state is not saved; the state saved before stays.
TEST_F(DiskFullFault, ResumeOnAFullDiskReportsTheFailedSavesOnce) {
  std::ofstream(Path("fast_saves.yaml"))
      << Slurp(Path("rig.yaml")) << "state: {save_interval_s: 0.05}\n";
  const ScriptRun run = RunOnSmallDisk(kResumeScript);
  if (!run.cannot.empty()) RIGCAL_SKIP_MISSING() << kCannotMount << run.cannot;
  const RunResult& r = run.result;
  if (r.exit_code == 77) RIGCAL_SKIP_MISSING() << r.out << r.err;
  ASSERT_EQ(r.exit_code, 0) << r.Explain();
  EXPECT_EQ(r.out, "replay1 0\nresume 1\nstate kept\nresume 1\nstate kept\n")
      << Slurp(Path("err1.txt"));
  const std::string err = Slurp(Path("err_resume.txt"));
  const std::string cannot = "cannot write '" + Path("mnt/s.state") + "'";
  int reported = 0;
  for (size_t at = err.find(cannot); at != std::string::npos; at = err.find(cannot, at + 1)) {
    ++reported;
  }
  // Per command: logged once when it happens, listed once among the errors at the end.
  EXPECT_EQ(reported, 4) << err.substr(0, 4000);
  EXPECT_NE(err.find("No space left on device"), std::string::npos) << err.substr(0, 4000);
  EXPECT_NE(err.find("saves of " + Path("mnt/s.state") + " failed, the last one too"),
            std::string::npos)
      << err.substr(0, 4000);
  EXPECT_LT(err.size(), 40'000u) << "stderr grows with the failed saves";
  const std::string listing = Slurp(Path("listing.txt"));
  EXPECT_EQ(listing.find(".tmp"), std::string::npos) << listing;
}

TEST_F(DiskFullFault, SavingAndRecordingOnAFullDiskKeepThePreviousFiles) {
  std::ofstream(Path("sim.yaml")) << support::SimulatedRigConfig(160, 120, 5);
  const ScriptRun run = RunOnSmallDisk(kScript);
  if (!run.cannot.empty()) RIGCAL_SKIP_MISSING() << kCannotMount << run.cannot;
  const RunResult& r = run.result;
  if (r.exit_code == 77) RIGCAL_SKIP_MISSING() << r.out << r.err;
  ASSERT_EQ(r.exit_code, 0) << r.Explain();
  EXPECT_NE(r.out.find("replay1 0\n"), std::string::npos) << r.out << Slurp(Path("err1.txt"));
  EXPECT_NE(r.out.find("record1 0\n"), std::string::npos) << r.out << Slurp(Path("err_rec1.txt"));
  std::cout << "tmpfs when full (df -k): " << Slurp(Path("df.txt"));

  // The saves of the second replay fail with the reason and the file; the earlier files stay.
  EXPECT_NE(r.out.find("replay2 1\n"), std::string::npos) << r.out;
  const std::string err2 = Slurp(Path("err2.txt"));
  EXPECT_NE(err2.find("cannot write '" + Path("mnt/s.state") + "'"), std::string::npos) << err2;
  EXPECT_NE(err2.find("No space left on device"), std::string::npos) << err2;
  EXPECT_EQ(Slurp(Path("r2.yaml")), Slurp(Path("r1.yaml")));
  EXPECT_EQ(Slurp(Path("s2.state")), Slurp(Path("s1.state")));
  EXPECT_FALSE(Slurp(Path("s1.state")).empty());

  // A new recording fails with the reason and the file; the earlier log stays. (A recording is
  // written in place, readable up to its last whole event: what it holds stays.)
  EXPECT_NE(r.out.find("record2 1\n"), std::string::npos) << r.out;
  const std::string err_rec2 = Slurp(Path("err_rec2.txt"));
  EXPECT_NE(err_rec2.find("No space left on device"), std::string::npos) << err_rec2;
  EXPECT_NE(err_rec2.find(Path("mnt/drive2.lcmlog")), std::string::npos) << err_rec2;
  EXPECT_TRUE(Slurp(Path("drive2.lcmlog")) == Slurp(Path("drive1.lcmlog")));
  EXPECT_FALSE(Slurp(Path("drive1.lcmlog")).empty());

  // No temporary file left behind.
  const std::string listing = Slurp(Path("listing.txt"));
  EXPECT_EQ(listing.find(".tmp"), std::string::npos) << listing;
  EXPECT_EQ(listing.rfind("drive.lcmlog\n", 0), 0u) << listing;
}

}  // namespace
}  // namespace rigcal
