// SPDX-License-Identifier: Apache-2.0
// Cost of the simulated rig's renderer per frame: a 752x480 pinhole camera in the room, a
// 640x640 fisheye in the room and in the pipe, each with one ray per 4x4 block and with exact
// ray casting per pixel (render_block 1), image noise on. Times are the CPU time of the
// rendering thread, so the figure holds on a busy machine too.
//
//   build/tests/bench/rigcal_calib_bench --benchmark_filter=RenderFrame

#include <benchmark/benchmark.h>

#include <cmath>
#include <ctime>

#include "rigcal/sim/simulated_rig.h"
#include "support/ideal_cameras.h"

namespace {

using rigcal::Pose;
using rigcal::sim::SimulatedRigSpec;

double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

Pose Mounting(const Eigen::Quaterniond& q, const Eigen::Vector3d& c) {
  Pose p;
  p.q = q;
  p.C = c;
  return p;
}

SimulatedRigSpec::Waypoint Waypoint(const Eigen::Vector3d& p, double yaw, double pitch = 0,
                                    double roll = 0) {
  SimulatedRigSpec::Waypoint w;
  w.position = p;
  w.world_from_master = rigcal::sim::WaypointOrientationFromYpr(yaw, pitch, roll);
  return w;
}

// The two-camera rig of tests/sim/simulated_rig_test.cc: a master and a slave looking right,
// moving and turning gently in the default room.
SimulatedRigSpec RoomSpec(int width, int height) {
  SimulatedRigSpec spec;
  spec.names = {"cam0", "cam1"};
  spec.cameras = {rigcal::support::PinholeWithFov(width, height, 60),
                  rigcal::support::PinholeWithFov(width, height, 60)};
  spec.master_from_camera = {
      Pose(), Mounting(Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY())),
                       Eigen::Vector3d(-0.5, 0, 0))};
  spec.waypoints = {Waypoint({-2, 0, 3}, 0), Waypoint({0, 1, 3.2}, 20, 10, -5),
                    Waypoint({2, 0, 2.8}, -15, -5, 10), Waypoint({0, -1, 3}, 30)};
  spec.waypoint_interval_s = 2.0;
  spec.frame_rate_hz = 20;
  spec.noise_sigma = 2;
  spec.seed = 7;
  return spec;
}

SimulatedRigSpec FisheyeSpec() {
  SimulatedRigSpec spec = RoomSpec(160, 120);
  spec.cameras = {rigcal::support::IdealEquidistant(640, 640, 191.0, 93.0),
                  rigcal::support::IdealEquidistant(640, 640, 191.0, 93.0)};
  return spec;
}

SimulatedRigSpec PipeSpec() {
  SimulatedRigSpec spec = FisheyeSpec();
  spec.scene.type = SimulatedRigSpec::SceneType::kPipe;
  spec.master_from_camera[1] =
      Mounting(Eigen::Quaterniond(0, 0, 1, 0), Eigen::Vector3d(0, 0, -0.35));
  spec.waypoints = {Waypoint({1, 0, 0}, 0), Waypoint({2, 0.02, 0.01}, 3, 2, 1),
                    Waypoint({3, 0, 0}, 0), Waypoint({4, 0, 0}, 0)};
  return spec;
}

// One iteration renders one frame, alternating the cameras; state.range(0) is render_block.
void RenderFrames(benchmark::State& state, SimulatedRigSpec spec) {
  spec.render_block = static_cast<int>(state.range(0));
  auto rig = rigcal::sim::MakeSimulatedRig(std::move(spec));
  if (!rig) {
    state.SkipWithError(rig.error().c_str());
    return;
  }
  int64_t k = 0;
  for (auto _ : state) {
    const double start = ThreadCpuSeconds();
    cv::Mat image = rig->RenderFrame(static_cast<int>(k % 2), k * 2);
    state.SetIterationTime(ThreadCpuSeconds() - start);
    benchmark::DoNotOptimize(image.data);
    ++k;
  }
}

void BM_RenderFramePinhole752x480Room(benchmark::State& state) {
  RenderFrames(state, RoomSpec(752, 480));
}
void BM_RenderFrameFisheye640Room(benchmark::State& state) { RenderFrames(state, FisheyeSpec()); }
void BM_RenderFrameFisheye640Pipe(benchmark::State& state) { RenderFrames(state, PipeSpec()); }

BENCHMARK(BM_RenderFramePinhole752x480Room)
    ->Arg(4)
    ->Arg(1)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RenderFrameFisheye640Room)
    ->Arg(4)
    ->Arg(1)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RenderFrameFisheye640Pipe)
    ->Arg(4)
    ->Arg(1)
    ->UseManualTime()
    ->Unit(benchmark::kMillisecond);

}  // namespace
