// SPDX-License-Identifier: Apache-2.0
#pragma once
// What the fuzz targets of tests/fuzz share: the input as a file for readers that take a path,
// quiet logs, and the check of a property that must hold for every accepted input.

#include <cstddef>
#include <cstdint>
#include <string>

namespace rigcal::fuzz {

// A file in a private directory (under /dev/shm when it exists, else TMPDIR or /tmp) that holds
// the current input; removed with its directory when the process exits normally.
class InputFile {
 public:
  // `name`: the file's name (its stem names a trajectory, its extension may matter).
  explicit InputFile(const std::string& name);
  ~InputFile();
  InputFile(const InputFile&) = delete;
  InputFile& operator=(const InputFile&) = delete;

  // Replaces the file's content with `size` bytes at `data`; returns the file's path.
  const std::string& Write(const uint8_t* data, size_t size);
  const std::string& path() const { return path_; }

 private:
  std::string dir_;
  std::string path_;
};

// Every module logger off: a parser's warnings for each of millions of inputs cost time and
// hide libFuzzer's output.
void QuietLogs();

// A broken property of an accepted input: prints `what` and aborts, which libFuzzer reports as a
// crash and keeps the input.
[[noreturn]] void PropertyFailed(const std::string& what);

#define RIGCAL_FUZZ_EXPECT(condition, what)                 \
  do {                                                      \
    if (!(condition)) ::rigcal::fuzz::PropertyFailed(what); \
  } while (0)

}  // namespace rigcal::fuzz
