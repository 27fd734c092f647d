// SPDX-License-Identifier: Apache-2.0
#include "rigcal/base/logging.h"

#include <spdlog/sinks/stdout_color_sinks.h>

#include <cstdlib>

#include "rigcal/base/thread_annotations.h"

namespace rigcal {
namespace {

// ModuleLogger and SetLogLevel may be called from any thread.
Mutex g_mutex;
spdlog::level::level_enum g_level RIGCAL_GUARDED_BY(g_mutex) = spdlog::level::info;
bool g_level_from_env_done RIGCAL_GUARDED_BY(g_mutex) = false;

void LevelFromEnvironmentLocked() RIGCAL_REQUIRES(g_mutex) {
  if (g_level_from_env_done) return;
  g_level_from_env_done = true;
  if (const char* env = std::getenv("RIGCAL_LOG_LEVEL")) {
    const auto level = spdlog::level::from_str(env);
    if (level != spdlog::level::off || std::string(env) == "off") g_level = level;
  }
}

}  // namespace

std::shared_ptr<spdlog::logger> ModuleLogger(const std::string& module) {
  MutexLock lock(g_mutex);
  LevelFromEnvironmentLocked();
  if (auto existing = spdlog::get(module)) return existing;
  auto logger = spdlog::stderr_color_mt(module);
  logger->set_pattern("[%H:%M:%S.%e] [%n] [%^%l%$] %v");
  logger->set_level(g_level);
  return logger;
}

bool SetLogLevel(const std::string& level) {
  const auto parsed = spdlog::level::from_str(level);
  if (parsed == spdlog::level::off && level != "off") return false;
  MutexLock lock(g_mutex);
  g_level_from_env_done = true;
  g_level = parsed;
  spdlog::apply_all([parsed](const std::shared_ptr<spdlog::logger>& l) { l->set_level(parsed); });
  return true;
}

}  // namespace rigcal
