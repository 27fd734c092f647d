// SPDX-License-Identifier: Apache-2.0
#pragma once
// Texture sampling of the simulated rig's renderer: trilinear samples of a mip-mapped texture
// tile (sim_texture.h), one at a time or for a whole block of pixels whose texture coordinates
// and mip level are interpolated bilinearly between the block's corners (four-lane kernels,
// SIMD where the build has it). Private to rigcal_sim.

#include <cstdint>

#include "rigcal/sim/simulated_rig.h"
#include "sim_texture.h"

namespace rigcal::sim::internal {

// The mip levels of one texture tile (of kTextureTileLog2), as the samplers read them.
struct TileView {
  const uint8_t* level[16];
  int num_levels;
};
// The view of `tile`, which must outlive it.
TileView MakeTileView(const TextureTile& tile);

// Trilinear sample of `tile` at level-0 texel coordinates (u, v) (continuous, wrapping) and mip
// level `lod` (<= 0: level 0 only); grey level.
float SampleTrilinear(const TileView& tile, float u, float v, float lod);

// f(x, y) = a + b x + c y + d x y: the bilinear interpolant of the four corner values of a
// block of `block` pixels, x and y in pixels from the block's top-left node.
struct Bilinear2d {
  float a, b, c, d;
  Bilinear2d(float q00, float q10, float q01, float q11, float inv_block)
      : a(q00),
        b((q10 - q00) * inv_block),
        c((q01 - q00) * inv_block),
        d((q11 - q10 - q01 + q00) * inv_block * inv_block) {}
};

// Texture coordinates (u, v, level-0 texels) and mip level at the four corner nodes of a block,
// in the order top-left, top-right, bottom-left, bottom-right.
struct BlockCorners {
  float u[4];
  float v[4];
  float lod[4];
};

// Adds weight * texture to the nx x ny pixels of one block (rows `stride` floats apart) whose
// corner nodes lie `block` pixels apart: texture coordinates and mip level are interpolated
// bilinearly between the corners. `kernel`: SIMD (where the build has it) or scalar; both add
// the same values (sim_simd.h).
void FillTexturedBlock(const TileView& tile, const BlockCorners& corners, int block, int nx, int ny,
                       float weight, float* out, int stride, RenderKernel kernel);

}  // namespace rigcal::sim::internal
