// SimulatedRig::GroundTruthFiles: the simulated rig's true trajectories (TUM) and true rig (rig
// YAML) as file contents; rigcal_io writes them (WriteGroundTruth).
#include <filesystem>
#include <sstream>

#include "rigcal/base/format.h"
#include "rigcal/base/time_format.h"
#include "rigcal/sim/simulated_rig.h"
#include "sim_rig_data.h"

namespace rigcal::sim {
std::vector<std::pair<std::string, std::string>> SimulatedRig::GroundTruthFiles() const {
  std::vector<std::pair<std::string, std::string>> files;
  const SimulatedRigSpec& spec = data_->spec;
  for (int c = 0; c < num_cameras(); ++c) {
    std::ostringstream local, world;
    const std::string header = "# simulated ground truth of camera " + spec.names[c] +
                               " (TUM: t tx ty tz qx qy qz qw; world_from_camera, metres)\n";
    local << header << "# frame: the camera's pose at frame 0\n";
    world << header << "# frame: the simulated world (z up)\n";
    const Pose first = CameraPoseAt(c, 0.0);
    for (int64_t k = 0; k < num_frames(); ++k) {
      const Pose w = CameraPoseAt(c, FrameStreamTime(k));
      const Pose l = first.Between(w);
      const std::string t = FormatNsAsSeconds(FrameTimeNs(k));
      for (auto [out, pose] : {std::pair<std::ostringstream*, const Pose*>{&local, &l},
                               std::pair<std::ostringstream*, const Pose*>{&world, &w}}) {
        *out << t << ' ' << ShortestText(pose->C.x()) << ' ' << ShortestText(pose->C.y()) << ' '
             << ShortestText(pose->C.z()) << ' ' << ShortestText(pose->q.x()) << ' '
             << ShortestText(pose->q.y()) << ' ' << ShortestText(pose->q.z()) << ' '
             << ShortestText(pose->q.w()) << '\n';
      }
    }
    files.emplace_back(spec.names[c] + ".txt", local.str());
    files.emplace_back("world_" + spec.names[c] + ".txt", world.str());
  }
  std::ostringstream yaml;
  yaml << "# True rig of a simulated source: every slave's orientation and centre in the master\n"
          "# frame (metres); scale 1 because the simulated truth is metric.\n";
  yaml << "master: " << spec.names[0] << "\n";
  const std::vector<Similarity> rig = TrueRig();
  for (size_t i = 0; i < rig.size(); ++i) {
    const Similarity& s = rig[i];
    yaml << spec.names[i + 1] << ":\n"
         << "  q_wxyz: [" << ShortestText(s.q.w()) << ", " << ShortestText(s.q.x()) << ", "
         << ShortestText(s.q.y()) << ", " << ShortestText(s.q.z()) << "]\n"
         << "  C: [" << ShortestText(s.C.x()) << ", " << ShortestText(s.C.y()) << ", "
         << ShortestText(s.C.z()) << "]\n"
         << "  scale: 1\n";
  }
  files.emplace_back("truth.yaml", yaml.str());
  return files;
}

}  // namespace rigcal::sim
