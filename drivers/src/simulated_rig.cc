#include "rigcal/drivers/simulated_rig.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <set>
#include <sstream>

#include "rigcal/calib/logging.h"
#include "rigcal/calib/thread_annotations.h"
#include "sim_random.h"
#include "sim_scene.h"
#include "sim_trajectory.h"

namespace rigcal::drivers {
namespace internal {

constexpr size_t kNoiseTableSize = 1 << 18;

struct SimulatedRigData {
  SimulatedRigSpec spec;
  int64_t num_frames = 0;
  Trajectory trajectory;
  Scene scene;
  std::vector<CameraTables> cameras;
  std::vector<NodeGrid> grids;  // per camera, for spec.render_block (unused when 1)
  std::vector<float> noise;     // standard normal samples
  std::vector<std::optional<double>> fail_after_s;  // per camera

  double StreamTime(int64_t k) const { return static_cast<double>(k) / spec.frame_rate_hz; }
  int64_t OffsetNs(int64_t k) const {
    return std::llround(static_cast<double>(k) * 1e9 / spec.frame_rate_hz);
  }
  Pose CameraPose(int camera, double t_s) const {
    return trajectory.At(t_s) * spec.master_from_camera[camera];
  }
  bool Dropped(int camera, int64_t k) const {
    if (spec.drop_probability <= 0.0) return false;
    Rng rng(
        HashKey(spec.seed, kPurposeDrop, static_cast<uint64_t>(camera), static_cast<uint64_t>(k)));
    return rng.Uniform() < spec.drop_probability;
  }
  int64_t JitterNs(int camera, int64_t k) const {
    if (spec.timestamp_jitter_s <= 0.0) return 0;
    Rng rng(HashKey(spec.seed, kPurposeJitter, static_cast<uint64_t>(camera),
                    static_cast<uint64_t>(k)));
    const double z = std::clamp(rng.Gaussian(), -3.0, 3.0);
    return std::llround(z * spec.timestamp_jitter_s * 1e9);
  }

  // Frame k of `camera`: renders (with motion blur), adds noise, quantises.
  cv::Mat Render(int camera, int64_t k, std::vector<float>* acc, std::vector<Hit>* hits) const {
    const CameraTables& tables = cameras[camera];
    const NodeGrid* grid = spec.render_block >= 2 ? &grids[camera] : nullptr;
    acc->assign(static_cast<size_t>(tables.width) * tables.height, 0.f);
    const double t = StreamTime(k);
    if (spec.blur_exposure_s > 0.0) {
      const int samples = spec.blur_samples;
      const float weight = 1.f / static_cast<float>(samples);
      for (int s = 0; s < samples; ++s) {
        const double ts = t + spec.blur_exposure_s * ((s + 0.5) / samples - 0.5);
        RenderAccumulate(scene, tables, grid, CameraPose(camera, ts), weight, acc->data(), hits);
      }
    } else {
      RenderAccumulate(scene, tables, grid, CameraPose(camera, t), 1.f, acc->data(), hits);
    }
    return Quantise(camera, k, *acc, tables.width, tables.height);
  }

  cv::Mat Quantise(int camera, int64_t k, const std::vector<float>& acc, int width,
                   int height) const {
    cv::Mat image(height, width, CV_8UC1);
    const auto sigma = static_cast<float>(spec.noise_sigma);
    Rng rng(
        HashKey(spec.seed, kPurposeNoise, static_cast<uint64_t>(camera), static_cast<uint64_t>(k)));
    for (int y = 0; y < height; ++y) {
      const float* in = acc.data() + static_cast<size_t>(y) * width;
      uint8_t* out = image.ptr<uint8_t>(y);
      // Rounds and saturates (a loop the compiler vectorises).
      if (sigma > 0.f) {
        const float* n = noise.data() + rng.Below(static_cast<uint32_t>(noise.size() - width));
        for (int x = 0; x < width; ++x) {
          const float v = std::min(std::max(in[x] + sigma * n[x] + 0.5f, 0.f), 255.f);
          out[x] = static_cast<uint8_t>(static_cast<int>(v));
        }
      } else {
        for (int x = 0; x < width; ++x) {
          const float v = std::min(std::max(in[x] + 0.5f, 0.f), 255.f);
          out[x] = static_cast<uint8_t>(static_cast<int>(v));
        }
      }
    }
    return image;
  }
};

int64_t MonotonicNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// The shared time base of a realtime rig: CLOCK_MONOTONIC (std::chrono::steady_clock on
// Linux) at the first Grab of any of its devices, whose capture threads share it.
struct RigClock {
  Mutex mutex;
  bool started RIGCAL_GUARDED_BY(mutex) = false;
  int64_t epoch_ns RIGCAL_GUARDED_BY(mutex) = 0;

