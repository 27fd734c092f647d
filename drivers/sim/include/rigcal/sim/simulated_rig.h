// SPDX-License-Identifier: Apache-2.0
#pragma once
// The simulated rig: N cameras rigidly mounted on a moving rig, rendering grey images of a
// textured 3D scene by ray casting through their camera models, with image noise, motion blur,
// dropped frames, timestamp jitter and camera failures. It behaves like a set of capture
// devices (one CameraDevice per camera) and knows the ground truth (rig motion and mounting).
// Deterministic for a seed: frame k of camera i is the same image whichever thread renders it
// and whenever.
//
// Frames of reference. The world is z-up (metres). The rig moves as its master camera does:
// the trajectory gives world_from_master (camera frame x right, y down, z forward), and camera
// i sits at master_from_camera[i] (the `truth` mounting of the rig config, master frame).
//
// What it simulates and the `source:` section of a rig config that describes it:
// SimulatedRigSpec (simulated_rig_spec.h).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "rigcal/base/status.h"
#include "rigcal/base/types.h"
#include "rigcal/capture/capture_device.h"
#include "rigcal/sim/simulated_ground_truth.h"
#include "rigcal/sim/simulated_rig_spec.h"

namespace rigcal::sim {

// The implementation of the renderer's texture kernels. kSimd: four-lane SIMD where the build
// has it (SSE2 on x86-64, NEON on ARM; see SimdRenderKernelName), else the scalar code.
// kScalar: portable C++ only. Both compute every pixel with the same operations in the same
// order, so they render the same images (bit for bit on x86-64; within one grey level where a
// compiler fuses multiply-adds in one of them). Devices render with kSimd.
enum class RenderKernel { kSimd, kScalar };
// What kSimd runs in this build: "SSE2", "NEON" or "scalar".
const char* SimdRenderKernelName();

namespace internal {
struct SimulatedRigData;
struct RigClock;
}  // namespace internal

// One camera of a simulated rig. Created by SimulatedRig::MakeDevice. Threads: one capture
// thread calls Grab; Interrupt may come from any thread (it wakes a Grab that waits for its
// capture time). The devices of a rig share its clock, which locks itself.
class SimulatedCamera final : public capture::CameraDevice {
 public:
  ~SimulatedCamera() override;

  const std::string& name() const override;
  double frame_rate_hz() const override;
  // Renders the next frame that is not dropped. Realtime: the first Grab of any device of the
  // rig starts the rig clock; the frame is returned at its capture time; a device more than one
  // frame period late skips the overdue frames (counted by late_skipped()), as a camera whose
  // driver buffer overflows does. After the configured failure time every call returns an
  // error.
  Expected<std::optional<capture::Frame>> Grab() override;
  void Interrupt() override;

  int camera() const { return camera_; }
  // Counters, for the Grab thread (or any thread after it has been joined):
  int64_t dropped() const { return dropped_; }            // frames dropped by drop_probability
  int64_t late_skipped() const { return late_skipped_; }  // realtime frames skipped while late

 private:
  friend class SimulatedRig;
  struct State;
  SimulatedCamera(std::shared_ptr<const internal::SimulatedRigData> data,
                  std::shared_ptr<internal::RigClock> clock, int camera);

  std::shared_ptr<const internal::SimulatedRigData> data_;
  std::shared_ptr<internal::RigClock> clock_;
  int camera_ = 0;
  int64_t next_frame_ = 0;
  int64_t dropped_ = 0;
  int64_t late_skipped_ = 0;
  bool failed_ = false;
  std::unique_ptr<State> state_;  // render buffers, interrupt flag
};

// A simulated rig: the immutable scene, trajectory and per-camera render tables, shared by its
// devices. Copying a SimulatedRig is cheap and shares the scene and the rig clock. All const
// methods are thread-safe.
class SimulatedRig {
 public:
  const SimulatedRigSpec& spec() const;
  int num_cameras() const;
  int64_t num_frames() const;
  double frame_rate_hz() const;

