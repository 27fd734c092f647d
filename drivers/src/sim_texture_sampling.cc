// Texture sampling of the simulated rig: the fixed-point row-pair sampler, one sample at a time
// and SSE2 block kernels.
#include "sim_texture_sampling.h"

#include <emmintrin.h>

#include <algorithm>
#include <cstring>

namespace rigcal::drivers::internal {
namespace {

constexpr int kTileLog2 = kTextureTileLog2;
constexpr int kPairPad = kTexturePairPad;

inline int FloorToInt(float x) {
  const int i = static_cast<int>(x);
  return i - (x < static_cast<float>(i));
}

// Texture levels are stored as "row pairs" (TextureTile::pairs): entry (x, y) holds the
// texels (x, y) and (x, y + 1 mod n) as two bytes, rows of n + kPairPad entries whose entry n
// repeats entry 0. One unaligned 32-bit load at entry (x0, y0) then yields the four texels of a
// bilinear sample in the byte order p00, p01, p10, p11 (p_xy), without any wrapping arithmetic.
// Sample coordinates are 16.16 fixed point in the level's texels, shifted by half a texel; their
// integer part wraps (2^16 is a multiple of every level's size).

inline uint32_t PairOffset(int log2n, uint32_t x0, uint32_t y0) {  // in bytes
  return (y0 << (log2n + 1)) + y0 * (2 * kPairPad) + (x0 << 1);
}

// Scalar bilinear sample; returns the intensity * 2^16.
inline int BilinearPair(const uint8_t* pairs, int log2n, uint32_t x, uint32_t y) {
  const uint32_t mask = (1u << log2n) - 1u;
  uint32_t q;
  std::memcpy(&q, pairs + PairOffset(log2n, (x >> 16) & mask, (y >> 16) & mask), sizeof(q));
  const uint32_t ax = (x >> 8) & 0xFFu;
  const uint32_t ay = (y >> 8) & 0xFFu;
  // Two 16-bit lanes (left and right column) interpolated vertically at once: every lane stays
  // below 255 * 256, so no carry crosses lanes.
  const uint32_t columns = (q & 0x00FF00FFu) * (256u - ay) + ((q >> 8) & 0x00FF00FFu) * ay;
  return static_cast<int>((columns & 0xFFFFu) * (256u - ax) + (columns >> 16) * ax);
}

// Four bilinear samples at once (SSE2): lanes of x and y as above. Returns intensity * 256.
template <int log2n>
inline __m128 BilinearPair4(const uint8_t* pairs, __m128i x, __m128i y) {
  const __m128i mask = _mm_set1_epi32((1 << log2n) - 1);
  const __m128i x0 = _mm_and_si128(_mm_srli_epi32(x, 16), mask);
  const __m128i y0 = _mm_and_si128(_mm_srli_epi32(y, 16), mask);
  const __m128i offset = _mm_add_epi32(
      _mm_add_epi32(_mm_slli_epi32(y0, log2n + 1), _mm_slli_epi32(y0, 5)), _mm_slli_epi32(x0, 1));
  static_assert(2 * kPairPad == 32, "offset uses y0 << 5");
  alignas(16) uint32_t offsets[4];
  _mm_store_si128(reinterpret_cast<__m128i*>(offsets), offset);
  uint32_t q[4];
  for (int i = 0; i < 4; ++i) std::memcpy(&q[i], pairs + offsets[i], sizeof(uint32_t));
  const __m128i quads = _mm_setr_epi32(static_cast<int>(q[0]), static_cast<int>(q[1]),
                                       static_cast<int>(q[2]), static_cast<int>(q[3]));
  const __m128i byte_mask = _mm_set1_epi32(0xFF);
  const __m128i ay = _mm_and_si128(_mm_srli_epi32(y, 8), byte_mask);
  // 16-bit weight pairs (256 - ay, ay) per pixel.
  const __m128i wy = _mm_or_si128(_mm_sub_epi32(_mm_set1_epi32(256), ay), _mm_slli_epi32(ay, 16));
  const __m128i zero = _mm_setzero_si128();
  const __m128i q01 = _mm_unpacklo_epi8(quads, zero);  // pixels 0, 1: p00 p01 p10 p11 (16 bit)
  const __m128i q23 = _mm_unpackhi_epi8(quads, zero);
  const __m128i w01 = _mm_shuffle_epi32(wy, _MM_SHUFFLE(1, 1, 0, 0));
  const __m128i w23 = _mm_shuffle_epi32(wy, _MM_SHUFFLE(3, 3, 2, 2));
  // Left and right columns interpolated vertically, * 256: [L0 R0 L1 R1], [L2 R2 L3 R3].
  const __m128 c01 = _mm_cvtepi32_ps(_mm_madd_epi16(q01, w01));
  const __m128 c23 = _mm_cvtepi32_ps(_mm_madd_epi16(q23, w23));
  const __m128 left = _mm_shuffle_ps(c01, c23, _MM_SHUFFLE(2, 0, 2, 0));
  const __m128 right = _mm_shuffle_ps(c01, c23, _MM_SHUFFLE(3, 1, 3, 1));
  const __m128 ax = _mm_mul_ps(_mm_cvtepi32_ps(_mm_and_si128(_mm_srli_epi32(x, 8), byte_mask)),
                               _mm_set1_ps(1.f / 256.f));
  return _mm_add_ps(left, _mm_mul_ps(ax, _mm_sub_ps(right, left)));
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

// The same in 16.16 fixed point for texel coordinates of a level of size 2^log2n, scaled by
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
struct FixedLanes {
  __m128i value;
  __m128i row_step;
  FixedLanes(const FixedBilinear2d& f, int x0) {
    uint32_t v[4], s[4];
    for (int i = 0; i < 4; ++i) {
      const auto x = static_cast<uint32_t>(x0 + i);
      v[i] = f.a + x * f.b;
      s[i] = f.c + x * f.d;
    }
    value = _mm_setr_epi32(static_cast<int>(v[0]), static_cast<int>(v[1]), static_cast<int>(v[2]),
                           static_cast<int>(v[3]));
    row_step = _mm_setr_epi32(static_cast<int>(s[0]), static_cast<int>(s[1]),
                              static_cast<int>(s[2]), static_cast<int>(s[3]));
  }
  void NextRow() { value = _mm_add_epi32(value, row_step); }
};

// The same for a float interpolant.
struct FloatLanes {
  __m128 value;
  __m128 row_step;
  FloatLanes(const Bilinear2d& f, int x0) {
    const __m128 x = _mm_setr_ps(static_cast<float>(x0), static_cast<float>(x0 + 1),
                                 static_cast<float>(x0 + 2), static_cast<float>(x0 + 3));
    value = _mm_add_ps(_mm_set1_ps(f.a), _mm_mul_ps(x, _mm_set1_ps(f.b)));
    row_step = _mm_add_ps(_mm_set1_ps(f.c), _mm_mul_ps(x, _mm_set1_ps(f.d)));
  }
  void NextRow() { value = _mm_add_ps(value, row_step); }
};

// out[i] += lanes i < n of v.
inline void AddLanes(__m128 v, int n, float* out) {
  if (n == 4) {
    _mm_storeu_ps(out, _mm_add_ps(_mm_loadu_ps(out), v));
    return;
  }
  alignas(16) float values[4];
  _mm_store_ps(values, v);
  for (int i = 0; i < n; ++i) out[i] += values[i];
}

// Level 0 only (magnified texture).
template <int log2n>
void FillMagnified(const uint8_t* level, const FixedBilinear2d& fu, const FixedBilinear2d& fv,
                   int nx, int ny, float weight, float* out, int stride) {
  const __m128 scale = _mm_set1_ps(weight * (1.f / 256.f));
  for (int x0 = 0; x0 < nx; x0 += 4) {
    const int n = std::min(4, nx - x0);
    FixedLanes u(fu, x0), v(fv, x0);
    float* row = out + x0;
    for (int y = 0; y < ny; ++y, row += stride, u.NextRow(), v.NextRow()) {
      AddLanes(_mm_mul_ps(BilinearPair4<log2n>(level, u.value, v.value), scale), n, row);
    }
  }
}

// Levels l, l + 1 and l + 2 (sizes 2^log2l, 2^(log2l - 1), 2^(log2l - 2)) cover the block:
// trilinear between l and l + 1 (fraction f in [0, 1)) or l + 1 and l + 2 (f in [1, 2)).
// Coordinates are kept for level l; level l + 1's are (X >> 1) - 1/4 texel (16.16, half-texel
// shifted, wrapping).
template <int log2l>
void FillTrilinear(const uint8_t* const levels[3], const FixedBilinear2d& fu,
                   const FixedBilinear2d& fv, const Bilinear2d& frac, int nx, int ny, float weight,
                   float* out, int stride) {
  const __m128 scale = _mm_set1_ps(weight * (1.f / 256.f));
  const __m128 one = _mm_set1_ps(1.f);
  const __m128 two = _mm_set1_ps(2.f);
  const __m128 zero = _mm_setzero_ps();
  const __m128i quarter = _mm_set1_epi32(16384);
  auto half = [&quarter](__m128i c) { return _mm_sub_epi32(_mm_srli_epi32(c, 1), quarter); };
  for (int x0 = 0; x0 < nx; x0 += 4) {
    const int n = std::min(4, nx - x0);
    FixedLanes u(fu, x0), v(fv, x0);
    FloatLanes fl(frac, x0);
    float* row = out + x0;
    for (int y = 0; y < ny; ++y, row += stride, u.NextRow(), v.NextRow(), fl.NextRow()) {
      const __m128 f = _mm_min_ps(_mm_max_ps(fl.value, zero), two);
      const __m128i u1 = half(u.value), v1 = half(v.value);
      const int coarse = _mm_movemask_ps(_mm_cmpge_ps(f, one));  // lanes in [l + 1, l + 2]
      __m128 value;
      if (coarse == 0) {
        const __m128 a = BilinearPair4<log2l>(levels[0], u.value, v.value);
        const __m128 b = BilinearPair4<log2l - 1>(levels[1], u1, v1);
        value = _mm_add_ps(a, _mm_mul_ps(f, _mm_sub_ps(b, a)));
      } else if (coarse == 0xF) {
        const __m128 a = BilinearPair4<log2l - 1>(levels[1], u1, v1);
        const __m128 b = BilinearPair4<log2l - 2>(levels[2], half(u1), half(v1));
        value = _mm_add_ps(a, _mm_mul_ps(_mm_sub_ps(f, one), _mm_sub_ps(b, a)));
      } else {  // the level boundary runs through these four pixels
        const __m128 a = BilinearPair4<log2l>(levels[0], u.value, v.value);
        const __m128 b = BilinearPair4<log2l - 1>(levels[1], u1, v1);
        const __m128 c = BilinearPair4<log2l - 2>(levels[2], half(u1), half(v1));
        const __m128 fine = _mm_add_ps(a, _mm_mul_ps(f, _mm_sub_ps(b, a)));
        const __m128 rough = _mm_add_ps(b, _mm_mul_ps(_mm_sub_ps(f, one), _mm_sub_ps(c, b)));
        const __m128 use_rough = _mm_cmpge_ps(f, one);
        value = _mm_or_ps(_mm_and_ps(use_rough, rough), _mm_andnot_ps(use_rough, fine));
      }
      AddLanes(_mm_mul_ps(value, scale), n, row);
    }
  }
}

}  // namespace

void FillTexturedBlock(const TileView& tile, const BlockCorners& corners, int block, int nx, int ny,
                       float weight, float* out, int stride) {
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
    FillMagnified<kTileLog2>(tile.level[0], fu, fv, nx, ny, weight, out, stride);
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
#define RIGCAL_FILL_CASE(n)                                              \
  case n:                                                                \
    FillTrilinear<n>(levels, fu, fv, frac, nx, ny, weight, out, stride); \
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

}  // namespace rigcal::drivers::internal
