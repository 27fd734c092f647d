// SPDX-License-Identifier: Apache-2.0
// Texture sampling of the simulated rig: the fixed-point row-pair sampler, one sample at a time,
// and the block kernels, written once for the four-lane backends of sim_simd.h.
#include "sim_texture_sampling.h"

#include <algorithm>
#include <cstring>

#include "sim_simd.h"

namespace rigcal::sim::internal {
namespace {

constexpr int kTileLog2 = kTextureTileLog2;

inline int FloorToInt(float x) {
  const int i = static_cast<int>(x);
  return i - (x < static_cast<float>(i));
}

// Sample coordinates are 16.16 fixed point in the level's texels, shifted by half a texel; their
// integer part wraps (2^16 is a multiple of every level's size). Texels are read in the
// row-pair layout (sim_texture.h, PairOffset).

// Scalar bilinear sample; returns the intensity * 2^16.
inline int BilinearPair(const uint8_t* pairs, int log2n, uint32_t x, uint32_t y) {
  const uint32_t mask = (1u << log2n) - 1u;
  uint32_t q;
  std::memcpy(&q, pairs + PairOffset(log2n, (x >> 16) & mask, (y >> 16) & mask), sizeof(q));
  const uint32_t ax = (x >> 8) & 0xFFu;
  const uint32_t columns = BilinearColumns(q, (y >> 8) & 0xFFu);
  return static_cast<int>((columns & 0xFFFFu) * (256u - ax) + (columns >> 16) * ax);
}

// 16.16 fixed-point start of a texel coordinate at a level of size 2^log2n (the coordinate is
// in that level's texels), shifted by half a texel and reduced modulo the level size.
inline uint32_t ToFixed(float coordinate, int log2n) {
  const float size = static_cast<float>(1 << log2n);
  const uint32_t inverse_bits = static_cast<uint32_t>(127 - log2n) << 23;  // 2^-log2n
  float inverse;
  std::memcpy(&inverse, &inverse_bits, sizeof(inverse));
  float c = coordinate - 0.5f;
  c -= size * static_cast<float>(FloorToInt(c * inverse));
  return static_cast<uint32_t>(static_cast<int64_t>(c * 65536.f));
}
inline uint32_t ToFixedStep(float step) {
  return static_cast<uint32_t>(static_cast<int32_t>(step * 65536.f));
}

}  // namespace

TileView MakeTileView(const TextureTile& tile) {
  TileView view{};
  view.num_levels = static_cast<int>(tile.pairs.size());
  for (int l = 0; l < view.num_levels; ++l) view.level[l] = tile.pairs[l].data();
  return view;
}

float SampleTrilinear(const TileView& tile, float u, float v, float lod) {
  const int top = tile.num_levels - 1;
  const int l = lod <= 0.f ? 0 : std::min(static_cast<int>(lod), top);
  const float scale = 1.f / static_cast<float>(1 << l);
  const int log2n = kTileLog2 - l;
  const float a = static_cast<float>(BilinearPair(tile.level[l], log2n, ToFixed(u * scale, log2n),
                                                  ToFixed(v * scale, log2n))) *
                  (1.f / 65536.f);
  if (lod <= 0.f || l == top) return a;
  const float b = static_cast<float>(BilinearPair(tile.level[l + 1], log2n - 1,
                                                  ToFixed(0.5f * u * scale, log2n - 1),
                                                  ToFixed(0.5f * v * scale, log2n - 1))) *
                  (1.f / 65536.f);
  return a + (lod - static_cast<float>(l)) * (b - a);
}

namespace {

// Bilinear2d in 16.16 fixed point for texel coordinates of a level of size 2^log2n, scaled by
// `scale` (2^-level), with the half-texel shift and the wrap applied to the start.
struct FixedBilinear2d {
  uint32_t a, b, c, d;
  FixedBilinear2d(const Bilinear2d& f, float scale, int log2n)
      : a(ToFixed(f.a * scale, log2n)),
        b(ToFixedStep(f.b * scale)),
        c(ToFixedStep(f.c * scale)),
        d(ToFixedStep(f.d * scale)) {}
};

// The 16.16 coordinates of pixels x0 .. x0 + 3 of a block's row y, walked down the rows:
// lane i at row y is a + (x0 + i) b + y (c + (x0 + i) d), so each row adds a constant vector.
template <typename L>
struct FixedLanes {
  typename L::U value;
  typename L::U row_step;
  FixedLanes(const FixedBilinear2d& f, int x0) {
    uint32_t v[4], s[4];
    for (int i = 0; i < 4; ++i) {
      const auto x = static_cast<uint32_t>(x0 + i);
      v[i] = f.a + x * f.b;
      s[i] = f.c + x * f.d;
    }
    value = L::Load(v);
    row_step = L::Load(s);
  }
  void NextRow() { value = L::AddU(value, row_step); }
};

// The same for a float interpolant.
template <typename L>
struct FloatLanes {
  typename L::F value;
  typename L::F row_step;
  FloatLanes(const Bilinear2d& f, int x0) {
    const typename L::F x = L::Iota(x0);
    value = L::Add(L::Splat(f.a), L::Mul(x, L::Splat(f.b)));
    row_step = L::Add(L::Splat(f.c), L::Mul(x, L::Splat(f.d)));
  }
  void NextRow() { value = L::Add(value, row_step); }
};

// Level 0 only (magnified texture).
template <typename L, int log2n>
void FillMagnified(const uint8_t* level, const FixedBilinear2d& fu, const FixedBilinear2d& fv,
                   int nx, int ny, float weight, float* out, int stride) {
  const typename L::F scale = L::Splat(weight * (1.f / 256.f));
  for (int x0 = 0; x0 < nx; x0 += 4) {
    const int n = std::min(4, nx - x0);
    FixedLanes<L> u(fu, x0), v(fv, x0);
    float* row = out + x0;
    for (int y = 0; y < ny; ++y, row += stride, u.NextRow(), v.NextRow()) {
      L::AddTo(L::Mul(L::template Bilinear<log2n>(level, u.value, v.value), scale), n, row);
    }
  }
}

// Levels l, l + 1 and l + 2 (sizes 2^log2l, 2^(log2l - 1), 2^(log2l - 2)) cover the block:
// trilinear between l and l + 1 (fraction f in [0, 1)) or l + 1 and l + 2 (f in [1, 2)).
// Coordinates are kept for level l; level l + 1's are (X >> 1) - 1/4 texel (16.16, half-texel
// shifted, wrapping).
template <typename L, int log2l>
void FillTrilinear(const uint8_t* const levels[3], const FixedBilinear2d& fu,
                   const FixedBilinear2d& fv, const Bilinear2d& frac, int nx, int ny, float weight,
                   float* out, int stride) {
  using F = typename L::F;
  using U = typename L::U;
  const F scale = L::Splat(weight * (1.f / 256.f));
  const F one = L::Splat(1.f);
  const F two = L::Splat(2.f);
  const F zero = L::Splat(0.f);
  const U quarter = L::SplatU(16384);
  auto half = [&quarter](U c) { return L::SubU(L::template ShiftRight<1>(c), quarter); };
  auto lerp = [](F a, F b, F t) { return L::Add(a, L::Mul(t, L::Sub(b, a))); };  // a + t (b - a)
  for (int x0 = 0; x0 < nx; x0 += 4) {
    const int n = std::min(4, nx - x0);
    FixedLanes<L> u(fu, x0), v(fv, x0);
    FloatLanes<L> fl(frac, x0);
    float* row = out + x0;
    for (int y = 0; y < ny; ++y, row += stride, u.NextRow(), v.NextRow(), fl.NextRow()) {
      const F f = L::Min(L::Max(fl.value, zero), two);
      const U u1 = half(u.value), v1 = half(v.value);
      const auto use_rough = L::CompareGe(f, one);  // lanes in [l + 1, l + 2]
      const int coarse = L::MoveMask(use_rough);
      F value;
      if (coarse == 0) {
        const F a = L::template Bilinear<log2l>(levels[0], u.value, v.value);
        const F b = L::template Bilinear<log2l - 1>(levels[1], u1, v1);
        value = lerp(a, b, f);
      } else if (coarse == 0xF) {
        const F a = L::template Bilinear<log2l - 1>(levels[1], u1, v1);
        const F b = L::template Bilinear<log2l - 2>(levels[2], half(u1), half(v1));
        value = lerp(a, b, L::Sub(f, one));
      } else {  // the level boundary runs through these four pixels
        const F a = L::template Bilinear<log2l>(levels[0], u.value, v.value);
        const F b = L::template Bilinear<log2l - 1>(levels[1], u1, v1);
        const F c = L::template Bilinear<log2l - 2>(levels[2], half(u1), half(v1));
        value = L::Select(use_rough, lerp(b, c, L::Sub(f, one)), lerp(a, b, f));
      }
      L::AddTo(L::Mul(value, scale), n, row);
    }
  }
}

// FillTexturedBlock with the kernels of backend L.
template <typename L>
void FillTexturedBlockWith(const TileView& tile, const BlockCorners& corners, int block, int nx,
                           int ny, float weight, float* out, int stride) {
  const float inv_block = 1.f / static_cast<float>(block);
  const float* cu = corners.u;
  const float* cv = corners.v;
  const float* cl = corners.lod;
  const Bilinear2d u(cu[0], cu[1], cu[2], cu[3], inv_block);
  const Bilinear2d v(cv[0], cv[1], cv[2], cv[3], inv_block);
  const Bilinear2d lod(cl[0], cl[1], cl[2], cl[3], inv_block);
  const float lod_min = std::min(std::min(cl[0], cl[1]), std::min(cl[2], cl[3]));
  const float lod_max = std::max(std::max(cl[0], cl[1]), std::max(cl[2], cl[3]));
  if (lod_max <= 0.f) {  // magnified: the finest level only, fixed point
    const FixedBilinear2d fu(u, 1.f, kTileLog2), fv(v, 1.f, kTileLog2);
    FillMagnified<L, kTileLog2>(tile.level[0], fu, fv, nx, ny, weight, out, stride);
    return;
  }
  const int l = std::max(0, static_cast<int>(lod_min));
  if (static_cast<int>(lod_max) <= l + 1 && l + 2 < tile.num_levels) {
    const float scale = 1.f / static_cast<float>(1 << l);
    const int log2_l = kTileLog2 - l;
    const FixedBilinear2d fu(u, scale, log2_l), fv(v, scale, log2_l);
    Bilinear2d frac = lod;
    frac.a -= static_cast<float>(l);
    const uint8_t* levels[3] = {tile.level[l], tile.level[l + 1], tile.level[l + 2]};
    switch (log2_l) {
#define RIGCAL_FILL_CASE(n)                                                 \
  case n:                                                                   \
    FillTrilinear<L, n>(levels, fu, fv, frac, nx, ny, weight, out, stride); \
    return;
      RIGCAL_FILL_CASE(10)
      RIGCAL_FILL_CASE(9)
      RIGCAL_FILL_CASE(8)
      RIGCAL_FILL_CASE(7)
      RIGCAL_FILL_CASE(6)
      RIGCAL_FILL_CASE(5)
      RIGCAL_FILL_CASE(4)
      RIGCAL_FILL_CASE(3)
      RIGCAL_FILL_CASE(2)
#undef RIGCAL_FILL_CASE
      default:
        break;
    }
  }
  for (int y = 0; y < ny; ++y, out += stride) {
    const float yf = static_cast<float>(y);
    for (int x = 0; x < nx; ++x) {
      const float xf = static_cast<float>(x);
      out[x] += weight * SampleTrilinear(tile, u.a + xf * u.b + yf * (u.c + xf * u.d),
                                         v.a + xf * v.b + yf * (v.c + xf * v.d),
                                         lod.a + xf * lod.b + yf * (lod.c + xf * lod.d));
    }
  }
}

}  // namespace

void FillTexturedBlock(const TileView& tile, const BlockCorners& corners, int block, int nx, int ny,
                       float weight, float* out, int stride, RenderKernel kernel) {
  if (kernel == RenderKernel::kSimd) {
    FillTexturedBlockWith<SimdLanes>(tile, corners, block, nx, ny, weight, out, stride);
  } else {
    FillTexturedBlockWith<ScalarLanes>(tile, corners, block, nx, ny, weight, out, stride);
  }
}

}  // namespace rigcal::sim::internal

namespace rigcal::sim {

const char* SimdRenderKernelName() { return internal::SimdLanes::kName; }

}  // namespace rigcal::sim
