// Scene, ray casting and rendering of the simulated rig.
#include "sim_scene.h"

#include <emmintrin.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <sstream>

#include "rigcal/calib/thread_annotations.h"
#include "sim_random.h"

namespace rigcal::drivers::internal {
namespace {

constexpr int kTileLog2 = 10;  // 1024 x 1024 texels per tile
constexpr int kNumTiles = 6;
constexpr int kPairPad = kTexturePairPad;
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();

// log2 within ~0.01 (selects mip levels only).
inline float FastLog2(float x) {
  uint32_t bits;
  std::memcpy(&bits, &x, sizeof(bits));
  const float exponent = static_cast<float>(static_cast<int>(bits >> 23) - 127);
  bits = (bits & 0x007FFFFFu) | 0x3F800000u;
  float m;
  std::memcpy(&m, &bits, sizeof(m));
  return exponent + (-0.34484843f * m + 2.02466578f) * m - 0.67487759f;
}

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

inline float SkyIntensity(float dz) { return 160.f + 60.f * dz; }

// The process-wide tile cache of CachedTile; scenes may be built on any thread.
struct TileCache {
  Mutex mutex;
  std::map<std::pair<int, uint64_t>, std::weak_ptr<const TextureTile>> tiles
      RIGCAL_GUARDED_BY(mutex);
};

// Tiles are immutable and deterministic for their seed: rigs built with the same seed (tests,
// a rig rebuilt with other options) share them instead of generating them again.
std::shared_ptr<const TextureTile> CachedTile(int log2_size, uint64_t seed) {
  static TileCache cache;
  MutexLock lock(cache.mutex);
  std::weak_ptr<const TextureTile>& entry = cache.tiles[{log2_size, seed}];
  if (auto tile = entry.lock()) return tile;
  auto tile = std::make_shared<const TextureTile>(MakeDeadLeavesTile(log2_size, seed));
  entry = tile;
  return tile;
}

}  // namespace

Scene Scene::Build(const SimulatedRigSpec& spec) {
  Scene scene;
  const double texel = spec.TexelSize();
  scene.inv_texel_ = static_cast<float>(1.0 / texel);
  for (int i = 0; i < kNumTiles; ++i) {
    scene.tiles_.push_back(CachedTile(kTileLog2, HashKey(spec.seed, kPurposeTexture, i)));
  }
  for (const auto& tile : scene.tiles_) {
    TileView view{};
    view.num_levels = static_cast<int>(tile->pairs.size());
    for (int l = 0; l < view.num_levels; ++l) view.level[l] = tile->pairs[l].data();
    scene.tile_views_.push_back(view);
  }
  Rng rng(HashKey(spec.seed, kPurposeLayout));
  const float tile_texels = static_cast<float>(1 << kTileLog2);
  auto add_surface = [&](Kind kind, int tile, float u_period) {
    Surface f;
    f.kind = kind;
    f.tile = tile % kNumTiles;
    f.offset_u = static_cast<float>(rng.Uniform(0, tile_texels));
    f.offset_v = static_cast<float>(rng.Uniform(0, tile_texels));
    f.u_period = u_period;
    scene.surfaces_.push_back(f);
  };

  std::ostringstream description;
  if (spec.scene.type == SimulatedRigSpec::SceneType::kPipe) {
    scene.has_pipe_ = true;
    scene.radius_ = 0.5 * spec.scene.pipe_diameter;
    scene.x0_ = 0.0;
    scene.x1_ = spec.scene.pipe_length;
    add_surface(Kind::kCylinderX, 0, static_cast<float>(2.0 * M_PI * scene.radius_ / texel));
    add_surface(Kind::kPlaneX, 1, 0.f);  // cap at x0
    add_surface(Kind::kPlaneX, 2, 0.f);  // cap at x1
    description << "pipe, diameter " << spec.scene.pipe_diameter << " m, length "
                << spec.scene.pipe_length << " m";
  } else {
    const Eigen::Vector3d size = spec.SceneSize();
    scene.has_enclosure_ = true;
    scene.open_top_ = spec.scene.type != SimulatedRigSpec::SceneType::kRoom;
    scene.lo_[0] = -0.5 * size.x();
    scene.hi_[0] = 0.5 * size.x();
    scene.lo_[1] = -0.5 * size.y();
    scene.hi_[1] = 0.5 * size.y();
    scene.lo_[2] = 0.0;
    scene.hi_[2] = size.z();
    // Enclosure faces: surface 2 * axis + (0: lo, 1: hi).
    const Kind kinds[3] = {Kind::kPlaneX, Kind::kPlaneY, Kind::kPlaneZ};
    for (int face = 0; face < 6; ++face) add_surface(kinds[face / 2], face, 0.f);
    // Boxes along the walls, in the outer 30% of each half-extent.
    for (int b = 0; b < spec.scene.boxes; ++b) {
      const int wall = static_cast<int>(rng.Below(4));  // -x, +x, -y, +y
      const int across = wall / 2;                      // axis perpendicular to the wall
      const int along = 1 - across;
      const double half_across = 0.5 * size[across];
      const double half_along = 0.5 * size[along];
      const double band = 0.3 * half_across;
      const double depth = rng.Uniform(0.3, 1.0) * band;
      const double length = std::min(rng.Uniform(0.3, 1.2) * band, 0.5 * size[along]);
      const double height = rng.Uniform(0.15, 0.7) * size.z();
      const double centre = rng.Uniform(-half_along + 0.5 * length, half_along - 0.5 * length);
      Box box;
      if (wall % 2 == 0) {
        box.lo[across] = -half_across;
        box.hi[across] = -half_across + depth;
      } else {
        box.lo[across] = half_across - depth;
        box.hi[across] = half_across;
      }
      box.lo[along] = centre - 0.5 * length;
      box.hi[along] = centre + 0.5 * length;
      box.lo[2] = 0.0;
      box.hi[2] = height;
      box.first_surface = static_cast<int32_t>(scene.surfaces_.size());
      const int tile = static_cast<int>(rng.Below(kNumTiles));
      for (int face = 0; face < 6; ++face) add_surface(kinds[face / 2], tile + face, 0.f);
      scene.wall_boxes_[wall].push_back(static_cast<int>(scene.boxes_.size()));
      scene.boxes_.push_back(box);
    }
    // Boxes of wall w lie in its band: x <= lo_x + band_x (w = 0), x >= hi_x - band_x (1),
    // likewise in y (2, 3).
    for (int a = 0; a < 2; ++a) {
      const double band = 0.3 * 0.5 * size[a];
      scene.band_[2 * a] = scene.lo_[a] + band;
      scene.band_[2 * a + 1] = scene.hi_[a] - band;
    }
    description << ToString(spec.scene.type) << " " << size.x() << " x " << size.y() << " x "
                << size.z() << " m with " << spec.scene.boxes << " boxes";
  }
  description << ", texel " << texel * 1000.0 << " mm";
  scene.description_ = description.str();
  return scene;
}

std::string Scene::Describe() const { return description_; }

size_t Scene::TextureBytes() const {
  size_t bytes = 0;
  for (const auto& tile : tiles_) {
    for (const auto& level : tile->pairs) bytes += level.size();
  }
  return bytes;
}

template <typename T>
int32_t Scene::Intersect(const T o[3], const T d[3], T* t_hit, const int* boxes,
                         int num_boxes) const {
  T best = std::numeric_limits<T>::infinity();
  int32_t surface = kSky;
  if (has_enclosure_) {
    for (int a = 0; a < 3; ++a) {
      T t;
      int face;
      if (d[a] > T(0)) {
        t = (static_cast<T>(hi_[a]) - o[a]) / d[a];
        face = 2 * a + 1;
      } else if (d[a] < T(0)) {
        t = (static_cast<T>(lo_[a]) - o[a]) / d[a];
        face = 2 * a;
      } else {
        continue;
      }
      if (t < best) {
        best = t;
        surface = face;
      }
    }
    // The boxes stand in the bands along the walls (half-spaces). From a camera outside every
    // band, a ray can only reach the boxes of the bands that contain its exit point from the
    // enclosure (a segment enters a half-space only if it ends inside it).
    const T exit[2] = {o[0] + best * d[0], o[1] + best * d[1]};
    if (open_top_ && surface == 5) {
      surface = kSky;
      best = std::numeric_limits<T>::infinity();
    }
    if (!boxes_.empty()) {
      const T inv[3] = {T(1) / d[0], T(1) / d[1], T(1) / d[2]};
      auto test_box = [&](const Box& box) {
        T t_near = -std::numeric_limits<T>::infinity();
        T t_far = std::numeric_limits<T>::infinity();
        int axis = 0;
        for (int a = 0; a < 3; ++a) {
          const T t1 = (static_cast<T>(box.lo[a]) - o[a]) * inv[a];
          const T t2 = (static_cast<T>(box.hi[a]) - o[a]) * inv[a];
          const T t_min = std::min(t1, t2);
          const T t_max = std::max(t1, t2);
          if (t_min > t_near) {
            t_near = t_min;
            axis = a;
          }
          t_far = std::min(t_far, t_max);
        }
        if (t_near <= t_far && t_near > T(0) && t_near < best) {
          best = t_near;
          surface = box.first_surface + 2 * axis + (d[axis] > T(0) ? 0 : 1);
        }
      };
      const bool inner = o[0] > static_cast<T>(band_[0]) && o[0] < static_cast<T>(band_[1]) &&
                         o[1] > static_cast<T>(band_[2]) && o[1] < static_cast<T>(band_[3]);
      if (boxes != nullptr) {
        for (int i = 0; i < num_boxes; ++i) test_box(boxes_[boxes[i]]);
      } else if (!inner) {
        for (const Box& box : boxes_) test_box(box);
      } else {
        const T margin = T(1e-3);  // against rounding of the exit point
        const bool in_band[4] = {exit[0] <= static_cast<T>(band_[0]) + margin,
                                 exit[0] >= static_cast<T>(band_[1]) - margin,
                                 exit[1] <= static_cast<T>(band_[2]) + margin,
                                 exit[1] >= static_cast<T>(band_[3]) - margin};
        for (int w = 0; w < 4; ++w) {
          if (!in_band[w]) continue;
          for (int b : wall_boxes_[w]) test_box(boxes_[b]);
        }
      }
    }
  }
  if (has_pipe_) {
    const T a = d[1] * d[1] + d[2] * d[2];
    bool wall = false;
    if (a > T(1e-12)) {
      const T b = o[1] * d[1] + o[2] * d[2];
      const T c = o[1] * o[1] + o[2] * o[2] - static_cast<T>(radius_) * static_cast<T>(radius_);
      const T disc = b * b - a * c;
      if (disc >= T(0)) {
        const T t = (-b + std::sqrt(disc)) / a;
        const T x = o[0] + t * d[0];
        if (t > T(0) && x >= static_cast<T>(x0_) && x <= static_cast<T>(x1_) && t < best) {
          best = t;
          surface = 0;
          wall = true;
        }
      }
    }
    if (!wall) {
      if (d[0] > T(0)) {
        const T t = (static_cast<T>(x1_) - o[0]) / d[0];
        if (t > T(0) && t < best) {
          best = t;
          surface = 2;
        }
      } else if (d[0] < T(0)) {
        const T t = (static_cast<T>(x0_) - o[0]) / d[0];
        if (t > T(0) && t < best) {
          best = t;
          surface = 1;
        }
      }
    }
  }
  *t_hit = best;
  return surface;
}

Hit Scene::Cast(const float o[3], const float d[3], float pixel_angle) const {
  float t = 0.f;
  const int32_t s = Intersect(o, d, &t);
  return Shade(o, d, pixel_angle, s, t);
}

Hit Scene::CastAmong(const float o[3], const float d[3], float pixel_angle, const int* boxes,
                     int num_boxes) const {
  float t = 0.f;
  const int32_t s = Intersect(o, d, &t, boxes, num_boxes);
  return Shade(o, d, pixel_angle, s, t);
}

Hit Scene::Shade(const float o[3], const float d[3], float pixel_angle, int32_t s, float t) const {
  Hit hit;
  hit.surface = s;
  if (s < 0) {
    hit.u = SkyIntensity(d[2]);
    return hit;
  }
  const Surface& f = surfaces_[s];
  const float hx = o[0] + t * d[0];
  const float hy = o[1] + t * d[1];
  const float hz = o[2] + t * d[2];
  float u = 0.f, v = 0.f, cos_incidence = 1.f;
  switch (f.kind) {
    case Kind::kPlaneX:
      u = hy;
      v = hz;
      cos_incidence = std::abs(d[0]);
      break;
    case Kind::kPlaneY:
      u = hx;
      v = hz;
      cos_incidence = std::abs(d[1]);
      break;
    case Kind::kPlaneZ:
      u = hx;
      v = hy;
      cos_incidence = std::abs(d[2]);
      break;
    case Kind::kCylinderX:
      u = std::atan2(hz, hy) * static_cast<float>(radius_);
      v = hx;
      cos_incidence = std::abs(hy * d[1] + hz * d[2]) / static_cast<float>(radius_);
      break;
  }
  hit.u = u * inv_texel_ + f.offset_u;
  hit.v = v * inv_texel_ + f.offset_v;
  // Texels per pixel: head-on footprint, widened at grazing incidence (between the geometric
  // mean and the long axis of the anisotropic footprint).
  const float footprint = t * pixel_angle * inv_texel_;
  hit.lod = FastLog2(std::max(footprint, 1e-6f)) - 0.7f * FastLog2(std::max(cos_incidence, 0.02f));
  return hit;
}

std::optional<double> Scene::Distance(const Eigen::Vector3d& o, const Eigen::Vector3d& d) const {
  const double od[3] = {o.x(), o.y(), o.z()};
  const double dd[3] = {d.x(), d.y(), d.z()};
  double t = 0.0;
  const int32_t s = Intersect(od, dd, &t);
  if (s < 0 || !std::isfinite(t)) return std::nullopt;
  return t;
}

std::string Scene::CheckFree(const Eigen::Vector3d& p, double clearance) const {
  std::ostringstream out;
  if (has_enclosure_) {
    for (int a = 0; a < 3; ++a) {
      if (p[a] < lo_[a] + clearance || p[a] > hi_[a] - clearance) {
        out << "leaves the " << (open_top_ ? "yard" : "room") << " [" << lo_[0] << ", " << hi_[0]
            << "] x [" << lo_[1] << ", " << hi_[1] << "] x [" << lo_[2] << ", " << hi_[2]
            << "] (clearance " << clearance << " m)";
        return out.str();
      }
    }
    for (size_t b = 0; b < boxes_.size(); ++b) {
      const Box& box = boxes_[b];
      bool inside = true;
      for (int a = 0; a < 3; ++a) {
        inside = inside && p[a] > box.lo[a] - clearance && p[a] < box.hi[a] + clearance;
      }
      if (inside) {
        out << "enters box " << b << " [" << box.lo[0] << ", " << box.hi[0] << "] x [" << box.lo[1]
            << ", " << box.hi[1] << "] x [" << box.lo[2] << ", " << box.hi[2]
            << "] (boxes stand in the outer 30% of the floor plan)";
        return out.str();
      }
    }
  }
  if (has_pipe_) {
    const double r = std::hypot(p.y(), p.z());
    if (r > radius_ - clearance || p.x() < x0_ + clearance || p.x() > x1_ - clearance) {
      out << "leaves the pipe (radius " << radius_ << " m along x in [" << x0_ << ", " << x1_
          << "]; distance from the axis " << r << " m)";
      return out.str();
    }
  }
  return {};
}

float Scene::Sample(int32_t surface, float u, float v, float lod) const {
  return SampleTile(tile_views_[surfaces_[surface].tile], u, v, lod);
}

float Scene::SampleTile(const TileView& tile, float u, float v, float lod) {
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

void Scene::FillBlock(const Hit& h00, const Hit& h10, const Hit& h01, const Hit& h11, int block,
                      int nx, int ny, float weight, float* out, int stride) const {
  const float inv_block = 1.f / static_cast<float>(block);
  const Bilinear2d u(h00.u, h10.u, h01.u, h11.u, inv_block);
  if (h00.surface == kSky) {  // u holds the sky's intensity
    for (int y = 0; y < ny; ++y, out += stride) {
      const float start = u.a + static_cast<float>(y) * u.c;
      const float step = u.b + static_cast<float>(y) * u.d;
      for (int x = 0; x < nx; ++x) out[x] += weight * (start + static_cast<float>(x) * step);
    }
    return;
  }
  const TileView& tile = tile_views_[surfaces_[h00.surface].tile];
  const Bilinear2d v(h00.v, h10.v, h01.v, h11.v, inv_block);
  const Bilinear2d lod(h00.lod, h10.lod, h01.lod, h11.lod, inv_block);
  const float lod_min = std::min(std::min(h00.lod, h10.lod), std::min(h01.lod, h11.lod));
  const float lod_max = std::max(std::max(h00.lod, h10.lod), std::max(h01.lod, h11.lod));
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
      out[x] += weight * SampleTile(tile, u.a + xf * u.b + yf * (u.c + xf * u.d),
                                    v.a + xf * v.b + yf * (v.c + xf * v.d),
                                    lod.a + xf * lod.b + yf * (lod.c + xf * lod.d));
    }
  }
}

