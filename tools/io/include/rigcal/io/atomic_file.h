#pragma once
// Crash-safe file replacement: a reader sees either the old file or the complete new one.

#include <string>
#include <string_view>

namespace rigcal::tools {

// Writes `contents` to `path` atomically: writes a temporary file in the same directory,
// fsyncs it, renames it over `path` and fsyncs the directory. The new file gets mode 0644.
// Returns an empty string on success, else a message that
// names `path` and the failing step with its errno text; on failure `path` is unchanged and
// no temporary file is left behind. Thread-safe for distinct paths.
[[nodiscard]] std::string WriteFileAtomically(const std::string& path, std::string_view contents);

}  // namespace rigcal::tools
