// SPDX-License-Identifier: Apache-2.0
#pragma once
// Textures of the simulated rig: square, periodic, mip-mapped grey tiles of procedural "dead
// leaves" or of a photograph, stored in the row-pair layout the texture sampler reads. Private to
// rigcal_sim.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "rigcal/sim/simulated_rig_spec.h"

namespace rigcal::sim::internal {

// Every texture tile of the simulated scenes is 2^kTextureTileLog2 texels wide.
inline constexpr int kTextureTileLog2 = 10;

// A square, power-of-two, periodic grey texture with its mip pyramid (2x2 box filtered), in the
// "row pair" layout of the sampler: level l (size n = size >> l) holds n rows of
// n + kTexturePairPad two-byte entries; entry (x, y) is texel (x, y) followed by texel
// (x, y + 1 mod n); entry n of a row repeats entry 0 (the rest of the padding is zero).
inline constexpr int kTexturePairPad = 16;
struct TextureTile {
  int log2_size = 0;
  std::vector<std::vector<uint8_t>> pairs;
  // Texel (x, y) of level l.
  uint8_t At(int l, int x, int y) const {
    const size_t n = size_t{1} << (log2_size - l);
    return pairs[l][2 * (static_cast<size_t>(y) * (n + kTexturePairPad) + static_cast<size_t>(x))];
  }
};

// Byte offset of entry (x0, y0) of a level of size 2^log2n in the row-pair layout. One unaligned
// 32-bit load there yields the four texels of a bilinear sample in the byte order p00, p01,
// p10, p11 (p_xy, x0 and y0 in [0, 2^log2n)), without any wrapping arithmetic.
inline uint32_t PairOffset(int log2n, uint32_t x0, uint32_t y0) {
  return (y0 << (log2n + 1)) + y0 * (2 * kTexturePairPad) + (x0 << 1);
}

// Scale-invariant "dead leaves" texture: opaque axis-aligned rectangles, rotated rectangles and
// discs of random grey with sizes from 1.5 to size/8 texels (density ~ r^-3), lightly blurred.
// Periodic (tiles seamlessly), deterministic for `seed`.
TextureTile MakeDeadLeavesTile(int log2_size, uint64_t seed);

// A tile of a photograph (source.scene.textures): its centre square scaled to half the tile
// and mirrored across both axes, so that the tile repeats without seams.
TextureTile MakePhotoTile(const SimulatedRigSpec::GreyImage& photo, int log2_size);

// MakeDeadLeavesTile through a process-wide cache: tiles are immutable and deterministic for
// their seed, so rigs built with the same seed (tests, a rig rebuilt with other options) share
// them instead of generating them again. Thread-safe.
std::shared_ptr<const TextureTile> SharedDeadLeavesTile(int log2_size, uint64_t seed);

}  // namespace rigcal::sim::internal
