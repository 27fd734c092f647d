// SPDX-License-Identifier: Apache-2.0
#pragma once
// Four-lane vectors for the texture kernels of the simulated rig's renderer, one backend per
// instruction set: Sse2Lanes (x86, `__SSE2__`), NeonLanes (ARM, `__ARM_NEON`) and ScalarLanes
// (portable C++, every build). A kernel is written once against this interface
// (`template <typename Lanes>`) and runs on each backend. Every backend computes each lane with
// the same integer and IEEE single-precision operations in the same order as the others, so
// they agree bit for bit unless the compiler contracts a multiply and an add into a fused
// multiply-add in one backend and not in another (possible on arm64, never on plain x86-64).
// SimdLanes is the SIMD backend of the build (ScalarLanes where there is none).
//
// Interface of a backend `L` (F: 4 floats, U: 4 uint32, M: a lane mask):
//   Splat(float), SplatU(uint32), Iota(x0) = (x0, x0 + 1, x0 + 2, x0 + 3), Load(uint32[4]);
//   Add/Sub/Mul of F; Min(a, b) = a < b ? a : b and Max(a, b) = a > b ? a : b per lane (the
//   SSE semantics: b when either is NaN); AddU/SubU of U (wrapping), ShiftRight<n>(U);
//   CompareGe(F, F) -> M, MoveMask(M) (bit i: lane i set), Select(M, if_set, if_clear);
//   Bilinear<log2n>(pairs, x, y): four bilinear samples of a row-pair texture level
//   (sim_texture.h) of size 2^log2n at 16.16 fixed-point coordinates (half-texel shifted,
//   wrapping), intensity * 256;
//   AddTo(F v, n, out): out[i] += v[i] for the first n lanes.
// Private to rigcal_sim.

#include <cstdint>
#include <cstring>

#include "sim_texture.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#define RIGCAL_SIM_SIMD_SSE2 1
#elif defined(__ARM_NEON)
#include <arm_neon.h>
#define RIGCAL_SIM_SIMD_NEON 1
#endif

namespace rigcal::sim::internal {

// Left and right columns of the bilinear sample whose four texels `quad` holds (row-pair
// layout: bytes p00, p01, p10, p11), interpolated vertically with weight ay / 256 (ay in
// [0, 255]), * 256: two 16-bit lanes (left low, right high) computed at once; every lane stays
// below 255 * 256, so no carry crosses lanes.
inline uint32_t BilinearColumns(uint32_t quad, uint32_t ay) {
  return (quad & 0x00FF00FFu) * (256u - ay) + ((quad >> 8) & 0x00FF00FFu) * ay;
}

// Portable backend: plain arrays, one lane after the other.
struct ScalarLanes {
  struct F {
    float v[4];
  };
  struct U {
    uint32_t v[4];
  };
  struct M {
    bool v[4];
  };
  static constexpr const char* kName = "scalar";

  static F Splat(float a) { return {{a, a, a, a}}; }
  static U SplatU(uint32_t a) { return {{a, a, a, a}}; }
  static F Iota(int x0) {
    return {{static_cast<float>(x0), static_cast<float>(x0 + 1), static_cast<float>(x0 + 2),
             static_cast<float>(x0 + 3)}};
  }
  static U Load(const uint32_t a[4]) { return {{a[0], a[1], a[2], a[3]}}; }
  static F Add(F a, F b) {
    return Map(a, b, [](float x, float y) { return x + y; });
  }
  static F Sub(F a, F b) {
    return Map(a, b, [](float x, float y) { return x - y; });
  }
  static F Mul(F a, F b) {
    return Map(a, b, [](float x, float y) { return x * y; });
  }
  static F Min(F a, F b) {
    return Map(a, b, [](float x, float y) { return x < y ? x : y; });
  }
  static F Max(F a, F b) {
    return Map(a, b, [](float x, float y) { return x > y ? x : y; });
  }
  static U AddU(U a, U b) {
    for (int i = 0; i < 4; ++i) a.v[i] += b.v[i];
    return a;
  }
  static U SubU(U a, U b) {
    for (int i = 0; i < 4; ++i) a.v[i] -= b.v[i];
    return a;
  }
  template <int n>
  static U ShiftRight(U a) {
    for (uint32_t& x : a.v) x >>= n;
    return a;
  }
  static M CompareGe(F a, F b) {
    M m;
    for (int i = 0; i < 4; ++i) m.v[i] = a.v[i] >= b.v[i];
    return m;
  }
  static int MoveMask(M m) { return m.v[0] | m.v[1] << 1 | m.v[2] << 2 | m.v[3] << 3; }
  static F Select(M m, F if_set, F if_clear) {
    for (int i = 0; i < 4; ++i) {
      if (!m.v[i]) if_set.v[i] = if_clear.v[i];
    }
    return if_set;
  }
  template <int log2n>
  static F Bilinear(const uint8_t* pairs, U x, U y) {
    constexpr uint32_t kMask = (1u << log2n) - 1u;
    F result;
    for (int i = 0; i < 4; ++i) {
      uint32_t quad;
      std::memcpy(&quad, pairs + PairOffset(log2n, (x.v[i] >> 16) & kMask, (y.v[i] >> 16) & kMask),
                  sizeof(quad));
      const uint32_t columns = BilinearColumns(quad, (y.v[i] >> 8) & 0xFFu);
      const auto left = static_cast<float>(static_cast<int32_t>(columns & 0xFFFFu));
      const auto right = static_cast<float>(static_cast<int32_t>(columns >> 16));
      const float ax =
          static_cast<float>(static_cast<int32_t>((x.v[i] >> 8) & 0xFFu)) * (1.f / 256.f);
      result.v[i] = left + ax * (right - left);
    }
    return result;
  }
  static void AddTo(F a, int n, float* out) {
    for (int i = 0; i < n; ++i) out[i] += a.v[i];
  }