CameraTables MakeCameraTables(std::shared_ptr<const camera::CameraModel> model) {
  CameraTables tables;
  tables.width = model->width();
  tables.height = model->height();
  tables.bearings.resize(static_cast<size_t>(tables.width) * tables.height * 3);
  for (int y = 0; y < tables.height; ++y) {
    for (int x = 0; x < tables.width; ++x) {
      float* b = &tables.bearings[3 * (static_cast<size_t>(y) * tables.width + x)];
      const auto bearing = model->Unproject(Eigen::Vector2d(x, y));
      if (bearing && bearing->allFinite() && bearing->norm() > 0.5) {
        const Eigen::Vector3d unit = bearing->normalized();
        b[0] = static_cast<float>(unit.x());
        b[1] = static_cast<float>(unit.y());
        b[2] = static_cast<float>(unit.z());
      } else {
        b[0] = b[1] = b[2] = kNaN;
      }
    }
  }
  tables.model = std::move(model);
  return tables;
}

NodeGrid MakeNodeGrid(const CameraTables& camera, int block) {
  NodeGrid grid;
  grid.block = block;
  grid.nodes_x = (camera.width - 1 + block - 1) / block + 1;
  grid.nodes_y = (camera.height - 1 + block - 1) / block + 1;
  const size_t n = static_cast<size_t>(grid.nodes_x) * grid.nodes_y;
  grid.bearings.assign(3 * n, kNaN);
  grid.pixel_angle.assign(n, 0.f);
  auto bearing_at = [&](double x, double y) -> std::optional<Eigen::Vector3d> {
    const auto b = camera.model->Unproject(Eigen::Vector2d(x, y));
    if (!b || !b->allFinite() || b->norm() < 0.5) return std::nullopt;
    return b->normalized();
  };
  for (int j = 0; j < grid.nodes_y; ++j) {
    for (int i = 0; i < grid.nodes_x; ++i) {
      const double x = i * block;
      const double y = j * block;
      const auto b = bearing_at(x, y);
      if (!b) continue;
      const size_t k = static_cast<size_t>(j) * grid.nodes_x + i;
      grid.bearings[3 * k] = static_cast<float>(b->x());
      grid.bearings[3 * k + 1] = static_cast<float>(b->y());
      grid.bearings[3 * k + 2] = static_cast<float>(b->z());
      // Local pixel angle: the larger of the angles to the next pixel right and down.
      double angle = 0.0;
      for (const Eigen::Vector2d& step : {Eigen::Vector2d(1, 0), Eigen::Vector2d(0, 1)}) {
        auto nb = bearing_at(x + step.x(), y + step.y());
        if (!nb) nb = bearing_at(x - step.x(), y - step.y());
        if (nb) angle = std::max(angle, std::acos(std::clamp(b->dot(*nb), -1.0, 1.0)));
      }
      grid.pixel_angle[k] = static_cast<float>(angle > 0 ? angle : 1e-3);
    }
  }
  return grid;
}

