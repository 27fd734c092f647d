// WriteGroundTruth: a simulated rig's truth files, written atomically.
#include "rigcal/io/ground_truth_files.h"

#include <filesystem>

#include "rigcal/io/atomic_file.h"

namespace rigcal::tools {

Status WriteGroundTruth(const sim::SimulatedRig& rig, const std::string& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return Error{dir + ": cannot create directory: " + ec.message()};
  for (const auto& [name, contents] : rig.GroundTruthFiles()) {
    if (Status status = WriteFileAtomically((fs::path(dir) / name).string(), contents);
        !status.ok()) {
      return status;
    }
  }
  return Status::Ok();
}

}  // namespace rigcal::tools
