// SimulatedRig::WriteGroundTruth: the simulated rig's true trajectories (TUM) and true rig
// (rig YAML), written atomically.
#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <sstream>

#include "rigcal/drivers/simulated_rig.h"
#include "sim_rig_data.h"

namespace rigcal::drivers {
namespace {

std::string Num(double v) {
  char buffer[64];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), v);
  return std::string(buffer, result.ptr);
}

// Seconds with 9 decimals, exactly.
std::string FormatNs(int64_t t_ns) {
  const bool negative = t_ns < 0;
  const uint64_t magnitude =
      negative ? static_cast<uint64_t>(-(t_ns + 1)) + 1 : static_cast<uint64_t>(t_ns);
  char text[40];
  std::snprintf(text, sizeof(text), "%s%llu.%09llu", negative ? "-" : "",
                static_cast<unsigned long long>(magnitude / 1000000000ull),
                static_cast<unsigned long long>(magnitude % 1000000000ull));
  return text;
}

// Writes `contents` to `path` through a temporary file in the same directory and a rename.
Status WriteAtomically(const std::string& path, const std::string& contents) {
  static std::atomic<int> counter{0};
  const std::string tmp =
      path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter.fetch_add(1));
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return Error{path + ": cannot create temporary file: " + std::strerror(errno)};
  size_t written = 0;
  while (written < contents.size()) {
    const ssize_t n = ::write(fd, contents.data() + written, contents.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string error = path + ": write failed: " + std::strerror(errno);
      ::close(fd);
      ::unlink(tmp.c_str());
      return Error{error};
    }
    written += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const std::string error = path + ": fsync/close failed: " + std::strerror(errno);
    ::unlink(tmp.c_str());
    return Error{error};
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string error = path + ": rename failed: " + std::strerror(errno);
    ::unlink(tmp.c_str());
    return Error{error};
  }
  return Status::Ok();
}

}  // namespace

Status SimulatedRig::WriteGroundTruth(const std::string& dir) const {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return Error{dir + ": cannot create directory: " + ec.message()};
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
      const std::string t = FormatNs(FrameTimeNs(k));
      for (auto [out, pose] : {std::pair<std::ostringstream*, const Pose*>{&local, &l},
                               std::pair<std::ostringstream*, const Pose*>{&world, &w}}) {
        *out << t << ' ' << Num(pose->C.x()) << ' ' << Num(pose->C.y()) << ' ' << Num(pose->C.z())
             << ' ' << Num(pose->q.x()) << ' ' << Num(pose->q.y()) << ' ' << Num(pose->q.z()) << ' '
             << Num(pose->q.w()) << '\n';
      }
    }
    const std::string base = (fs::path(dir) / spec.names[c]).string();
    if (Status status = WriteAtomically(base + ".txt", local.str()); !status.ok()) return status;
    const std::string world_path = (fs::path(dir) / ("world_" + spec.names[c] + ".txt")).string();
    if (Status status = WriteAtomically(world_path, world.str()); !status.ok()) return status;
  }
  std::ostringstream yaml;
  yaml << "# True rig of a simulated source: every slave's orientation and centre in the master\n"
          "# frame (metres); scale 1 because the simulated truth is metric.\n";
  yaml << "master: " << spec.names[0] << "\n";
  const std::vector<Similarity> rig = TrueRig();
  for (size_t i = 0; i < rig.size(); ++i) {
    const Similarity& s = rig[i];
    yaml << spec.names[i + 1] << ":\n"
         << "  q_wxyz: [" << Num(s.q.w()) << ", " << Num(s.q.x()) << ", " << Num(s.q.y()) << ", "
         << Num(s.q.z()) << "]\n"
         << "  C: [" << Num(s.C.x()) << ", " << Num(s.C.y()) << ", " << Num(s.C.z()) << "]\n"
         << "  scale: 1\n";
  }
  return WriteAtomically((fs::path(dir) / "truth.yaml").string(), yaml.str());
}

}  // namespace rigcal::drivers