namespace {

struct Transform {
  float r[9];
  float o[3];
  void Apply(const float* b, float* d) const {
    d[0] = r[0] * b[0] + r[1] * b[1] + r[2] * b[2];
    d[1] = r[3] * b[0] + r[4] * b[1] + r[5] * b[2];
    d[2] = r[6] * b[0] + r[7] * b[1] + r[8] * b[2];
  }
};

}  // namespace

void RenderAccumulate(const Scene& scene, const CameraTables& camera, const NodeGrid* grid,
                      const Pose& world_from_camera, float weight, float* acc,
                      std::vector<Hit>* hits) {
  Transform xf;
  const Eigen::Matrix3d r = world_from_camera.R();
  for (int i = 0; i < 9; ++i) xf.r[i] = static_cast<float>(r(i / 3, i % 3));
  for (int i = 0; i < 3; ++i) xf.o[i] = static_cast<float>(world_from_camera.C[i]);
  const int w = camera.width;
  const int h = camera.height;

  auto shade = [&scene](const Hit& hit) -> float {
    if (hit.surface == kInvalid) return 0.f;
    if (hit.surface == kSky) return hit.u;
    return scene.Sample(hit.surface, hit.u, hit.v, hit.lod);
  };
  // Boxes a fallback block may show: those its corners hit (null: unknown, test all).
  const int* candidates = nullptr;
  int num_candidates = 0;
  auto cast_pixel = [&](int x, int y) -> float {
    const float* b = &camera.bearings[3 * (static_cast<size_t>(y) * w + x)];
    if (b[0] != b[0]) return 0.f;
    // Local pixel angle as for the nodes: the larger of the chords to the next pixel right and
    // down (the previous one at the last column / row).
    float pixel_angle = 0.f;
    for (const float* nb : {x + 1 < w ? b + 3 : b - 3, y + 1 < h ? b + 3 * w : b - 3 * w}) {
      if (nb[0] != nb[0]) continue;
      const float dx = nb[0] - b[0], dy = nb[1] - b[1], dz = nb[2] - b[2];
      pixel_angle = std::max(pixel_angle, std::sqrt(dx * dx + dy * dy + dz * dz));
    }
    if (pixel_angle <= 0.f) pixel_angle = 1e-3f;
    float d[3];
    xf.Apply(b, d);
    return shade(candidates != nullptr
                     ? scene.CastAmong(xf.o, d, pixel_angle, candidates, num_candidates)
                     : scene.Cast(xf.o, d, pixel_angle));
  };

  if (grid == nullptr || grid->block < 2) {
    for (int y = 0; y < h; ++y) {
      float* row = acc + static_cast<size_t>(y) * w;
      for (int x = 0; x < w; ++x) row[x] += weight * cast_pixel(x, y);
    }
    return;
  }

  const int block = grid->block;
  const int gx = grid->nodes_x;
  const int gy = grid->nodes_y;
  hits->resize(static_cast<size_t>(gx) * gy);
  for (size_t k = 0; k < hits->size(); ++k) {
    const float* b = &grid->bearings[3 * k];
    if (b[0] != b[0]) {
      (*hits)[k].surface = kInvalid;
      continue;
    }
    float d[3];
    xf.Apply(b, d);
    (*hits)[k] = scene.Cast(xf.o, d, grid->pixel_angle[k]);
  }

  for (int bj = 0; bj + 1 < gy; ++bj) {
    const int y0 = bj * block;
    const int y1 = std::min(h, y0 + block);
    for (int bi = 0; bi + 1 < gx; ++bi) {
      const int x0 = bi * block;
      const int x1 = std::min(w, x0 + block);
      const Hit& h00 = (*hits)[static_cast<size_t>(bj) * gx + bi];
      const Hit& h10 = (*hits)[static_cast<size_t>(bj) * gx + bi + 1];
      const Hit& h01 = (*hits)[static_cast<size_t>(bj + 1) * gx + bi];
      const Hit& h11 = (*hits)[static_cast<size_t>(bj + 1) * gx + bi + 1];
      const int32_t s = h00.surface;
      bool uniform = s == h10.surface && s == h01.surface && s == h11.surface;
      if (uniform && s >= 0) {
        const float period = scene.UPeriod(s);
        if (period > 0.f) {
          const float u_min = std::min(std::min(h00.u, h10.u), std::min(h01.u, h11.u));
          const float u_max = std::max(std::max(h00.u, h10.u), std::max(h01.u, h11.u));
          uniform = u_max - u_min < 0.5f * period;
        }
      }
      if (!uniform) {
        // Cast every pixel, against the boxes the corners hit when every corner hits a
        // surface (an object seen by no corner is missed, as in uniform blocks).
        int boxes[4];
        num_candidates = 0;
        bool all_surfaces = true;
        for (const Hit* corner : {&h00, &h10, &h01, &h11}) {
          all_surfaces = all_surfaces && corner->surface >= 0;
          const int box = scene.BoxOfSurface(corner->surface);
          if (box >= 0 && std::find(boxes, boxes + num_candidates, box) == boxes + num_candidates) {
            boxes[num_candidates++] = box;
          }
        }
        candidates = all_surfaces ? boxes : nullptr;
        for (int y = y0; y < y1; ++y) {
          float* row = acc + static_cast<size_t>(y) * w;
          for (int x = x0; x < x1; ++x) row[x] += weight * cast_pixel(x, y);
        }
        candidates = nullptr;
        continue;
      }
      if (s == kInvalid) continue;
      scene.FillBlock(h00, h10, h01, h11, block, x1 - x0, y1 - y0, weight,
                      acc + static_cast<size_t>(y0) * w + x0, w);
    }
  }
}

template int32_t Scene::Intersect<float>(const float[3], const float[3], float*, const int*,
                                         int) const;
template int32_t Scene::Intersect<double>(const double[3], const double[3], double*, const int*,
                                          int) const;

}  // namespace rigcal::drivers::internal
