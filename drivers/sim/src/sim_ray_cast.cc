// SPDX-License-Identifier: Apache-2.0
// Ray casting of the simulated rig: the first surface along a ray, its texture coordinates and
// mip level.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <limits>

#include "sim_scene.h"

namespace rigcal::sim::internal {
namespace {

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

inline float SkyIntensity(float dz) { return 160.f + 60.f * dz; }

}  // namespace

template <typename T>
int32_t Scene::Intersect(const T o[3], const T d[3], T* t_hit, const int* boxes,
                         int num_boxes) const {
  T best = std::numeric_limits<T>::infinity();
  int32_t surface = kSky;
  if (has_enclosure_) IntersectEnclosure(o, d, boxes, num_boxes, &best, &surface);
  if (has_pipe_) IntersectPipe(o, d, &best, &surface);
  *t_hit = best;
  return surface;
}

template <typename T>
void Scene::IntersectEnclosure(const T o[3], const T d[3], const int* boxes, int num_boxes, T* best,
                               int32_t* surface) const {
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
    if (t < *best) {
      *best = t;
      *surface = face;
    }
  }
  // The boxes stand in the bands along the walls (half-spaces). From a camera outside every
  // band, a ray can only reach the boxes of the bands that contain its exit point from the
  // enclosure (a segment enters a half-space only if it ends inside it).
  const T exit[2] = {o[0] + *best * d[0], o[1] + *best * d[1]};
  if (open_top_ && *surface == 5) {
    *surface = kSky;
    *best = std::numeric_limits<T>::infinity();
  }
  if (!boxes_.empty()) IntersectBoxes(o, d, exit, boxes, num_boxes, best, surface);
}

template <typename T>
void Scene::IntersectBoxes(const T o[3], const T d[3], const T exit[2], const int* boxes,
                           int num_boxes, T* best, int32_t* surface) const {
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
    if (t_near <= t_far && t_near > T(0) && t_near < *best) {
      *best = t_near;
      *surface = box.first_surface + 2 * axis + (d[axis] > T(0) ? 0 : 1);
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
    const bool in_band[4] = {
        exit[0] <= static_cast<T>(band_[0]) + margin, exit[0] >= static_cast<T>(band_[1]) - margin,
        exit[1] <= static_cast<T>(band_[2]) + margin, exit[1] >= static_cast<T>(band_[3]) - margin};
    for (int w = 0; w < 4; ++w) {
      if (!in_band[w]) continue;
      for (int b : wall_boxes_[w]) test_box(boxes_[b]);
    }
  }
}

template <typename T>
void Scene::IntersectPipe(const T o[3], const T d[3], T* best, int32_t* surface) const {
  const T a = d[1] * d[1] + d[2] * d[2];
  bool wall = false;
  if (a > T(1e-12)) {
    const T b = o[1] * d[1] + o[2] * d[2];
    const T c = o[1] * o[1] + o[2] * o[2] - static_cast<T>(radius_) * static_cast<T>(radius_);
    const T disc = b * b - a * c;
    if (disc >= T(0)) {
      const T t = (-b + std::sqrt(disc)) / a;
      const T x = o[0] + t * d[0];
      if (t > T(0) && x >= static_cast<T>(x0_) && x <= static_cast<T>(x1_) && t < *best) {
        *best = t;
        *surface = 0;
        wall = true;
      }
    }
  }
  if (wall) return;
  if (d[0] > T(0)) {
    const T t = (static_cast<T>(x1_) - o[0]) / d[0];
    if (t > T(0) && t < *best) {
      *best = t;
      *surface = 2;
    }
  } else if (d[0] < T(0)) {
    const T t = (static_cast<T>(x0_) - o[0]) / d[0];
    if (t > T(0) && t < *best) {
      *best = t;
      *surface = 1;
    }
  }
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

Hit Scene::Cast(const float o[3], const float d[3], float pixel_angle,
                const MovingBoxes& moving) const {
  float t = 0.f;
  const int32_t s = Intersect(o, d, &t);
  return ShadeWithMoving(o, d, pixel_angle, s, t, moving);
}

Hit Scene::CastAmong(const float o[3], const float d[3], float pixel_angle, const int* boxes,
                     int num_boxes, const MovingBoxes& moving) const {
  float t = 0.f;
  const int32_t s = Intersect(o, d, &t, boxes, num_boxes);
  return ShadeWithMoving(o, d, pixel_angle, s, t, moving);
}

int Scene::IntersectMoving(const float o[3], const float d[3], const MovingBoxes& moving,
                           float* best, int32_t* surface) const {
  const float inv[3] = {1.f / d[0], 1.f / d[1], 1.f / d[2]};
  const float half[3] = {static_cast<float>(moving_half_.x()), static_cast<float>(moving_half_.y()),
                         static_cast<float>(moving_half_.z())};
  int nearest = -1;
  for (int i = 0; i < moving.num_visible; ++i) {
    const int b = moving.visible[i];
    const float* centre = moving.centres + 3 * static_cast<ptrdiff_t>(b);
    float t_near = -std::numeric_limits<float>::infinity();
    float t_far = std::numeric_limits<float>::infinity();
    int axis = 0;
    for (int a = 0; a < 3; ++a) {
      const float local = o[a] - centre[a];
      const float t1 = (-half[a] - local) * inv[a];
      const float t2 = (half[a] - local) * inv[a];
      const float t_min = std::min(t1, t2);
      if (t_min > t_near) {
        t_near = t_min;
        axis = a;
      }
      t_far = std::min(t_far, std::max(t1, t2));
    }
    if (t_near <= t_far && t_near > 0.f && t_near < *best) {
      *best = t_near;
      *surface = first_moving_surface_ + 6 * b + 2 * axis + (d[axis] > 0.f ? 0 : 1);
      nearest = b;
    }
  }
  return nearest;
}

Hit Scene::ShadeWithMoving(const float o[3], const float d[3], float pixel_angle, int32_t surface,
                           float t, const MovingBoxes& moving) const {
  const int b = IntersectMoving(o, d, moving, &t, &surface);
  // A moving box's hit in the box's own frame (centred on its centre), so that its texture
  // moves with it.
  const float* centre = b >= 0 ? moving.centres + 3 * static_cast<ptrdiff_t>(b) : nullptr;
  const float origin[3] = {centre ? o[0] - centre[0] : o[0], centre ? o[1] - centre[1] : o[1],
                           centre ? o[2] - centre[2] : o[2]};
  return Shade(origin, d, pixel_angle, surface, t);
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

}  // namespace rigcal::sim::internal
