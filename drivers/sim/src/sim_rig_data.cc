// SPDX-License-Identifier: Apache-2.0
// Frame production of the simulated rig: motion blur, rolling shutter, image noise, quantisation,
// drops and stamp jitter, all deterministic per (seed, camera, frame).
#include "sim_rig_data.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "sim_random.h"

namespace rigcal::sim::internal {

bool SimulatedRigData::Dropped(int camera, int64_t k) const {
  if (spec.drop_probability <= 0.0) return false;
  Rng rng(
      HashKey(spec.seed, kPurposeDrop, static_cast<uint64_t>(camera), static_cast<uint64_t>(k)));
  return rng.Uniform() < spec.drop_probability;
}
bool SimulatedRigData::Blackout(int camera, int64_t k) const {
  if (spec.blackout_s.empty()) return false;
  const auto it = spec.blackout_s.find(spec.names[static_cast<size_t>(camera)]);
  const double t = StreamTime(k);
  return it != spec.blackout_s.end() && t >= it->second.first && t < it->second.second;
}
bool SimulatedRigData::BlurBurst(int camera, int64_t k) const {
  if (spec.blur_burst_s.empty()) return false;
  const auto it = spec.blur_burst_s.find(spec.names[static_cast<size_t>(camera)]);
  const double t = StreamTime(k);
  return it != spec.blur_burst_s.end() && t >= it->second.first && t < it->second.second;
}
int64_t SimulatedRigData::JitterNs(int camera, int64_t k) const {
  if (spec.timestamp_jitter_s <= 0.0) return 0;
  Rng rng(
      HashKey(spec.seed, kPurposeJitter, static_cast<uint64_t>(camera), static_cast<uint64_t>(k)));
  const double z = std::clamp(rng.Gaussian(), -3.0, 3.0);
  return std::llround(z * spec.timestamp_jitter_s * 1e9);
}

double SimulatedRigData::RowDelay(int camera, int row) const {
  if (spec.rolling_shutter_s <= 0.0) return 0.0;
  const int last_row = std::max(1, cameras[camera].height - 1);
  return spec.rolling_shutter_s * static_cast<double>(row) / last_row;
}

void SimulatedRigData::RenderAt(int camera, double t_s, float weight, std::vector<float>* acc,
                                std::vector<Hit>* hits, RenderKernel kernel) const {
  const CameraTables& tables = cameras[camera];
  const NodeGrid* grid = spec.render_block >= 2 ? &grids[camera] : nullptr;
  if (spec.rolling_shutter_s > 0.0) {
    const RowPose at_row = [&](int row) {
      return WorldFromCamera(camera, t_s + RowDelay(camera, row));
    };
    RowMoving moving_at_row;
    if (!moving.empty()) {
      moving_at_row = [&](int row, float* centres) {
        moving.CentresAt(t_s + RowDelay(camera, row), centres);
      };
    }
    RenderAccumulateRows(scene, tables, grid, at_row, weight, acc->data(), hits, kernel,
                         moving_at_row);
  } else {
    std::vector<float> centres(3 * static_cast<size_t>(moving.size()));
    moving.CentresAt(t_s, centres.data());
    RenderAccumulate(scene, tables, grid, WorldFromCamera(camera, t_s), weight, acc->data(), hits,
                     kernel, moving.empty() ? nullptr : centres.data());
  }
}

cv::Mat SimulatedRigData::Render(int camera, int64_t k, std::vector<float>* acc,
                                 std::vector<Hit>* hits, RenderKernel kernel) const {
  const CameraTables& tables = cameras[camera];
  acc->assign(static_cast<size_t>(tables.width) * tables.height, 0.f);
  const double t = StreamTime(k);
  const bool burst = BlurBurst(camera, k);
  const double exposure_s = burst ? 0.9 / spec.frame_rate_hz : spec.blur_exposure_s;
  if (exposure_s > 0.0) {
    const int samples = burst ? std::max(spec.blur_samples, 8) : spec.blur_samples;
    const float weight = 1.f / static_cast<float>(samples);
    for (int s = 0; s < samples; ++s) {
      RenderAt(camera, t + exposure_s * ((s + 0.5) / samples - 0.5), weight, acc, hits, kernel);
    }
  } else {
    RenderAt(camera, t, 1.f, acc, hits, kernel);
  }
  return Quantise(camera, k, *acc, tables.width, tables.height);
}

double SimulatedRigData::Gain(int camera, int64_t k) const {
  const SimulatedRigSpec::ExposureSteps& steps = spec.exposure_steps;
  if (!(steps.interval_s > 0.0) || !(steps.max_factor > 1.0)) return 1.0;
  const auto step = static_cast<uint64_t>(std::floor(StreamTime(k) / steps.interval_s));
  if (step == 0) return 1.0;  // the first interval at the nominal gain
  Rng rng(HashKey(spec.seed, kPurposeExposure, static_cast<uint64_t>(camera), step));
  return std::exp(rng.Uniform(-1.0, 1.0) * std::log(steps.max_factor));
}

cv::Mat SimulatedRigData::Quantise(int camera, int64_t k, const std::vector<float>& acc, int width,
                                   int height) const {
  cv::Mat image(height, width, CV_8UC1);
  const auto gain = static_cast<float>(Gain(camera, k));
  const auto sigma = static_cast<float>(spec.noise_sigma) * gain;  // the gain amplifies the noise
  Rng rng(
      HashKey(spec.seed, kPurposeNoise, static_cast<uint64_t>(camera), static_cast<uint64_t>(k)));
  // Light gathered per pixel: gain (1 - v (r / r_corner)²), r from the image centre; exactly 1
  // without vignetting and exposure steps.
  const float cx = 0.5f * static_cast<float>(width - 1);
  const float cy = 0.5f * static_cast<float>(height - 1);
  const float falloff = static_cast<float>(spec.vignetting) / (cx * cx + cy * cy);
  std::vector<float> dx2(static_cast<size_t>(width)), light(static_cast<size_t>(width));
  for (int x = 0; x < width; ++x) {
    dx2[x] = (static_cast<float>(x) - cx) * (static_cast<float>(x) - cx);
  }
  for (int y = 0; y < height; ++y) {
    const float* in = acc.data() + static_cast<size_t>(y) * width;
    const float* n = noise.data() + rng.Below(static_cast<uint32_t>(noise.size() - width));
    const float dy2 = (static_cast<float>(y) - cy) * (static_cast<float>(y) - cy);
    for (int x = 0; x < width; ++x) light[x] = gain * (1.f - falloff * (dx2[x] + dy2));
    uint8_t* out = image.ptr<uint8_t>(y);
    // Rounds and saturates (a loop the compiler vectorises).
    for (int x = 0; x < width; ++x) {
      const float v = std::min(std::max(in[x] * light[x] + sigma * n[x] + 0.5f, 0.f), 255.f);
      out[x] = static_cast<uint8_t>(static_cast<int>(v));
    }
  }
  return image;
}

}  // namespace rigcal::sim::internal
