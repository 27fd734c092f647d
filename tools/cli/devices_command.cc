// SPDX-License-Identifier: Apache-2.0
// `rigcal devices`: the cameras and serial ports of this computer (capture::ListDevices): every
// V4L2 capture node with driver, card, bus, stable paths, formats and sizes; libcamera's
// cameras; the serial ports a trigger generator could be on. Text, or --json.
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "commands.h"
#include "exit_codes.h"
#include "rigcal/capture/device_list.h"

namespace rigcal::cli {
namespace {

nlohmann::json DevicesJson(const capture::DeviceList& list) {
  nlohmann::json out;
  out["v4l2"] = nlohmann::json::array();
  for (const capture::V4l2NodeInfo& n : list.v4l2) {
    nlohmann::json formats = nlohmann::json::array();
    for (const capture::V4l2FormatInfo& f : n.formats) {
      formats.push_back({{"fourcc", f.fourcc}, {"description", f.description}, {"sizes", f.sizes}});
    }
    out["v4l2"].push_back({{"node", n.node},
                           {"driver", n.driver},
                           {"card", n.card},
                           {"bus", n.bus_info},
                           {"stable_paths", n.stable_paths},
                           {"formats", formats}});
  }
  out["v4l2_problems"] = list.v4l2_problems;
  out["libcamera"] = {{"built_in", list.libcamera_built_in},
                      {"cameras", list.libcamera},
                      {"problem", list.libcamera_problem}};
  out["serial"] = nlohmann::json::array();
  for (const capture::SerialPortInfo& p : list.serial) {
    out["serial"].push_back(
        {{"node", p.node}, {"driver", p.driver}, {"stable_paths", p.stable_paths}});
  }
  return out;
}

void PrintDevices(const capture::DeviceList& list) {
  std::cout << "V4L2 capture devices (source.type: v4l2; device: a stable path below):\n";
  if (list.v4l2.empty()) std::cout << "  none\n";
  for (const capture::V4l2NodeInfo& n : list.v4l2) {
    std::cout << "  " << n.node << ": " << n.card << " (driver " << n.driver << ", bus "
              << n.bus_info << ")\n";
    for (const std::string& path : n.stable_paths) std::cout << "    " << path << "\n";
    for (const capture::V4l2FormatInfo& f : n.formats) {
      std::cout << "    " << f.fourcc << " (" << f.description << "):";
      for (const std::string& size : f.sizes) std::cout << " " << size;
      std::cout << "\n";
    }
  }
  for (const std::string& problem : list.v4l2_problems) std::cout << "  " << problem << "\n";
  std::cout << "libcamera cameras (source.type: libcamera; device: the id):\n";
  if (!list.libcamera_built_in) std::cout << "  not built in (libcamera-dev missing at build)\n";
  if (!list.libcamera_problem.empty()) std::cout << "  " << list.libcamera_problem << "\n";
  if (list.libcamera_built_in && list.libcamera.empty() && list.libcamera_problem.empty()) {
    std::cout << "  none\n";
  }
  for (const std::string& camera : list.libcamera) std::cout << "  " << camera << "\n";
  std::cout << "serial ports for a trigger generator (trigger.port):\n";
  if (list.serial.empty()) std::cout << "  none\n";
  for (const capture::SerialPortInfo& p : list.serial) {
    std::cout << "  " << p.node << (p.driver.empty() ? "" : " (driver " + p.driver + ")") << "\n";
    for (const std::string& path : p.stable_paths) std::cout << "    " << path << "\n";
  }
}

}  // namespace

void RegisterDevices(CLI::App& app, int* exit_code) {
  auto json = std::make_shared<bool>(false);
  CLI::App* cmd = app.add_subcommand(
      "devices",
      "Lists the cameras and serial ports of this computer, for a rig config: every V4L2\n"
      "capture device (driver, card, bus, the stable /dev/v4l/by-id and by-path names, pixel\n"
      "formats and frame sizes), the cameras libcamera sees, and the serial ports a trigger\n"
      "generator could be on (with /dev/serial/by-id names). Nothing is captured.");
  cmd->add_flag("--json", *json, "Print JSON instead of text");
  cmd->callback([json, exit_code]() {
    const capture::DeviceList list = capture::ListDevices();
    if (*json) {
      std::cout << DevicesJson(list).dump(2) << "\n";
    } else {
      PrintDevices(list);
    }
    *exit_code = kExitOk;
  });
}

}  // namespace rigcal::cli
