// SPDX-License-Identifier: Apache-2.0
#pragma once
// An empty directory for a test's files under GoogleTest's temporary directory. Header-only.

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace rigcal::support {

// <TempDir>/rigcal_<name>, emptied and created.
inline std::filesystem::path FreshTempDir(const std::string& name) {
  const std::filesystem::path dir =
      std::filesystem::path(::testing::TempDir()) / ("rigcal_" + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace rigcal::support