 private:
  template <typename Op>
  static F Map(F a, F b, Op op) {
    for (int i = 0; i < 4; ++i) a.v[i] = op(a.v[i], b.v[i]);
    return a;
  }
};

#if defined(RIGCAL_SIM_SIMD_SSE2)
struct Sse2Lanes {
  using F = __m128;
  using U = __m128i;
  using M = __m128;
  static constexpr const char* kName = "SSE2";

  static F Splat(float a) { return _mm_set1_ps(a); }
  static U SplatU(uint32_t a) { return _mm_set1_epi32(static_cast<int>(a)); }
  static F Iota(int x0) {
    return _mm_setr_ps(static_cast<float>(x0), static_cast<float>(x0 + 1),
                       static_cast<float>(x0 + 2), static_cast<float>(x0 + 3));
  }
  static U Load(const uint32_t a[4]) {
    return _mm_setr_epi32(static_cast<int>(a[0]), static_cast<int>(a[1]), static_cast<int>(a[2]),
                          static_cast<int>(a[3]));
  }
  static F Add(F a, F b) { return _mm_add_ps(a, b); }
  static F Sub(F a, F b) { return _mm_sub_ps(a, b); }
  static F Mul(F a, F b) { return _mm_mul_ps(a, b); }
  static F Min(F a, F b) { return _mm_min_ps(a, b); }
  static F Max(F a, F b) { return _mm_max_ps(a, b); }
  static U AddU(U a, U b) { return _mm_add_epi32(a, b); }
  static U SubU(U a, U b) { return _mm_sub_epi32(a, b); }
  template <int n>
  static U ShiftRight(U a) {
    return _mm_srli_epi32(a, n);
  }
  static M CompareGe(F a, F b) { return _mm_cmpge_ps(a, b); }
  static int MoveMask(M m) { return _mm_movemask_ps(m); }
  static F Select(M m, F if_set, F if_clear) {
    return _mm_or_ps(_mm_and_ps(m, if_set), _mm_andnot_ps(m, if_clear));
  }
  template <int log2n>
  static F Bilinear(const uint8_t* pairs, U x, U y) {
    const __m128i mask = _mm_set1_epi32((1 << log2n) - 1);
    const __m128i x0 = _mm_and_si128(_mm_srli_epi32(x, 16), mask);
    const __m128i y0 = _mm_and_si128(_mm_srli_epi32(y, 16), mask);
    // PairOffset in four lanes.
    const __m128i offset = _mm_add_epi32(
        _mm_add_epi32(_mm_slli_epi32(y0, log2n + 1), _mm_slli_epi32(y0, 5)), _mm_slli_epi32(x0, 1));
    static_assert(2 * kTexturePairPad == 32, "offset uses y0 << 5");
    alignas(16) uint32_t offsets[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(offsets), offset);
    uint32_t q[4];
    for (int i = 0; i < 4; ++i) std::memcpy(&q[i], pairs + offsets[i], sizeof(uint32_t));
    const __m128i quads = Load(q);
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
  static void AddTo(F a, int n, float* out) {
    if (n == 4) {
      _mm_storeu_ps(out, _mm_add_ps(_mm_loadu_ps(out), a));
      return;
    }
    alignas(16) float values[4];
    _mm_store_ps(values, a);
    for (int i = 0; i < n; ++i) out[i] += values[i];
  }
};
using SimdLanes = Sse2Lanes;
#elif defined(RIGCAL_SIM_SIMD_NEON)
struct NeonLanes {
  using F = float32x4_t;
  using U = uint32x4_t;
  using M = uint32x4_t;
  static constexpr const char* kName = "NEON";

