// SPDX-License-Identifier: Apache-2.0
#pragma once
// Crash-safe file replacement: a reader sees either the old file or the complete new one. Every
// file rigcal writes goes through here (WriteFileAtomically, or AtomicFile for files another
// library writes by name, such as LCM logs).

#include <string>
#include <string_view>

#include "rigcal/base/status.h"

namespace rigcal::io {

// Permission bits of a file rigcal creates where none was (before the umask).
inline constexpr unsigned kNewFileMode = 0644;

// Writes `contents` to `path` atomically: writes a temporary file in the same directory,
// fsyncs it, renames it over `path` and fsyncs the directory. Only a regular file is replaced:
// when `path` is a symbolic link, FIFO, device, directory or socket the error says so
// ("cannot write '<path>': it is a FIFO, not a regular file ...") and nothing is written. The
// new file keeps the permission bits of the file it replaces (`new_file_mode`, 0644 unless
// given, for a new file). On failure the error names `path` and the failing step with its errno
// text
// ("cannot write '<path>': <step>: <errno text>"), `path` is unchanged and no temporary file is
// left behind. Thread-safe for distinct paths.
[[nodiscard]] Status WriteFileAtomically(const std::string& path, std::string_view contents,
                                         unsigned new_file_mode = kNewFileMode);

// Ok when `path` does not exist or is a regular file (a symbolic link is not followed): what
// WriteFileAtomically may replace. Otherwise the error says what it is ("cannot write '<path>':
// it is a directory, not a regular file ...").
[[nodiscard]] Status CheckReplaceable(const std::string& path);

// Writes all of `data` to the open file descriptor `fd`, retrying short writes and EINTR.
// Returns 0 or the errno value of the failing write. Thread-safe for distinct descriptors.
int WriteAllBytes(int fd, std::string_view data);

// A file set aside by KeepAside: where it is now and its permission bits (a file written in its
// place gets the same: WriteFileAtomically(path, contents, mode)).
struct KeptAside {
  std::string path;
  unsigned mode = kNewFileMode;
};

// Renames the regular file `path` to "<path>.<tag>-<UTC time, YYYYmmddTHHMMSSZ>" (with "-2",
// "-3", ... when that exists) so that a file rigcal will not use (e.g. a rejected state file) is
// kept, not overwritten; its mode is kept. Anything but a regular file (a directory, symbolic
// link, device, ...) is not rigcal's to move: the error says what it is, and nothing is renamed.
// The new path, or the error naming `path`.
Expected<KeptAside> KeepAside(const std::string& path, const std::string& tag);

// A file that is written by name by someone else (e.g. ::lcm::LogFile) and replaces `path`
// atomically: Create() makes an empty temporary file next to `path` (the mode and the refusal
// of anything but a regular file as WriteFileAtomically's; checked again by Commit()); the caller
// writes temp_path() and closes it; Commit() fsyncs it, renames it over `path` and fsyncs the
// directory. A temporary file that was not committed is removed by the destructor. Errors as
// WriteFileAtomically's. One thread at a time.
// Temporary files are ".<name>.tmp.<pid>.XXXXXX" next to `path`; Create() removes those of
// `path` whose process no longer exists (left by a writer killed mid-write).
class AtomicFile {
 public:
  // The temporary file for `path`, or the error ("cannot write '<path>': ...").
  // `new_file_mode`: the permission bits when `path` does not exist yet.
  static Expected<AtomicFile> Create(const std::string& path,
                                     unsigned new_file_mode = kNewFileMode);
  ~AtomicFile();
  AtomicFile(AtomicFile&& other) noexcept;
  AtomicFile& operator=(AtomicFile&& other) noexcept;
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  const std::string& path() const { return path_; }
  // Where to write the contents until Commit().
  const std::string& temp_path() const { return temp_path_; }
  // Appends `data` to the temporary file (for callers that write through this object).
  [[nodiscard]] Status Write(std::string_view data);
  // Makes the temporary file `path` (see above). After a failure the temporary file is gone
  // and `path` is unchanged. Call at most once.
  [[nodiscard]] Status Commit();
  // As Commit(), but the file stays open: the descriptor, now the caller's to close, writes on
  // at the end of `path` (a recording that replaces an old one once it has its first event).
  [[nodiscard]] Expected<int> CommitAndKeepOpen();

 private:
  AtomicFile(std::string path, std::string temp_path, int fd);
  // "cannot write '<path>': <step>: <errno text>", and the temporary file removed.
  Status Fail(const std::string& step, int err);
  // The synced, closed or kept temporary file renamed over `path` (checked again), the
  // directory synced; on failure the temporary file is removed.
  Status RenameOverPath();

  std::string path_;
  std::string temp_path_;
  int fd_ = -1;  // open on temp_path_ until Commit(); -1 when committed or failed
};

}  // namespace rigcal::io