  int64_t StartOnce() RIGCAL_EXCLUDES(mutex) {
    MutexLock lock(mutex);
    if (!started) {
      started = true;
      epoch_ns = MonotonicNs();
    }
    return epoch_ns;
  }
  int64_t Epoch() RIGCAL_EXCLUDES(mutex) {
    MutexLock lock(mutex);
    return epoch_ns;
  }
};

}  // namespace internal

namespace {

using internal::MonotonicNs;

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
std::string WriteAtomically(const std::string& path, const std::string& contents) {
  static std::atomic<int> counter{0};
  const std::string tmp =
      path + ".tmp." + std::to_string(::getpid()) + "." + std::to_string(counter.fetch_add(1));
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return path + ": cannot create temporary file: " + std::strerror(errno);
  size_t written = 0;
  while (written < contents.size()) {
    const ssize_t n = ::write(fd, contents.data() + written, contents.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string error = path + ": write failed: " + std::strerror(errno);
      ::close(fd);
      ::unlink(tmp.c_str());
      return error;
    }
    written += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) {
    const std::string error = path + ": fsync/close failed: " + std::strerror(errno);
    ::unlink(tmp.c_str());
    return error;
  }
  if (::rename(tmp.c_str(), path.c_str()) != 0) {
    const std::string error = path + ": rename failed: " + std::strerror(errno);
    ::unlink(tmp.c_str());
    return error;
  }
  return {};
}

double TrajectoryDuration(const SimulatedRigSpec& spec) {
  if (!spec.waypoints.empty()) {
    return static_cast<double>(spec.waypoints.size() - 1) * spec.waypoint_interval_s;
  }
  if (spec.trajectory_t_ns.size() >= 2) {
    return static_cast<double>(spec.trajectory_t_ns.back() - spec.trajectory_t_ns.front()) * 1e-9;
  }
  return 0.0;
}

int64_t NumFrames(const SimulatedRigSpec& spec) {
  if (spec.num_frames > 0) return spec.num_frames;
  if (spec.duration_s > 0) return std::llround(spec.duration_s * spec.frame_rate_hz);
  return static_cast<int64_t>(std::floor(TrajectoryDuration(spec) * spec.frame_rate_hz + 1e-6)) + 1;
}

bool IsUnit(const Eigen::Quaterniond& q) {
  return q.coeffs().allFinite() && std::abs(q.norm() - 1.0) <= 1e-6;
}

}  // namespace

std::string ToString(SimulatedRigSpec::SceneType type) {
  switch (type) {
    case SimulatedRigSpec::SceneType::kRoom:
      return "room";
    case SimulatedRigSpec::SceneType::kYard:
      return "yard";
    case SimulatedRigSpec::SceneType::kStreet:
      return "street";
    case SimulatedRigSpec::SceneType::kPipe:
      return "pipe";
  }
  return "?";
}

std::optional<SimulatedRigSpec::SceneType> SceneTypeFromString(const std::string& name) {
  for (auto type : {SimulatedRigSpec::SceneType::kRoom, SimulatedRigSpec::SceneType::kYard,
                    SimulatedRigSpec::SceneType::kStreet, SimulatedRigSpec::SceneType::kPipe}) {
    if (ToString(type) == name) return type;
  }
  return std::nullopt;
}

Eigen::Quaterniond WaypointOrientationFromYpr(double yaw_deg, double pitch_deg, double roll_deg) {
  constexpr double kDeg = M_PI / 180.0;
  // Level camera looking along +x: camera z -> world x, camera x -> world -y, camera y ->
  // world -z.
  Eigen::Matrix3d level;
  level << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  const Eigen::Matrix3d r = (Eigen::AngleAxisd(yaw_deg * kDeg, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(pitch_deg * kDeg, Eigen::Vector3d::UnitY()) *
                             Eigen::AngleAxisd(roll_deg * kDeg, Eigen::Vector3d::UnitX()))
                                .toRotationMatrix() *
                            level;
  return Eigen::Quaterniond(r).normalized();
}

Eigen::Vector3d SimulatedRigSpec::SceneSize() const {
  if (scene.size.x() > 0 && scene.size.y() > 0 && scene.size.z() > 0) return scene.size;
  switch (scene.type) {
    case SceneType::kYard:
      return {60, 60, 8};
    case SceneType::kStreet:
      return {200, 16, 10};
    case SceneType::kRoom:
    case SceneType::kPipe:
      break;
  }
  return {20, 16, 6};
}

double SimulatedRigSpec::TexelSize() const {
  if (scene.texel_m > 0) return scene.texel_m;
  switch (scene.type) {
    case SceneType::kPipe:
      return 0.002;
    case SceneType::kYard:
    case SceneType::kStreet:
      return 0.02;
    case SceneType::kRoom:
      break;
  }
  return 0.01;
}

bool SimulatedRigSpec::Check(std::string* error) const {
  std::ostringstream e;
  auto fail = [&]() {
    if (error) *error = e.str();
    return false;
  };
  // Cameras.
  if (names.empty()) {
    e << "names: no cameras";
    return fail();
  }
  if (cameras.size() != names.size() || master_from_camera.size() != names.size()) {
    e << "cameras: " << names.size() << " names, " << cameras.size() << " camera models and "
      << master_from_camera.size() << " mountings; need one of each per camera";
    return fail();
  }
  std::set<std::string> unique;
  for (size_t i = 0; i < names.size(); ++i) {
    if (names[i].empty() || !unique.insert(names[i]).second) {
      e << "names[" << i << "]: empty or duplicate camera name '" << names[i] << "'";
      return fail();
    }
    if (!cameras[i]) {
      e << names[i] << ": no camera model";
      return fail();
    }
    if (cameras[i]->width() < 8 || cameras[i]->height() < 8 || cameras[i]->width() > 8192 ||
        cameras[i]->height() > 8192) {
      e << names[i] << ": resolution " << cameras[i]->width() << " x " << cameras[i]->height()
        << " outside [8, 8192]";
      return fail();
    }
    const Pose& m = master_from_camera[i];
    if (!IsUnit(m.q) || !m.C.allFinite()) {
      e << names[i] << ".truth: mounting must have a unit quaternion and a finite centre";
      return fail();
    }
  }
  if (Eigen::AngleAxisd(master_from_camera[0].q).angle() > 1e-9 ||
      master_from_camera[0].C.norm() > 1e-12) {
    e << names[0] << ".truth: the master defines the rig frame; its mounting must be the identity";
    return fail();
  }
  // Timing.
  if (!(frame_rate_hz > 0 && frame_rate_hz <= 1000)) {
    e << "frame_rate_hz: " << frame_rate_hz << " outside (0, 1000]";
    return fail();
  }
  if (num_frames < 0 || !(duration_s >= 0)) {
    e << "num_frames/duration_s: must not be negative";
    return fail();
  }
  if (num_frames > 0 && duration_s > 0) {
    e << "num_frames, duration_s: give at most one of them";
    return fail();
  }
  // Trajectory.
  const bool has_file = !trajectory_t_ns.empty() || !trajectory_poses.empty();
  if (waypoints.empty() == !has_file) {
    e << "trajectory: give either waypoints or a trajectory file";
    return fail();
  }
  if (!waypoints.empty()) {
    if (waypoints.size() < 2) {
      e << "trajectory.waypoints: need at least 2 waypoints, got " << waypoints.size();
      return fail();
    }
    if (!(waypoint_interval_s > 0 && std::isfinite(waypoint_interval_s))) {
      e << "trajectory.waypoint_interval_s: must be > 0";
      return fail();
    }
    for (size_t i = 0; i < waypoints.size(); ++i) {
      if (!waypoints[i].position.allFinite() || !IsUnit(waypoints[i].world_from_master)) {
        e << "trajectory.waypoints[" << i << "]: position must be finite, orientation unit";
        return fail();
      }
    }
  } else {
    if (trajectory_t_ns.size() != trajectory_poses.size() || trajectory_t_ns.size() < 2) {
      e << "trajectory.file: need at least 2 poses with one stamp each, got "
        << trajectory_poses.size() << " poses and " << trajectory_t_ns.size() << " stamps";
      return fail();
    }
    for (size_t i = 1; i < trajectory_t_ns.size(); ++i) {
      if (trajectory_t_ns[i] <= trajectory_t_ns[i - 1]) {
        e << "trajectory.file: stamps must increase strictly (pose " << i << ")";
        return fail();
      }
    }
    if (!IsUnit(body_from_master.q) || !body_from_master.C.allFinite()) {
      e << "trajectory.body_from_master: needs a unit quaternion and a finite centre";
      return fail();
    }
  }
  const int64_t frames = NumFrames(*this);
  const double duration = TrajectoryDuration(*this);
  const double last = static_cast<double>(frames - 1) / frame_rate_hz;
  if (frames < 1) {
    e << "num_frames: no frames";
    return fail();
  }
  if (last > duration + 1e-6) {
    e << (num_frames > 0 ? "num_frames" : "duration_s") << ": " << frames << " frames at "
      << frame_rate_hz << " Hz last " << last << " s, longer than the trajectory (" << duration
      << " s)";
    return fail();
  }
  // Scene.
  if (scene.type != SceneType::kPipe) {
    const Eigen::Vector3d size = SceneSize();
    if (!(size.minCoeff() > 0) || !size.allFinite() || size.maxCoeff() > 100000) {
      e << "scene.size: every extent must be in (0, 100000] m";
      return fail();
    }
  }
  if (scene.boxes < 0 || scene.boxes > 64) {
    e << "scene.boxes: " << scene.boxes << " outside [0, 64]";
    return fail();
  }
  if (!(scene.pipe_diameter > 0 && scene.pipe_diameter <= 1000)) {
    e << "scene.diameter: must be in (0, 1000] m";
    return fail();
  }
  if (!(scene.pipe_length > 0 && scene.pipe_length <= 100000)) {
    e << "scene.length: must be in (0, 100000] m";
    return fail();
  }
  if (!(scene.texel_m >= 0 && scene.texel_m <= 10)) {
    e << "scene.texel_m: must be in (0, 10] m";
    return fail();
  }
  // Imaging and device behaviour.
  const double period = 1.0 / frame_rate_hz;
  if (!(noise_sigma >= 0 && noise_sigma <= 100)) {
    e << "noise_sigma: " << noise_sigma << " outside [0, 100]";
    return fail();
  }
  if (!(blur_exposure_s >= 0 && blur_exposure_s < period)) {
    e << "motion_blur.exposure_ms: " << blur_exposure_s * 1e3
      << " must be >= 0 and shorter than the frame period (" << period * 1e3 << " ms)";
    return fail();
  }
  if (blur_exposure_s > 0 && (blur_samples < 2 || blur_samples > 32)) {
    e << "motion_blur.samples: " << blur_samples << " outside [2, 32]";
    return fail();
  }
  if (!(drop_probability >= 0 && drop_probability < 1)) {
    e << "drop_probability: " << drop_probability << " outside [0, 1)";
    return fail();
  }
  if (!(timestamp_jitter_s >= 0 && 3 * timestamp_jitter_s < 0.5 * period)) {
    e << "timestamp_jitter_ms: " << timestamp_jitter_s * 1e3
      << " must be >= 0 with 3 sigma below half a frame period (" << period * 0.5e3 << " ms)";
    return fail();
  }
  for (const auto& [name, t] : fail_after_s) {
    if (unique.count(name) == 0) {
      e << "fail_after_s." << name << ": no camera of that name";
      return fail();
    }
    if (!(t >= 0 && std::isfinite(t))) {
      e << "fail_after_s." << name << ": must be >= 0 s";
      return fail();
    }
  }
  if (render_block < 1 || render_block > 32) {
    e << "render_block: " << render_block << " outside [1, 32]";
    return fail();
  }
  if (error) error->clear();
  return true;
}

// ---------------------------------------------------------------------------------------------
// SimulatedCamera

// The interrupt flag (Interrupt on any thread, Grab on the capture thread) and the capture
// thread's render buffers.
struct SimulatedCamera::State {
  Mutex mutex;
  std::condition_variable cv;  // signalled by Interrupt
  bool interrupted RIGCAL_GUARDED_BY(mutex) = false;
  std::vector<float> acc;           // the capture thread's
  std::vector<internal::Hit> hits;  // the capture thread's
};

SimulatedCamera::SimulatedCamera(std::shared_ptr<const internal::SimulatedRigData> data,
                                 std::shared_ptr<internal::RigClock> clock, int camera)
    : data_(std::move(data)),
      clock_(std::move(clock)),
      camera_(camera),
      state_(std::make_unique<State>()) {}

SimulatedCamera::~SimulatedCamera() = default;

const std::string& SimulatedCamera::name() const { return data_->spec.names[camera_]; }

double SimulatedCamera::frame_rate_hz() const { return data_->spec.frame_rate_hz; }

void SimulatedCamera::Interrupt() {
  {
    MutexLock lock(state_->mutex);
    state_->interrupted = true;
  }
  state_->cv.notify_all();
}

Expected<std::optional<Frame>> SimulatedCamera::Grab() {
  const internal::SimulatedRigData& d = *data_;
  const SimulatedRigSpec& spec = d.spec;
  // Waits until CLOCK_MONOTONIC reaches t_ns; false when interrupted.
  auto wait_until = [this](int64_t t_ns) {
    MutexLock lock(state_->mutex);
    const auto deadline = std::chrono::steady_clock::time_point(std::chrono::nanoseconds(t_ns));
    while (!state_->interrupted) {
      if (lock.WaitUntil(state_->cv, deadline) == std::cv_status::timeout) break;
    }
    return !state_->interrupted;
  };
  {
    MutexLock lock(state_->mutex);
    if (state_->interrupted) return std::optional<Frame>();
  }
  const std::optional<double> fail_after = d.fail_after_s[camera_];
  auto failure = [&]() {
    std::ostringstream msg;
    msg << name() << ": simulated camera failure at stream time " << *fail_after
        << " s (source.fail_after_s)";
    return Error{msg.str()};
  };
  if (failed_) return failure();
  const int64_t epoch = spec.realtime ? clock_->StartOnce() : spec.start_time_ns;
  const int64_t period_ns = std::llround(1e9 / spec.frame_rate_hz);
  while (next_frame_ < d.num_frames) {
    int64_t k = next_frame_;
    if (spec.realtime) {
      const int64_t late = MonotonicNs() - (epoch + d.OffsetNs(k));
      if (late > period_ns) {
        // The frames that were due meanwhile are gone, as from an overflowing driver buffer.
        const int64_t newest = std::min<int64_t>(
            d.num_frames,
            static_cast<int64_t>(std::floor(static_cast<double>(MonotonicNs() - epoch) * 1e-9 *
                                            spec.frame_rate_hz)));
        if (newest > k) {
          late_skipped_ += newest - k;
          if (late_skipped_ == newest - k || late_skipped_ % 100 == 0) {
            ModuleLogger("drivers")->warn("{}: rendering fell behind real time; {} frames skipped",
                                          name(), late_skipped_);
          }
          k = next_frame_ = newest;
          if (k >= d.num_frames) break;
        }
      }
    }
    if (fail_after && d.StreamTime(k) >= *fail_after) {
      if (spec.realtime && !wait_until(epoch + d.OffsetNs(k))) return std::optional<Frame>();
      failed_ = true;
      ModuleLogger("drivers")->warn("{}: simulated failure at stream time {} s", name(),
                                    *fail_after);
      return failure();
    }
    ++next_frame_;
    if (d.Dropped(camera_, k)) {
      ++dropped_;
      continue;
    }
    Frame frame;
    frame.camera = camera_;
    frame.seq = k;
    frame.t_ns = epoch + d.OffsetNs(k) + d.JitterNs(camera_, k);
    frame.image = d.Render(camera_, k, &state_->acc, &state_->hits);
    if (spec.realtime && !wait_until(epoch + d.OffsetNs(k))) return std::optional<Frame>();
    return std::optional<Frame>(std::move(frame));
  }
  return std::optional<Frame>();
}

// ---------------------------------------------------------------------------------------------
// SimulatedRig

const SimulatedRigSpec& SimulatedRig::spec() const { return data_->spec; }
int SimulatedRig::num_cameras() const { return static_cast<int>(data_->spec.names.size()); }
int64_t SimulatedRig::num_frames() const { return data_->num_frames; }
double SimulatedRig::frame_rate_hz() const { return data_->spec.frame_rate_hz; }

std::unique_ptr<SimulatedCamera> SimulatedRig::MakeDevice(int camera) const {
  if (camera < 0 || camera >= num_cameras()) return nullptr;
  return std::unique_ptr<SimulatedCamera>(new SimulatedCamera(data_, clock_, camera));
}

std::vector<std::unique_ptr<CameraDevice>> SimulatedRig::MakeDevices() const {
  std::vector<std::unique_ptr<CameraDevice>> devices;
  for (int i = 0; i < num_cameras(); ++i) devices.push_back(MakeDevice(i));
  return devices;
}

void SimulatedRig::Start() const {
  if (data_->spec.realtime) clock_->StartOnce();
}

int64_t SimulatedRig::epoch_ns() const {
  return data_->spec.realtime ? clock_->Epoch() : data_->spec.start_time_ns;
}

int64_t SimulatedRig::FrameTimeNs(int64_t k) const { return epoch_ns() + data_->OffsetNs(k); }

double SimulatedRig::FrameStreamTime(int64_t k) const { return data_->StreamTime(k); }

Pose SimulatedRig::MasterPoseAt(double t_s) const { return data_->trajectory.At(t_s); }

Pose SimulatedRig::CameraPoseAt(int camera, double t_s) const {
  return data_->CameraPose(camera, t_s);
}

std::vector<Similarity> SimulatedRig::TrueRig() const {
  std::vector<Similarity> rig;
  for (size_t i = 1; i < data_->spec.master_from_camera.size(); ++i) {
    Similarity s;
    s.q = data_->spec.master_from_camera[i].q;
    s.C = data_->spec.master_from_camera[i].C;
    s.scale = 1.0;
    rig.push_back(s);
  }
  return rig;
}

cv::Mat SimulatedRig::RenderFrame(int camera, int64_t k) const {
  std::vector<float> acc;
  std::vector<internal::Hit> hits;
  return data_->Render(camera, k, &acc, &hits);
}

cv::Mat SimulatedRig::RenderView(int camera, const Pose& world_from_camera, int block) const {
  const internal::CameraTables& tables = data_->cameras[camera];
  if (block <= 0) block = data_->spec.render_block;
  std::optional<internal::NodeGrid> own_grid;
  const internal::NodeGrid* grid = nullptr;
  if (block >= 2) {
    if (block == data_->spec.render_block) {
      grid = &data_->grids[camera];
    } else {
      own_grid = internal::MakeNodeGrid(tables, block);
      grid = &*own_grid;
    }
  }
  std::vector<float> acc(static_cast<size_t>(tables.width) * tables.height, 0.f);
  std::vector<internal::Hit> hits;
  internal::RenderAccumulate(data_->scene, tables, grid, world_from_camera, 1.f, acc.data(), &hits);
  cv::Mat image(tables.height, tables.width, CV_8UC1);
  for (int y = 0; y < tables.height; ++y) {
    for (int x = 0; x < tables.width; ++x) {
      image.at<uint8_t>(y, x) =
          cv::saturate_cast<uint8_t>(acc[static_cast<size_t>(y) * tables.width + x]);
    }
  }
  return image;
}

std::optional<double> SimulatedRig::CastRay(const Eigen::Vector3d& origin,
                                            const Eigen::Vector3d& direction) const {
  return data_->scene.Distance(origin, direction);
}

std::string SimulatedRig::WriteGroundTruth(const std::string& dir) const {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return dir + ": cannot create directory: " + ec.message();
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
    if (std::string e = WriteAtomically(base + ".txt", local.str()); !e.empty()) return e;
    const std::string world_path = (fs::path(dir) / ("world_" + spec.names[c] + ".txt")).string();
    if (std::string e = WriteAtomically(world_path, world.str()); !e.empty()) return e;
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

Expected<SimulatedRig> MakeSimulatedRig(SimulatedRigSpec spec) {
  std::string error;
  if (!spec.Check(&error)) return Error{error};
  const auto start = std::chrono::steady_clock::now();
  for (Pose& m : spec.master_from_camera) m.q.normalize();
  for (auto& w : spec.waypoints) w.world_from_master.normalize();
  auto data = std::make_shared<internal::SimulatedRigData>();
  data->num_frames = NumFrames(spec);
  if (!spec.waypoints.empty()) {
    std::vector<Pose> waypoints;
    for (const auto& w : spec.waypoints) {
      Pose p;
      p.q = w.world_from_master;
      p.C = w.position;
      waypoints.push_back(p);
    }
    data->trajectory = internal::Trajectory::FromWaypoints(waypoints, spec.waypoint_interval_s);
  } else {
    for (Pose& p : spec.trajectory_poses) p.q.normalize();
    spec.body_from_master.q.normalize();
    data->trajectory = internal::Trajectory::FromSamples(
        spec.trajectory_t_ns, spec.trajectory_poses, spec.body_from_master);
  }
  data->fail_after_s.assign(spec.names.size(), std::nullopt);
  for (size_t i = 0; i < spec.names.size(); ++i) {
    const auto it = spec.fail_after_s.find(spec.names[i]);
    if (it != spec.fail_after_s.end()) data->fail_after_s[i] = it->second;
  }
  data->spec = std::move(spec);
  const SimulatedRigSpec& s = data->spec;
  data->scene = internal::Scene::Build(s);

  // Every camera must stay in free space.
  for (int64_t k = 0; k < data->num_frames; ++k) {
    for (size_t c = 0; c < s.names.size(); ++c) {
      const Eigen::Vector3d p = data->CameraPose(static_cast<int>(c), data->StreamTime(k)).C;
      const std::string where = data->scene.CheckFree(p, kMinClearance);
      if (!where.empty()) {
        std::ostringstream msg;
        msg << "trajectory: camera " << s.names[c] << " at stream time " << data->StreamTime(k)
            << " s (frame " << k << ") is at (" << p.x() << ", " << p.y() << ", " << p.z()
            << ") and " << where;
        return Error{msg.str()};
      }
    }
  }

  for (size_t c = 0; c < s.cameras.size(); ++c) {
    data->cameras.push_back(internal::MakeCameraTables(s.cameras[c]));
    data->grids.push_back(s.render_block >= 2
                              ? internal::MakeNodeGrid(data->cameras.back(), s.render_block)
                              : internal::NodeGrid{});
  }
  internal::Rng noise_rng(internal::HashKey(s.seed, internal::kPurposeNoiseTable));
  data->noise.resize(internal::kNoiseTableSize);
  for (float& n : data->noise) n = static_cast<float>(noise_rng.Gaussian());

  const double build_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  ModuleLogger("drivers")->info(
      "simulated rig: {} cameras, {} frames at {} Hz, {}; textures {:.1f} MB; built in {:.0f} ms",
      s.names.size(), data->num_frames, s.frame_rate_hz, data->scene.Describe(),
      static_cast<double>(data->scene.TextureBytes()) / 1e6, build_ms);

  SimulatedRig rig;
  rig.data_ = std::move(data);
  rig.clock_ = std::make_shared<internal::RigClock>();
  return rig;
}

}  // namespace rigcal::drivers
