// SPDX-License-Identifier: Apache-2.0
// Textures of the simulated rig: procedural dead leaves and photographs.
#include "sim_texture.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <utility>

#include "rigcal/base/thread_annotations.h"
#include "sim_random.h"

namespace rigcal::sim::internal {
namespace {

// Fills texels [x_begin, x_end] of row y with `value`, wrapping around.
inline void FillSpan(int8_t* data, int log2_size, int y, int x_begin, int x_end, int8_t value) {
  const int mask = (1 << log2_size) - 1;
  int8_t* row = data + (static_cast<size_t>(y & mask) << log2_size);
  if (x_end - x_begin >= mask) {
    std::fill(row, row + mask + 1, value);
    return;
  }
  for (int x = x_begin; x <= x_end; ++x) row[x & mask] = value;
}

// Paints the texels whose centres lie inside the shape with `value`, wrapping around. Every
// shape is painted as one span per row.
void PaintShape(std::vector<int8_t>* layer, int log2_size, Rng& rng, double half_size,
                int8_t value) {
  const int n = 1 << log2_size;
  const double cx = rng.Uniform(0, n);
  const double cy = rng.Uniform(0, n);
  const uint32_t kind = rng.Below(100);
  int8_t* data = layer->data();
  // Texel x is covered when its centre x + 0.5 - cx lies in [lo, hi].
  auto span = [&](int y, double lo, double hi) {
    const int x_begin = static_cast<int>(std::ceil(cx + lo - 0.5));
    const int x_end = static_cast<int>(std::floor(cx + hi - 0.5));
    if (x_end >= x_begin) FillSpan(data, log2_size, y, x_begin, x_end, value);
  };
  if (kind < 55) {  // axis-aligned rectangle: corners in the two image directions
    const double aspect = std::exp(rng.Uniform(-0.7, 0.7));
    const double hw = half_size * std::sqrt(aspect);
    const double hh = half_size / std::sqrt(aspect);
    const int y_begin = static_cast<int>(std::ceil(cy - hh - 0.5));
    const int y_end = static_cast<int>(std::floor(cy + hh - 0.5));
    for (int y = y_begin; y <= y_end; ++y) span(y, -hw, hw);
  } else if (kind < 85) {  // rotated rectangle: corners at every angle
    const double aspect = std::exp(rng.Uniform(-0.7, 0.7));
    const double hw = half_size * std::sqrt(aspect);
    const double hh = half_size / std::sqrt(aspect);
    const double angle = rng.Uniform(0.05, 1.52);  // away from axis-aligned
    const double c = std::cos(angle), s = std::sin(angle);
    const double reach_y = s * hw + c * hh;
    const int y_begin = static_cast<int>(std::floor(cy - reach_y));
    const int y_end = static_cast<int>(std::ceil(cy + reach_y));
    for (int y = y_begin; y <= y_end; ++y) {
      const double dy = y + 0.5 - cy;
      // |c dx + s dy| <= hw and |-s dx + c dy| <= hh, with c, s > 0.
      const double lo = std::max((-hw - s * dy) / c, (c * dy - hh) / s);
      const double hi = std::min((hw - s * dy) / c, (c * dy + hh) / s);
      if (hi >= lo) span(y, lo, hi);
    }
  } else {  // disc
    const double r2 = half_size * half_size;
    const int y_begin = static_cast<int>(std::floor(cy - half_size));
    const int y_end = static_cast<int>(std::ceil(cy + half_size));
    for (int y = y_begin; y <= y_end; ++y) {
      const double dy = y + 0.5 - cy;
      if (dy * dy > r2) continue;
      const double half_width = std::sqrt(r2 - dy * dy);
      span(y, -half_width, half_width);
    }
  }
}

// The mip pyramid (2x2 box filter) of an n x n CV_8U level 0 (n = 2^log2_size), in the sampler's
// row-pair layout.
TextureTile TileFromFinestLevel(const cv::Mat& level0, int log2_size) {
  const int n = 1 << log2_size;
  std::vector<std::vector<uint8_t>> levels;
  levels.emplace_back(level0.datastart, level0.dataend);
  for (int l = 1; l <= log2_size; ++l) {
    const int src_n = n >> (l - 1);
    const int dst_n = n >> l;
    const std::vector<uint8_t>& src = levels.back();
    std::vector<uint8_t> dst(static_cast<size_t>(dst_n) * dst_n);
    for (int y = 0; y < dst_n; ++y) {
      const uint8_t* r0 = &src[static_cast<size_t>(2 * y) * src_n];
      const uint8_t* r1 = r0 + src_n;
      for (int x = 0; x < dst_n; ++x) {
        dst[static_cast<size_t>(y) * dst_n + x] =
            static_cast<uint8_t>((r0[2 * x] + r0[2 * x + 1] + r1[2 * x] + r1[2 * x + 1] + 2) / 4);
      }
    }
    levels.push_back(std::move(dst));
  }
  TextureTile tile;
  tile.log2_size = log2_size;
  for (int l = 0; l <= log2_size; ++l) {
    const size_t size = size_t{1} << (log2_size - l);
    const size_t row = size + kTexturePairPad;
    const std::vector<uint8_t>& level = levels[l];
    std::vector<uint8_t> pairs(2 * row * size, 0);
    for (size_t y = 0; y < size; ++y) {
      const uint8_t* r0 = &level[y * size];
      const uint8_t* r1 = &level[((y + 1) % size) * size];
      uint8_t* out = &pairs[2 * row * y];
      for (size_t x = 0; x <= size; ++x) {
        out[2 * x] = r0[x % size];
        out[2 * x + 1] = r1[x % size];
      }
    }
    tile.pairs.push_back(std::move(pairs));
  }
  return tile;
}

}  // namespace

TextureTile MakeDeadLeavesTile(int log2_size, uint64_t seed) {
  const int n = 1 << log2_size;
  const size_t texels = static_cast<size_t>(n) * n;
  Rng rng(seed);
  // Dead leaves (Matheron; Lee, Mumford & Huang 2001): opaque shapes of random grey fall on
  // the tile one after the other. Half sizes follow a density ~ r^-3 between 1.5 texels and
  // n / 16, which makes the visible pattern scale invariant: every scale, and so every mip level
  // and viewing distance, shows edges and corners. Five coverages leave < 1% uncovered.
  std::vector<int8_t> layer(texels, 0);
  constexpr double kCoverage = 5.0;
  const double r_min = 1.5, r_max = n / 16.0;
  const double inv_min2 = 1.0 / (r_min * r_min), inv_max2 = 1.0 / (r_max * r_max);
  const double mean_r2 = std::log(r_max / r_min) / (0.5 * (inv_min2 - inv_max2));
  const int count = static_cast<int>(kCoverage * static_cast<double>(texels) / (3.7 * mean_r2));
  for (int c = 0; c < count; ++c) {
    const double half = 1.0 / std::sqrt(inv_min2 - rng.Uniform() * (inv_min2 - inv_max2));
    const auto value = static_cast<int8_t>(static_cast<int>(rng.Below(226)) - 113);
    PaintShape(&layer, log2_size, rng, half, value);
  }
  std::vector<float> sum(texels);
  for (size_t i = 0; i < texels; ++i) sum[i] = 128.f + static_cast<float>(layer[i]);
  cv::Mat image(n, n, CV_32F, sum.data());
  // A light blur (periodic border) so that edges are a texel wide rather than aliased steps.
  cv::Mat padded, blurred;
  constexpr int kPad = 4;
  cv::copyMakeBorder(image, padded, kPad, kPad, kPad, kPad, cv::BORDER_WRAP);
  cv::GaussianBlur(padded, blurred, cv::Size(0, 0), 0.5, 0.5, cv::BORDER_REFLECT);
  cv::Mat level0;
  blurred(cv::Rect(kPad, kPad, n, n)).convertTo(level0, CV_8U);  // rounds and saturates
  return TileFromFinestLevel(level0, log2_size);
}

TextureTile MakePhotoTile(const SimulatedRigSpec::GreyImage& photo, int log2_size) {
  // The centre square, scaled to half a tile (area averaging), mirrored across both axes: a
  // tile that repeats without seams, whatever the photograph's edges.
  const int half = 1 << (log2_size - 1);
  const cv::Mat image(photo.height, photo.width, CV_8U,
                      const_cast<uint8_t*>(photo.pixels.data()));  // read only
  const int side = std::min(photo.width, photo.height);
  const cv::Rect square((photo.width - side) / 2, (photo.height - side) / 2, side, side);
  cv::Mat scaled;
  cv::resize(image(square), scaled, cv::Size(half, half), 0, 0,
             side > half ? cv::INTER_AREA : cv::INTER_LINEAR);
  cv::Mat top, bottom, level0;
  cv::hconcat(scaled, scaled.clone(), top);
  cv::flip(scaled, top(cv::Rect(half, 0, half, half)), 1);
  cv::flip(top, bottom, 0);
  cv::vconcat(top, bottom, level0);
  return TileFromFinestLevel(level0, log2_size);
}

// The process-wide tile cache of SharedDeadLeavesTile; scenes may be built on any thread.
struct TileCache {
  Mutex mutex;
  std::map<std::pair<int, uint64_t>, std::weak_ptr<const TextureTile>> tiles
      RIGCAL_GUARDED_BY(mutex);
};

std::shared_ptr<const TextureTile> SharedDeadLeavesTile(int log2_size, uint64_t seed) {
  static TileCache cache;
  MutexLock lock(cache.mutex);
  std::weak_ptr<const TextureTile>& entry = cache.tiles[{log2_size, seed}];
  if (auto tile = entry.lock()) return tile;
  auto tile = std::make_shared<const TextureTile>(MakeDeadLeavesTile(log2_size, seed));
  entry = tile;
  return tile;
}

}  // namespace rigcal::sim::internal