  static F Splat(float a) { return vdupq_n_f32(a); }
  static U SplatU(uint32_t a) { return vdupq_n_u32(a); }
  static F Iota(int x0) {
    const float x[4] = {static_cast<float>(x0), static_cast<float>(x0 + 1),
                        static_cast<float>(x0 + 2), static_cast<float>(x0 + 3)};
    return vld1q_f32(x);
  }
  static U Load(const uint32_t a[4]) { return vld1q_u32(a); }
  static F Add(F a, F b) { return vaddq_f32(a, b); }
  static F Sub(F a, F b) { return vsubq_f32(a, b); }
  static F Mul(F a, F b) { return vmulq_f32(a, b); }
  // vminq/vmaxq return NaN for a NaN lane; these keep the SSE semantics.
  static F Min(F a, F b) { return vbslq_f32(vcltq_f32(a, b), a, b); }
  static F Max(F a, F b) { return vbslq_f32(vcgtq_f32(a, b), a, b); }
  static U AddU(U a, U b) { return vaddq_u32(a, b); }
  static U SubU(U a, U b) { return vsubq_u32(a, b); }
  template <int n>
  static U ShiftRight(U a) {
    return vshrq_n_u32(a, n);
  }
  static M CompareGe(F a, F b) { return vcgeq_f32(a, b); }
  static int MoveMask(M m) {
    return static_cast<int>((vgetq_lane_u32(m, 0) & 1u) | (vgetq_lane_u32(m, 1) & 2u) |
                            (vgetq_lane_u32(m, 2) & 4u) | (vgetq_lane_u32(m, 3) & 8u));
  }
  static F Select(M m, F if_set, F if_clear) { return vbslq_f32(m, if_set, if_clear); }
  template <int log2n>
  static F Bilinear(const uint8_t* pairs, U x, U y) {
    const uint32x4_t mask = vdupq_n_u32((1u << log2n) - 1u);
    const uint32x4_t x0 = vandq_u32(vshrq_n_u32(x, 16), mask);
    const uint32x4_t y0 = vandq_u32(vshrq_n_u32(y, 16), mask);
    // PairOffset in four lanes.
    const uint32x4_t offset =
        vaddq_u32(vaddq_u32(vshlq_n_u32(y0, log2n + 1), vmulq_n_u32(y0, 2 * kTexturePairPad)),
                  vshlq_n_u32(x0, 1));
    uint32_t offsets[4];
    vst1q_u32(offsets, offset);
    uint32_t q[4];
    for (int i = 0; i < 4; ++i) std::memcpy(&q[i], pairs + offsets[i], sizeof(uint32_t));
    const uint32x4_t quads = vld1q_u32(q);
    const uint32x4_t byte_mask = vdupq_n_u32(0xFFu);
    const uint32x4_t ay = vandq_u32(vshrq_n_u32(y, 8), byte_mask);
    const uint32x4_t by = vsubq_u32(vdupq_n_u32(256u), ay);
    const uint32x4_t p00 = vandq_u32(quads, byte_mask);
    const uint32x4_t p01 = vandq_u32(vshrq_n_u32(quads, 8), byte_mask);
    const uint32x4_t p10 = vandq_u32(vshrq_n_u32(quads, 16), byte_mask);
    const uint32x4_t p11 = vshrq_n_u32(quads, 24);
    // Left and right columns interpolated vertically, * 256 (exact integers).
    const float32x4_t left = vcvtq_f32_u32(vmlaq_u32(vmulq_u32(p00, by), p01, ay));
    const float32x4_t right = vcvtq_f32_u32(vmlaq_u32(vmulq_u32(p10, by), p11, ay));
    const float32x4_t ax =
        vmulq_f32(vcvtq_f32_u32(vandq_u32(vshrq_n_u32(x, 8), byte_mask)), vdupq_n_f32(1.f / 256.f));
    return vaddq_f32(left, vmulq_f32(ax, vsubq_f32(right, left)));
  }
  static void AddTo(F a, int n, float* out) {
    if (n == 4) {
      vst1q_f32(out, vaddq_f32(vld1q_f32(out), a));
      return;
    }
    float values[4];
    vst1q_f32(values, a);
    for (int i = 0; i < n; ++i) out[i] += values[i];
  }
};
using SimdLanes = NeonLanes;
#else
using SimdLanes = ScalarLanes;
#endif

// True when SimdLanes is a SIMD backend (not ScalarLanes).
#if defined(RIGCAL_SIM_SIMD_SSE2) || defined(RIGCAL_SIM_SIMD_NEON)
inline constexpr bool kHaveSimdLanes = true;
#else
inline constexpr bool kHaveSimdLanes = false;
#endif

}  // namespace rigcal::sim::internal
