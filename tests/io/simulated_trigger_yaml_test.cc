// SPDX-License-Identifier: Apache-2.0
// `source.trigger` of a simulated rig config: the simulated hardware trigger's keys, defaults
// and range errors that name the key.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "../../tools/io/src/config_sections.h"
#include "rigcal/io/rig_config.h"
#include "../../tools/io/src/yaml_fields.h"

namespace rigcal::io {
namespace {

namespace fs = std::filesystem;

Expected<sim::SimulatedRigSpec> ParseSource(const std::string& trigger_lines) {
  static int counter = 0;
  const fs::path dir =
      fs::temp_directory_path() / ("rigcal_sim_trigger_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const fs::path path = dir / ("source_" + std::to_string(counter++) + ".yaml");
  std::ofstream(path) << "source:\n"
                         "  type: simulated\n"
                         "  trajectory:\n"
                         "    waypoints:\n"
                         "      - {p: [0, 0, 3], ypr_deg: [0, 0, 0]}\n"
                         "      - {p: [1, 0, 3], ypr_deg: [10, 0, 0]}\n"
                      << trigger_lines;
  auto root = LoadYaml(path.string());
  if (!root) return Error{root.error()};
  return ParseSimulatedSource((*root)["source"], path.string());
}

TEST(SimulatedTriggerYaml, AbsentMeansOffAndEveryKeyIsRead) {
  auto off = ParseSource("");
  ASSERT_TRUE(off.ok()) << off.error();
  EXPECT_FALSE(off->trigger.enabled);
  auto on = ParseSource(
      "  trigger: {drift_ppm: -40, link_jitter_ms: 1.5, exposure_ms: 8, "
      "corrupt_probability: 0.001}\n");
  ASSERT_TRUE(on.ok()) << on.error();
  EXPECT_TRUE(on->trigger.enabled);
  EXPECT_DOUBLE_EQ(on->trigger.drift_ppm, -40);
  EXPECT_DOUBLE_EQ(on->trigger.link_jitter_ms, 1.5);
  EXPECT_DOUBLE_EQ(on->trigger.exposure_ms, 8);
  EXPECT_DOUBLE_EQ(on->trigger.corrupt_probability, 0.001);
  auto defaults = ParseSource("  trigger: {}\n");
  ASSERT_TRUE(defaults.ok()) << defaults.error();
  EXPECT_TRUE(defaults->trigger.enabled);
  EXPECT_DOUBLE_EQ(defaults->trigger.link_jitter_ms, 2.0);
}

TEST(SimulatedTriggerYaml, ErrorsNameTheKey) {
  auto unknown = ParseSource("  trigger: {rate_hz: 20}\n");
  ASSERT_FALSE(unknown.ok());
  EXPECT_NE(unknown.error().find("source.trigger.rate_hz"), std::string::npos) << unknown.error();
  auto drift = ParseSource("  trigger: {drift_ppm: 5000}\n");
  ASSERT_FALSE(drift.ok());
  EXPECT_NE(drift.error().find("source.trigger.drift_ppm"), std::string::npos) << drift.error();
  auto jitter = ParseSource("  trigger: {link_jitter_ms: -1}\n");
  ASSERT_FALSE(jitter.ok());
  EXPECT_NE(jitter.error().find("source.trigger.link_jitter_ms"), std::string::npos)
      << jitter.error();
}

}  // namespace
}  // namespace rigcal::io
