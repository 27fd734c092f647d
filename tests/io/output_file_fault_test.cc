// SPDX-License-Identifier: Apache-2.0
// Output files under hostile conditions: WriteFileAtomically / AtomicFile (the single writer of
// every file rigcal writes) replace only regular files and keep their permissions.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "io/trajectory_fixtures.h"
#include "rigcal/io/atomic_file.h"

namespace rigcal::io {
namespace {

using trajectory_test::HasSubstr;
namespace fs = std::filesystem;

// The temporary directory of the io tests (trajectory_fixtures.h).
class OutputFileFault : public trajectory_test::TrajectoryIoTest {
 protected:
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  static std::string Read(const std::string& path) {
    std::ifstream in(path);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }
  // Writing `path` (directly and through AtomicFile) must be refused, naming the path and
  // `kind`.
  void ExpectRefused(const std::string& path, const std::string& kind) {
    const Status status = WriteFileAtomically(path, "new contents\n");
    ASSERT_FALSE(status.ok()) << path << " was replaced";
    EXPECT_THAT(status.message(), HasSubstr("'" + path + "'"));
    EXPECT_THAT(status.message(), HasSubstr("it is " + kind + ", not a regular file"));
    auto file = AtomicFile::Create(path);
    ASSERT_FALSE(file.ok());
    EXPECT_THAT(file.error(), HasSubstr(kind));
  }
  size_t Entries() const {
    return static_cast<size_t>(std::distance(fs::directory_iterator(dir_), {}));
  }
};

TEST_F(OutputFileFault, FifoIsRefusedAndStaysAFifo) {
  const std::string fifo = Path("result.yaml");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  ExpectRefused(fifo, "a FIFO");
  EXPECT_TRUE(fs::is_fifo(fs::symlink_status(fifo)));
  EXPECT_EQ(Entries(), 1u);
}

TEST_F(OutputFileFault, SymlinkIsRefusedAndItsTargetUntouched) {
  const std::string target = Path("target.yaml");
  std::ofstream(target) << "good result\n";
  const std::string link = Path("result.yaml");
  fs::create_symlink(target, link);
  ExpectRefused(link, "a symbolic link");
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(link)));
  EXPECT_EQ(Read(target), "good result\n");
  // A dangling link too: it must not become a regular file.
  fs::remove(target);
  ExpectRefused(link, "a symbolic link");
  EXPECT_TRUE(fs::is_symlink(fs::symlink_status(link)));
  EXPECT_EQ(Entries(), 1u);
}

TEST_F(OutputFileFault, DeviceAndDirectoryAreRefused) {
  // A device is never replaced (as root the rename would succeed without the check).
  const std::string device = "/dev/zero";
  if (fs::is_character_file(fs::symlink_status(device))) {
    const Status dev = WriteFileAtomically(device, "x");
    ASSERT_FALSE(dev.ok());
    EXPECT_THAT(dev.message(), HasSubstr("'/dev/zero'"));
    EXPECT_TRUE(fs::is_character_file(fs::symlink_status(device)));
  }
  fs::create_directory(Path("out"));
  ExpectRefused(Path("out"), "a directory");
  EXPECT_TRUE(fs::is_directory(Path("out")));
}