  // A capture device for camera `camera` (index in spec().names) that starts at frame 0, or
  // nullptr when `camera` is out of range. Each call makes an independent device; devices of
  // one rig share the rig clock.
  std::unique_ptr<SimulatedCamera> MakeDevice(int camera) const;
  // One device per camera, in camera order.
  std::vector<std::unique_ptr<capture::CameraDevice>> MakeDevices() const;

  // Realtime: starts the rig clock now (the first Grab does it otherwise); no effect later.
  void Start() const;
  // Realtime: starts the rig clock with frame 0 at `epoch_ns` (CLOCK_MONOTONIC, may lie in the
  // near future: the first Grab then waits for it), e.g. the first pulse of a trigger generator;
  // no effect once started.
  void StartAt(int64_t epoch_ns) const;
  // Realtime: starts the rig clock on `host_ns_since` (the host time of a time since frame 0,
  // asked at every frame: a trigger generator's clock, trigger::TickClock); no effect once
  // started.
  void StartOn(std::function<int64_t(int64_t since_frame0_ns)> host_ns_since) const;
  // Stamp of frame 0: spec().start_time_ns, or in realtime the clock's start (0 before).
  int64_t epoch_ns() const;
  // Nominal (jitter-free) stamp of frame k: epoch_ns() + round(k * 1e9 / frame_rate_hz), or on
  // the clock of StartOn.
  int64_t FrameTimeNs(int64_t k) const;
  // Stream time of frame k in seconds (frame 0 at 0): the time the image is rendered at.
  double FrameStreamTime(int64_t k) const;

  // Ground truth at stream time t_s (seconds since frame 0, clamped to the trajectory):
  // world_from_master, and world_from_camera of camera `camera`.
  Pose WorldFromMasterAt(double t_s) const;
  Pose WorldFromCameraAt(int camera, double t_s) const;
  // The true rig: per slave (camera 1..N-1), master_from_slave with scale 1 (every camera's
  // truth is metric).
  std::vector<Similarity> TrueRig() const;

  // Frame k of camera `camera` exactly as its device returns it (noise, blur; ignores drops,
  // jitter and failures). `kernel`: the texture kernels to render with. Thread-safe.
  cv::Mat RenderFrame(int camera, int64_t k, RenderKernel kernel = RenderKernel::kSimd) const;
  // A noise-free, blur-free image of camera `camera` at pose world_from_camera, of the static
  // scene (a view has no time, so no moving objects). `block`:
  // render_block to use (0 = the spec's). Thread-safe.
  cv::Mat RenderView(int camera, const Pose& world_from_camera, int block = 0,
                     RenderKernel kernel = RenderKernel::kSimd) const;
  // The moving objects (spec().scene.moving_objects) at stream time t_s: their world boxes
  // (axis-aligned, m), in a fixed order; empty without them.
  std::vector<Eigen::AlignedBox3d> MovingObjectsAt(double t_s) const;
  // Distance along the ray origin + t * direction (world, direction need not be unit: t is in
  // units of |direction|) to the first surface of the static scene (moving objects are not
  // cast against), or nullopt (sky). Double precision.
  std::optional<double> CastRay(const Eigen::Vector3d& origin,
                                const Eigen::Vector3d& direction) const;

  // The ground truth of the simulated drive: every camera's mounting (scale 1) and its poses at
  // every nominal frame stamp FrameTimeNs(k), in the world and in its own reference frame
  // (simulated_ground_truth.h); rigcal_io writes it as files (WriteGroundTruth). In realtime
  // mode the stamps match the devices' stamps only once the rig clock has started (take the
  // truth after the run; before, stamps count from 0).
  SimulatedGroundTruth GroundTruth() const;

 private:
  friend Expected<SimulatedRig> MakeSimulatedRig(SimulatedRigSpec spec);
  SimulatedRig() = default;
  std::shared_ptr<const internal::SimulatedRigData> data_;
  std::shared_ptr<internal::RigClock> clock_;
};

// Checks the spec (SimulatedRigSpec::Check), builds the scene and its textures, precomputes the
// per-pixel bearings of every camera and checks the free space along the trajectory. Errors
// name the field, or the camera and time that leave the free space. Takes some 100 ms - 1 s.
Expected<SimulatedRig> MakeSimulatedRig(SimulatedRigSpec spec);

}  // namespace rigcal::sim
