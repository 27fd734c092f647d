// SPDX-License-Identifier: Apache-2.0
// Thesis 5.6 / issue 4 section 5: the sewer rig of config/sim_sewer.yaml (two 186-degree
// fisheyes back to back, 35 cm apart, 6 m through a 60 cm pipe with rotations below 10 degrees)
// through the whole live pipeline (rendering -> VO per camera -> sync -> online estimator with
// its final window refinement), as `rigcal run --eval --fast`, for the config's seed and five
// others (each seed renders other textures and other noise). Target: rotation error <= 0.25 deg
// (thesis: 0.258 deg with the purely translational model). The rotations, small as they are,
// are far above the VO's rotation noise, so the general model must be chosen; the
// translational one is biased by (I - R_0) dC (31 deg on these poses), and no decalibration
// may be reported. Slow (label eval): `ctest -L eval -R calib/sewer -V` prints the figures.

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>

#include "rigcal/calib/rig_estimator.h"
#include "rigcal/io/rig_config.h"
#include "rigcal/pipeline/pipeline.h"
#include "rigcal/pipeline/run_evaluation.h"
#include "rigcal/sim/simulated_rig.h"

namespace rigcal {
namespace {

constexpr double kTargetRotDeg = 0.25;

struct SewerRun {
  bool ok = false;
  double rot_deg = 0.0;
  MotionModel model = MotionModel::kAuto;
  uint32_t flags = 0;
  SlaveState state = SlaveState::kInitialising;
  int decalibration_events = 0;
  std::string message;
};

SewerRun RunSewer(uint64_t seed) {
  SewerRun out;
  auto config = io::LoadRigConfig(std::string(RIGCAL_SOURCE_DIR) + "/config/sim_sewer.yaml");
  EXPECT_TRUE(config) << config.error();
  if (!config || !config->simulated_source) return out;
  sim::SimulatedRigSpec spec = *config->simulated_source;
  spec.realtime = false;
  if (seed != 0) spec.seed = seed;
  auto rig = sim::MakeSimulatedRig(spec);
  EXPECT_TRUE(rig) << rig.error();
  if (!rig) return out;
  pipeline::PipelineOptions options;
  options.lossless = true;
  options.record_poses = true;
  pipeline::Pipeline pipeline(config->CameraNames(), rig->MakeDevices(), spec.cameras, config->online,
                           options);
  pipeline.Start();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(10);
  while (!pipeline.Finished() && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_TRUE(pipeline.Finished());
  pipeline.Stop();
  const pipeline::PipelineSnapshot s = pipeline.Snapshot();
  std::vector<std::vector<CameraPose>> poses;
  for (int i = 0; i < 2; ++i) poses.push_back(pipeline.RecordedPoses(i));
  auto evaluation = pipeline::EvaluateRun(*rig, poses, s.estimate.rig);
  EXPECT_TRUE(evaluation) << evaluation.error();
  if (!evaluation || evaluation->slaves.empty() || s.estimate.online.empty()) return out;
  const SlaveCalibration& slave = s.estimate.rig.slaves[0];
  out.ok = evaluation->slaves[0].usable;
  out.rot_deg = evaluation->slaves[0].error.rot_deg;
  out.model = slave.motion_model;
  out.flags = s.estimate.online[0].flags;
  out.state = s.estimate.rig.slaves[0].state;
  out.decalibration_events = s.estimate.online[0].decalibration_events;
  out.message = slave.message;
  return out;
}

TEST(SewerEval, RotationWithinTheThesisTargetOnEverySeed) {
  double sum_sq = 0.0;
  int runs = 0;
  for (uint64_t seed : {0u, 1u, 2u, 4u, 5u, 6u}) {  // 0: the config's own seed
    const SewerRun r = RunSewer(seed);
    std::printf("sewer seed %s: rotation %.3f deg, %s model, flags 0x%x, %d decalibrations\n",
                seed == 0 ? "config" : std::to_string(seed).c_str(), r.rot_deg,
                ToString(r.model).c_str(), r.flags, r.decalibration_events);
    ASSERT_TRUE(r.ok) << r.message;
    EXPECT_EQ(r.model, MotionModel::kGeneral) << r.message;
    EXPECT_FALSE(r.flags & kFlagTranslationalOnly) << r.message;
    EXPECT_NE(r.state, SlaveState::kDecalibrated) << r.message;
    EXPECT_EQ(r.decalibration_events, 0) << r.message;
    EXPECT_LE(r.rot_deg, kTargetRotDeg) << "seed " << seed << ": " << r.message;
    sum_sq += r.rot_deg * r.rot_deg;
    ++runs;
  }
  std::printf("sewer: RMS rotation error %.3f deg over %d seeds\n", std::sqrt(sum_sq / runs), runs);
}

}  // namespace
}  // namespace rigcal