TEST_F(OutputFileFault, ReplacedFileKeepsItsPermissions) {
  const std::string path = Path("state.txt");
  ASSERT_TRUE(WriteFileAtomically(path, "first\n").ok());
  ASSERT_EQ(::chmod(path.c_str(), 0600), 0);
  ASSERT_TRUE(WriteFileAtomically(path, "second\n").ok());
  EXPECT_EQ(Read(path), "second\n");
  struct stat st {};
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0600u);
  // Through AtomicFile (files another library writes by name) as well.
  ASSERT_EQ(::chmod(path.c_str(), 0640), 0);
  auto file = AtomicFile::Create(path);
  ASSERT_TRUE(file.ok()) << file.error();
  ASSERT_TRUE(file->Write("third\n").ok());
  ASSERT_TRUE(file->Commit().ok());
  ASSERT_EQ(::stat(path.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0640u);
  EXPECT_EQ(Read(path), "third\n");
  // A new file gets 0644.
  const std::string fresh = Path("fresh.txt");
  ASSERT_TRUE(WriteFileAtomically(fresh, "x").ok());
  ASSERT_EQ(::stat(fresh.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 07777, 0644u);
}

TEST_F(OutputFileFault, PathThatBecomesAFifoBeforeCommitIsNotReplaced) {
  const std::string path = Path("result.yaml");
  auto file = AtomicFile::Create(path);
  ASSERT_TRUE(file.ok()) << file.error();
  ASSERT_TRUE(file->Write("new\n").ok());
  ASSERT_EQ(::mkfifo(path.c_str(), 0644), 0);
  const Status status = file->Commit();
  ASSERT_FALSE(status.ok());
  EXPECT_THAT(status.message(), HasSubstr("it is a FIFO"));
  EXPECT_TRUE(fs::is_fifo(fs::symlink_status(path)));
  EXPECT_EQ(Entries(), 1u);  // the temporary file is gone
}

// A writer killed between Create and Commit (kill -9) leaves its temporary file; the next write
// of the same path removes it, but not the one of a writer still running.
TEST_F(OutputFileFault, LeftoverOfAKilledWriterIsRemoved) {
  const std::string path = Path("state.yaml");
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    auto file = AtomicFile::Create(path);
    if (!file.ok() || !file->Write("half").ok()) ::_exit(1);
    ::raise(SIGKILL);  // the destructor never runs
  }
  int wstatus = 0;
  ASSERT_EQ(::waitpid(child, &wstatus, 0), child);
  ASSERT_TRUE(WIFSIGNALED(wstatus));
  ASSERT_EQ(Entries(), 1u) << "the killed writer left no temporary file";
  auto running = AtomicFile::Create(path);  // this process's: alive
  ASSERT_TRUE(running.ok()) << running.error();
  EXPECT_EQ(Entries(), 1u);  // the leftover is gone, ours is there
  EXPECT_TRUE(fs::exists(running->temp_path()));
  ASSERT_TRUE(WriteFileAtomically(path, "whole\n").ok());
  EXPECT_TRUE(fs::exists(running->temp_path())) << "a running writer's file was removed";
  ASSERT_TRUE(running->Write("newer\n").ok());
  ASSERT_TRUE(running->Commit().ok());
  EXPECT_EQ(Read(path), "newer\n");
  EXPECT_EQ(Entries(), 1u);
}

// CommitAndKeepOpen: the file takes its name and the descriptor writes on at its end.
TEST_F(OutputFileFault, CommitAndKeepOpenWritesOnUnderTheName) {
  const std::string path = Path("drive.lcmlog");
  ASSERT_TRUE(WriteFileAtomically(path, "old\n").ok());
  ASSERT_EQ(::chmod(path.c_str(), 0600), 0);
  auto file = AtomicFile::Create(path);
  ASSERT_TRUE(file.ok()) << file.error();
  ASSERT_TRUE(file->Write("first\n").ok());
  EXPECT_EQ(Read(path), "old\n");
  Expected<int> fd = file->CommitAndKeepOpen();
  ASSERT_TRUE(fd.ok()) << fd.error();
  EXPECT_EQ(Read(path), "first\n");
  ASSERT_EQ(WriteAllBytes(*fd, "second\n"), 0);
  ASSERT_EQ(::close(*fd), 0);
  EXPECT_EQ(Read(path), "first\nsecond\n");
  EXPECT_EQ(fs::status(path).permissions() & fs::perms::all,
            fs::perms::owner_read | fs::perms::owner_write);
  EXPECT_EQ(Entries(), 1u);
}

}  // namespace
}  // namespace rigcal::io
